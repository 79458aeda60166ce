"""Lateral and speed actions as the reference player reads them: a relative target lane counts
lanes to the reference entity's left in the direction it faces (so +1 from a car driving in a
left-hand lane against the reference line is a lane of smaller id), a lane offset that carries a
lane-bound actor past the road's edge takes it off the road (OffroadCondition sees it), and a
speed transition over zero time or distance is a step whatever its shape."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim import speeds
from tests.sim import osc_scenarios as osc
from tests.sim.worlds import DT, Bench, lane, speed, teleport


def _change(target: model.RelativeTargetLane) -> model.LaneChangeAction:
    return model.LaneChangeAction(
        dynamics=model.TransitionDynamics(
            shape=model.DynamicsShape.SINUSOIDAL, dimension=model.DynamicsDimension.TIME, value=2.0
        ),
        target=target,
    )


@pytest.mark.parametrize(
    ("start_lane", "value", "expected_lane"),
    [
        (-1, 1, 1),  # along the reference line: left is +t, across the centre lane
        (-2, 1, -1),
        (1, 1, -1),  # against it (left-hand lane, RHT): left is -t, across the centre lane
        (2, 1, 1),
        (1, -1, 2),  # and right is +t
    ],
)
def test_relative_target_lane_counts_to_the_reference_entitys_left(
    start_lane: int, value: int, expected_lane: int
) -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(start_lane, 500.0)))
    bench.start("Car", speed(10.0))
    bench.start("Car", _change(model.RelativeTargetLane(entity_ref="Car", value=value)))
    bench.step(round(2.5 / DT))
    assert bench.actor("Car").lane_id == expected_lane


def test_relative_target_lane_follows_the_other_entitys_facing() -> None:
    bench = Bench("Car", "Oncoming")
    bench.start("Car", teleport(lane(-1, 500.0)))
    bench.start("Car", speed(10.0))
    bench.start("Oncoming", teleport(lane(2, 600.0)))
    # one lane to the left of the oncoming car (facing -s): lane 1, which Car then drives in
    bench.start("Car", _change(model.RelativeTargetLane(entity_ref="Oncoming", value=1)))
    bench.step(round(2.5 / DT))
    assert bench.actor("Car").lane_id == 1


@pytest.mark.parametrize(("target_offset", "off_road"), [(0.0, False), (-0.5, True)])
def test_lane_change_to_a_lane_beyond_the_road_ends_on_its_edge(
    target_offset: float, off_road: bool
) -> None:
    # esmini counts lanes the road does not have as 0 m wide: lane -11's centre is the right
    # edge (t = -7); a target lane offset past it leaves the road (OffroadCondition sees it)
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Car", speed(10.0))
    change = dataclasses.replace(
        _change(model.RelativeTargetLane(entity_ref="Car", value=-10)),
        target_lane_offset=target_offset or None,
    )
    bench.start("Car", change)
    bench.step(round(1.0 / DT))
    car = bench.actor("Car")
    assert car.y == pytest.approx(-1.75 + (-7.0 + target_offset + 1.75) / 2, abs=1e-6)
    bench.step(round(1.5 / DT))
    assert not bench.dispatcher.runs(car)
    assert car.lane_id == -2
    assert car.y == pytest.approx(-7.0 + target_offset)
    assert (car.offroad_time > 0.0) is off_road


def _offset(value: float) -> model.LaneOffsetAction:
    return model.LaneOffsetAction(
        continuous=True,
        shape=model.DynamicsShape.STEP,
        target=model.AbsoluteTargetLaneOffset(value=value),
    )


@pytest.mark.parametrize(
    ("offset", "off_road"),
    [(-1.5, False), (-1.8, True), (1.5, False)],  # lane -2 spans t in [-7, -3.5]: edge at -7
)
def test_lane_offset_past_the_road_edge_is_off_road(offset: float, off_road: bool) -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-2, 100.0)))
    bench.start("Car", speed(10.0))
    bench.start("Car", _offset(offset))
    bench.step(10)
    car = bench.actor("Car")
    assert (car.offroad_time > 0.0) is off_road
    if off_road:
        assert car.offroad_time == pytest.approx(10 * DT)


@pytest.mark.parametrize(
    ("shape", "dimension"),
    [
        (model.DynamicsShape.LINEAR, model.DynamicsDimension.TIME),
        (model.DynamicsShape.SINUSOIDAL, model.DynamicsDimension.DISTANCE),
    ],
)
def test_speed_transition_of_zero_time_or_distance_is_a_step(
    shape: model.DynamicsShape, dimension: model.DynamicsDimension
) -> None:
    # a step ignores the vehicle's acceleration limit (10 m/s^2 here), as in the reference player
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    dynamics = model.TransitionDynamics(shape=shape, dimension=dimension, value=0.0)
    bench.start(
        "Car", model.SpeedAction(dynamics=dynamics, target=model.AbsoluteTargetSpeed(value=30.0))
    )
    assert bench.actor("Car").speed == 30.0


def test_lane_change_over_a_distance_ends_after_that_distance_driven() -> None:
    # esmini steps a distance-shaped change by the distance gained along the road, so a car
    # that speeds up from 10 to 20 m/s right after starting a 100 m change ends it about
    # 100 m on (5 s), not after the 10 s that 100 m at the starting speed would take
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Car", speed(10.0))
    dynamics = model.TransitionDynamics(
        shape=model.DynamicsShape.SINUSOIDAL,
        dimension=model.DynamicsDimension.DISTANCE,
        value=100.0,
    )
    change = model.LaneChangeAction(
        dynamics=dynamics, target=model.RelativeTargetLane(entity_ref="Car", value=-1)
    )
    bench.start("Car", change)
    bench.start("Car", speed(20.0))
    car = bench.actor("Car")
    bench.step(round(2.5 / DT))  # half way: 50 m driven, half the lateral way
    assert car.s == pytest.approx(150.0, abs=0.1)
    assert car.y == pytest.approx(-1.75 - 3.5 / 2, abs=0.05)
    bench.step(round(2.6 / DT))
    assert not bench.dispatcher.runs(car)
    assert car.lane_id == -2 and car.y == pytest.approx(-5.25)
    assert car.s == pytest.approx(202.0, abs=0.2)


def test_lane_change_waits_while_the_car_stands() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Car", _change(model.RelativeTargetLane(entity_ref="Car", value=-1)))
    bench.step(round(3.0 / DT))
    car = bench.actor("Car")
    assert car.lane_id == -1 and car.y == pytest.approx(-1.75)
    assert bench.dispatcher.runs(car)


def test_continuous_lane_offset_ends_at_its_target() -> None:
    # esmini ends a LaneOffsetAction when its transition is done, continuous or not (so an
    # endTransition of it can trigger what follows)
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Car", speed(10.0))
    offset = model.LaneOffsetAction(
        continuous=True,
        shape=model.DynamicsShape.SINUSOIDAL,
        max_lateral_acc=2.0,
        target=model.AbsoluteTargetLaneOffset(value=1.0),
    )
    bench.start("Car", offset)
    car = bench.actor("Car")
    bench.step(round(2.0 / DT))  # pi * sqrt(1 / 4) = 1.57 s
    assert car.offset == pytest.approx(1.0)
    assert not bench.dispatcher.runs(car)


def test_relative_lane_position_past_the_road_is_on_its_edge() -> None:
    # dLane past the outermost lane: on the edge, as the lane change to such a lane
    bench = Bench("Car", "Other")
    bench.start("Car", teleport(lane(-1, 100.0)))
    beyond = model.RelativeLanePosition(entity_ref="Car", d_lane=-3, ds=10.0, offset=0.5)
    bench.start("Other", teleport(beyond))
    other = bench.actor("Other")
    assert (other.x, other.y) == (pytest.approx(110.0), pytest.approx(-7.0 + 0.5))
    assert other.lane_id == -2


def _relative_speed(
    dimension: model.DynamicsDimension, value: float, delta: float
) -> model.SpeedAction:
    """A linear SpeedAction to Lead's speed plus ``delta``, not continuous."""
    dynamics = model.TransitionDynamics(
        shape=model.DynamicsShape.LINEAR, dimension=dimension, value=value
    )
    relative = model.RelativeTargetSpeed(
        entity_ref="Lead",
        value=delta,
        value_type=model.SpeedTargetValueType.DELTA,
        continuous=False,
    )
    return model.SpeedAction(dynamics=dynamics, target=relative)


def test_relative_target_speed_not_continuous_is_re_read_every_step() -> None:
    # esmini (LongSpeedAction::Step) re-reads a relative target every step, continuous or not:
    # the car goes to the 20 m/s the lead speeds up to meanwhile (+2), not to its 10 m/s at
    # the start
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Lead", teleport(lane(-1, 200.0)))
    bench.start("Lead", speed(10.0))
    bench.start("Car", _relative_speed(model.DynamicsDimension.TIME, 2.0, 2.0))
    bench.start("Lead", speed(20.0))
    bench.step(round(3.0 / DT))
    assert bench.actor("Car").speed == pytest.approx(22.0)
    assert not bench.dispatcher.runs(bench.actor("Car"))


def test_relative_target_speed_over_a_rate_ramps_until_it_meets_the_moving_target() -> None:
    # at 5 m/s² towards a lead that went from 10 to 20 m/s after the start: the ramp goes on
    # past 10 m/s and ends at 20 m/s after 4 s (repeated_relative_speed: the ego stopped
    # 1.5 m/s short of the lead and never re-triggered, 6 m behind esmini)
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Lead", teleport(lane(-1, 200.0)))
    bench.start("Lead", speed(10.0))
    bench.start("Car", _relative_speed(model.DynamicsDimension.RATE, 5.0, 0.0))
    bench.start("Lead", speed(20.0))
    car = bench.actor("Car")
    bench.step(round(3.0 / DT))
    assert car.speed == pytest.approx(15.0)
    assert bench.dispatcher.runs(car)
    bench.step(round(1.0 / DT))
    assert car.speed == pytest.approx(20.0)
    assert not bench.dispatcher.runs(car)


def test_continuous_step_tracking_brakes_within_the_performance() -> None:
    # a continuous, step-shaped relative speed jumps to the target when it starts only; after
    # that esmini tracks within maxDeceleration (10 m/s² here): the follower of a lead that
    # stops dead slows 0.5 m/s a step (highway_merge_advanced's A5: it stopped at once, 33 m
    # short of esmini's)
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Lead", teleport(lane(-1, 200.0)))
    bench.start("Lead", speed(20.0))
    dynamics = model.TransitionDynamics(
        shape=model.DynamicsShape.STEP, dimension=model.DynamicsDimension.TIME, value=0.0
    )
    relative = model.RelativeTargetSpeed(
        entity_ref="Lead", value=0.0, value_type=model.SpeedTargetValueType.DELTA, continuous=True
    )
    bench.start("Car", model.SpeedAction(dynamics=dynamics, target=relative))
    car = bench.actor("Car")
    assert car.speed == 20.0
    bench.start("Lead", speed(0.0))
    bench.step()
    assert car.speed == pytest.approx(19.5)
    bench.step(round(1.0 / DT) - 1)
    assert car.speed == pytest.approx(10.0)
    bench.step(round(1.0 / DT))
    assert car.speed == pytest.approx(0.0)
    assert bench.dispatcher.runs(car)


def test_a_scenario_follower_of_a_lead_stopping_dead_brakes_within_its_performance(
    tmp_path: Path,
) -> None:
    # the same in an authored file: the Car keeps the Lead's speed (step, continuous) from
    # Init; the Lead steps to 0 after 1 s and the Car slows at its maxDeceleration (10 m/s²)
    follow = (
        '<Private entityRef="Car"><PrivateAction><LongitudinalAction><SpeedAction>'
        '<SpeedActionDynamics dynamicsShape="step" dynamicsDimension="time" value="0"/>'
        '<SpeedActionTarget><RelativeTargetSpeed entityRef="Lead" value="0"'
        ' speedTargetValueType="delta" continuous="true"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction></Private>"
    )
    text = osc.scenario(
        entities=osc.CAR.format(name="Car") + osc.CAR.format(name="Lead"),
        init=osc.place("Lead", s=100.0, speed=20.0) + osc.place("Car", s=20.0) + follow,
        stories=osc.story('<EntityRef entityRef="Lead"/>', osc.speed_action(0.0), osc.at_time(1.0)),
        stop=osc.at_time(4.0),
    )
    report = osc.run(osc.write(tmp_path, text), tmp_path)
    car = {round(sample[0]): sample[4] for sample in report.samples["Car"]}
    assert car[1] == pytest.approx(20.0)
    assert 8.0 < car[2] < 14.0  # braking at 10 m/s², not stopped dead (it was 0)
    assert car[4] == pytest.approx(0.0)


def test_a_scenario_ramping_to_an_accelerating_lead_follows_it(tmp_path: Path) -> None:
    # the file's own reading of the same: Car ramps at 5 m/s² from 0 to the Lead's speed
    # (delta 0, not continuous) while the Lead speeds up from 10 at 2 m/s²; they meet at
    # 10 + 2 t = 5 t, t = 3.33 s, 16.7 m/s (it used to stop at the 10 m/s read at the start)
    lead = (
        '<Private entityRef="Lead"><PrivateAction><LongitudinalAction><SpeedAction>'
        '<SpeedActionDynamics dynamicsShape="linear" dynamicsDimension="rate" value="2"/>'
        '<SpeedActionTarget><AbsoluteTargetSpeed value="30"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction></Private>"
    )
    ramp = (
        "<PrivateAction><LongitudinalAction><SpeedAction>"
        '<SpeedActionDynamics dynamicsShape="linear" dynamicsDimension="rate" value="5"/>'
        '<SpeedActionTarget><RelativeTargetSpeed entityRef="Lead" value="0"'
        ' speedTargetValueType="delta" continuous="false"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction>"
    )
    text = osc.scenario(
        entities=osc.CAR.format(name="Car") + osc.CAR.format(name="Lead"),
        init=osc.place("Car", s=20.0, speed=0.0) + osc.place("Lead", s=100.0) + lead,
        stories=osc.story('<EntityRef entityRef="Car"/>', ramp, osc.at_time(-1.0, edge="none")),
        stop=osc.at_time(5.0),
    )
    report = osc.run(osc.write(tmp_path, text), tmp_path)
    car = {round(sample[0]): sample[4] for sample in report.samples["Car"]}
    assert car[2] == pytest.approx(10.0, abs=0.3)  # still ramping past the Lead's start speed
    assert car[5] == pytest.approx(50.0 / 3.0, abs=0.3)  # met the Lead, then kept that speed


def test_a_speed_change_ends_in_the_step_that_completes_its_duration() -> None:
    # 10 -> 15 m/s at 10 m/s² lasts 0.5 s: ten steps of 0.05 s add up to 0.49999999999999994 s,
    # and esmini (within its SMALL_NUMBER) ends the action in the tenth step, not the eleventh,
    # so an event waiting for its end starts a step earlier (repeated_relative_speed: 0.69 m)
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 100.0)))
    bench.start("Car", speed(10.0))
    dynamics = model.TransitionDynamics(
        shape=model.DynamicsShape.LINEAR, dimension=model.DynamicsDimension.RATE, value=10.0
    )
    bench.start(
        "Car", model.SpeedAction(dynamics=dynamics, target=model.AbsoluteTargetSpeed(value=15.0))
    )
    bench.step(9)
    assert bench.dispatcher.runs(bench.actor("Car"))
    bench.step(1)
    assert bench.actor("Car").speed == 15.0
    assert not bench.dispatcher.runs(bench.actor("Car"))


def test_a_lane_change_rate_is_its_peak_lateral_speed() -> None:
    # esmini (TransitionDynamics, dimension rate): a sinusoidal change of 3.5 m at 2 m/s
    # lasts pi/2 * 3.5 / 2 = 2.75 s (not 3.5 / 2 = 1.75 s: the rate is not the mean).
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 500.0)))
    bench.start("Car", speed(10.0))
    change = model.LaneChangeAction(
        dynamics=model.TransitionDynamics(
            shape=model.DynamicsShape.SINUSOIDAL, dimension=model.DynamicsDimension.RATE, value=2.0
        ),
        target=model.RelativeTargetLane(entity_ref="Car", value=-1),
    )
    bench.start("Car", change)
    bench.step(round(1.375 / DT))
    car = bench.actor("Car")
    assert (car.lane_id, abs(car.offset)) == (-1, pytest.approx(1.75, abs=0.1))
    bench.step(round(1.45 / DT))
    assert (bench.actor("Car").lane_id, bench.actor("Car").offset) == (-2, 0.0)


def test_a_speed_change_rate_is_its_peak_acceleration() -> None:
    # esmini reads the rate of every transition as its peak (one TransitionDynamics for speed
    # and lateral actions): 0 -> 10 m/s sinusoidally at 2 m/s² takes pi/2 * 10 / 2 s.
    dynamics = model.TransitionDynamics(
        shape=model.DynamicsShape.SINUSOIDAL, dimension=model.DynamicsDimension.RATE, value=2.0
    )
    assert speeds.transition_duration(dynamics, 0.0, 10.0) == pytest.approx(math.pi * 2.5)
    linear = dataclasses.replace(dynamics, shape=model.DynamicsShape.LINEAR)
    assert speeds.transition_duration(linear, 0.0, 10.0) == pytest.approx(5.0)
