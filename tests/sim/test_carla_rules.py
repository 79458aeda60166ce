"""ScenarioRunner's rules on ScenarioRunner-style files (``carla_scenarios.maneuver`` on
``carla/avenue.xodr``): how long actions last (a SpeedAction its dynamics time or distance
whatever the shape, a ``rate`` read as seconds, the speed change going on after the action ended;
a routing action until the last waypoint, never on the external hero; a replaced action has
ended), event priorities not applied, lateral actions aimed at
the ``external_control`` hero ignored and listed, a LaneOffsetAction positive to the right, and the
conditions of 1.0-era files (unsigned longitudinal distance, standstill at <= 0.1 m/s), the
storyboard StopTrigger's conditions stopping nothing.

Each test reads the 1 Hz samples (t, x, y, heading, speed) of the run; the avenue runs along +x,
lane -1 centred at y = -1.75, lane -2 at y = -5.25 (OpenDRIVE's frame, also for ``CARLA:`` files).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.drivermodel import SutConfig, Takeover
from simtest_operator.verdicts import Verdict

from . import carla_scenarios as cs
from .carla_scenarios import run

Sample = tuple[float, float, float, float, float]


def at(samples: tuple[Sample, ...], time: float) -> Sample:
    """The sample taken at ``time`` (whole seconds)."""
    return next(s for s in samples if abs(s[0] - time) < 1e-6)


def adversary(tmp_path: Path, events: str, time_limit: float = 12.0, **kwargs: str) -> list[Sample]:
    report = run(cs.write(tmp_path, cs.maneuver(events, **kwargs)), time_limit=time_limit)
    assert report.rules.startswith("ScenarioRunner"), report.rules
    return list(report.samples["adversary"])


@pytest.mark.parametrize(
    ("dimension", "value"),
    [("time", 3.0), ("distance", 24.0)],
)
def test_a_step_speed_action_lasts_its_time_or_distance(
    tmp_path: Path, dimension: str, value: float
) -> None:
    # ChangeActorTargetSpeed ends after 3 s or 24 m (3 s at 8 m/s), not when the step is done.
    events = cs.event("Go", cs.speed(8.0, dimension=dimension, over=value), cs.at(0)) + cs.event(
        "Stop", cs.speed(0.0), cs.after("Go")
    )
    samples = tuple(adversary(tmp_path, events))
    assert at(samples, 1.0)[4] == pytest.approx(8.0)
    assert at(samples, 3.0)[4] == pytest.approx(8.0)
    assert at(samples, 4.0)[4] == 0.0


def test_a_rate_is_read_as_seconds_and_the_speed_change_goes_on(tmp_path: Path) -> None:
    # A rate of 1 m/s^2 to 8 m/s: the speed takes 8 s, ScenarioRunner's action ends after 1 s
    # (the value read as a duration) and its controller keeps the target, so the lane offset
    # waiting for the action's end starts at once and the speed still reaches 8 m/s.
    events = cs.event(
        "Accelerate", cs.speed(8.0, shape="linear", dimension="rate", over=1.0), cs.at(0)
    ) + cs.event("Shift", cs.lane_offset(1.0), cs.after("Accelerate"))
    samples = tuple(adversary(tmp_path, events))
    assert abs(at(samples, 4.0)[2] + 5.25) > 0.5  # shifted long before the speed was reached
    assert at(samples, 4.0)[4] == pytest.approx(4.0, abs=0.2)
    assert at(samples, 9.0)[4] == pytest.approx(8.0)


def test_priorities_are_not_applied(tmp_path: Path) -> None:
    # An `overwrite` event starting at 1 s leaves the running speed change alone.
    events = cs.event(
        "Speed", cs.speed(10.0, shape="linear", dimension="time", over=4.0), cs.at(0)
    ) + cs.event("Shift", cs.lane_offset(1.0), cs.at(1.0), priority="overwrite")
    samples = tuple(adversary(tmp_path, events))
    assert at(samples, 5.0)[4] == pytest.approx(10.0)
    assert abs(at(samples, 5.0)[2] + 5.25) > 0.5


def test_acquire_position_lasts_until_the_position_is_reached(tmp_path: Path) -> None:
    # 8 m/s from s=60 to s=100: ChangeActorWaypoints ends about 4.5 s later, then the offset.
    acquire = """<RoutingAction><AcquirePositionAction><Position>
                  <LanePosition roadId="1" laneId="-2" s="100" offset="0"/>
                </Position></AcquirePositionAction></RoutingAction>"""
    events = (
        cs.event("Go", cs.speed(8.0), cs.at(0))
        + cs.event("Route", acquire, cs.at(0))
        + cs.event("Shift", cs.lane_offset(1.0), cs.after("Route"))
    )
    samples = tuple(adversary(tmp_path, events))
    assert at(samples, 4.0)[2] == pytest.approx(-5.25, abs=0.05)
    assert abs(at(samples, 8.0)[2] + 5.25) > 0.5


@pytest.mark.parametrize(
    ("description", "written_y"),
    [("CARLA:Rules", 5.25), ("Rules", -5.25)],
)
def test_lane_offset_is_positive_to_the_right_for_scenario_runner(
    tmp_path: Path, description: str, written_y: float
) -> None:
    # Without the CARLA: header positions stay in OpenDRIVE's frame (ScenarioRunner negates y
    # only after the header), but a lane offset goes to the right in either file (ScenarioRunner
    # measures it from the waypoint in CARLA's frame): from lane -2 towards the sidewalk.
    events = cs.event("Shift", cs.lane_offset(1.0), cs.at(0))
    position = f'<WorldPosition x="60" y="{written_y:g}" z="0" h="0"/>'
    samples = tuple(
        adversary(tmp_path, events, description=description, adversary_position=position)
    )
    assert at(samples, 0.0)[2] == pytest.approx(-5.25)
    assert at(samples, 6.0)[2] == pytest.approx(-6.25, abs=0.05)


def test_lateral_actions_on_the_external_hero_are_ignored(tmp_path: Path) -> None:
    events = cs.event("HeroShift", cs.lane_offset(1.5, continuous=True), cs.at(1.0)) + cs.event(
        "HeroChange",
        """<LateralAction><LaneChangeAction>
                  <LaneChangeActionDynamics dynamicsShape="sinusoidal" value="2" dynamicsDimension="time"/>
                  <LaneChangeTarget><RelativeTargetLane entityRef="hero" value="-1"/></LaneChangeTarget>
                </LaneChangeAction></LateralAction>""",  # noqa: E501
        cs.at(2.0),
    )
    stop = cs.criteria("CollisionTest", "KeepLaneTest", distance=None)
    text = cs.maneuver(events, actor="hero", stop=stop)
    report = run(cs.write(tmp_path, text), time_limit=8.0)
    ignored = report.outcome.ignored_elements
    assert "LaneOffsetAction on the externally controlled hero" in ignored
    assert "LaneChangeAction on the externally controlled hero" in ignored
    # The SUT keeps its lane; the actions never reach their goals, so (as in ScenarioRunner)
    # the story does not end and the run times out with the criteria passed.
    assert all(abs(s[2] + 1.75) < 0.2 for s in report.samples["hero"])
    assert max(s[4] for s in report.samples["hero"]) > 5.0
    assert report.outcome.verdict is Verdict.TIMEOUT
    assert report.outcome.metrics["criteria.KeepLaneTest"] == 1.0


def test_longitudinal_distance_is_unsigned_in_a_1_0_file(tmp_path: Path) -> None:
    # The adversary stands 15 m behind the hero: "more than 10 m" holds for ScenarioRunner
    # (esmini reads a 1.0 file's distance to a reference behind as negative).
    behind = """<ByEntityCondition>
                  <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="hero"/>
                  </TriggeringEntities>
                  <EntityCondition><RelativeDistanceCondition entityRef="adversary"
                    freespace="false" relativeDistanceType="longitudinal" value="10"
                    rule="greaterThan"/>
                  </EntityCondition>
                </ByEntityCondition>"""
    events = cs.event("Go", cs.speed(5.0), behind)
    position = '<LanePosition roadId="1" laneId="-2" s="5" offset="0"/>'
    samples = tuple(adversary(tmp_path, events, adversary_position=position))
    assert at(samples, 2.0)[4] == pytest.approx(5.0)


def test_standstill_holds_at_a_crawl(tmp_path: Path) -> None:
    # 0.05 m/s is standing still for ScenarioRunner's rules: after 1 s the adversary drives off.
    still = """<ByEntityCondition>
                  <TriggeringEntities triggeringEntitiesRule="any">
                    <EntityRef entityRef="adversary"/>
                  </TriggeringEntities>
                  <EntityCondition><StandStillCondition duration="1"/></EntityCondition>
                </ByEntityCondition>"""
    events = cs.event("Crawl", cs.speed(0.05), cs.at(0)) + cs.event("Go", cs.speed(6.0), still)
    samples = tuple(adversary(tmp_path, events))
    assert at(samples, 3.0)[4] == pytest.approx(6.0)


def test_a_replaced_action_has_ended(tmp_path: Path) -> None:
    # A newer SpeedAction replaces the first at 1 s; ScenarioRunner knows one end of an element,
    # so the offset waiting for the first one's endTransition starts then (not only on a goal).
    events = (
        cs.event("First", cs.speed(5.0, shape="linear", dimension="time", over=10.0), cs.at(0))
        + cs.event("Second", cs.speed(8.0), cs.at(1.0))
        + cs.event("Shift", cs.lane_offset(1.0), cs.after("First"))
    )
    samples = tuple(adversary(tmp_path, events))
    assert at(samples, 3.0)[4] == pytest.approx(8.0)
    assert abs(at(samples, 6.0)[2] + 5.25) > 0.5


def test_a_route_of_the_external_hero_never_ends(tmp_path: Path) -> None:
    # ScenarioRunner's ExternalControl reports no reached goal: the hero drives past the
    # position, the event waiting for the routing action's end never starts.
    acquire = """<RoutingAction><AcquirePositionAction><Position>
                  <LanePosition roadId="1" laneId="-1" s="40" offset="0"/>
                </Position></AcquirePositionAction></RoutingAction>"""
    events = cs.event("Route", acquire, cs.at(0)) + cs.event(
        "Brake", cs.speed(0.0), cs.after("Route")
    )
    report = run(cs.write(tmp_path, cs.maneuver(events, actor="hero")), time_limit=10.0)
    hero = report.samples["hero"]
    assert max(s[1] for s in hero) > 60.0
    assert hero[-1][4] > 5.0


def test_the_storyboard_stop_trigger_stops_nothing(tmp_path: Path) -> None:
    # ScenarioRunner reads only criteria_* out of the storyboard StopTrigger; a SimulationTime
    # stop beside them does not end the run (OpenScenario._create_behavior builds no stop from
    # it): the run lasts until the act stopped after the hero drove 120 m, then passes.
    stop = (
        cs.criteria("CollisionTest", distance=None)
        + """
        <Condition name="EndAtThree" delay="0" conditionEdge="rising">
          <ByValueCondition><SimulationTimeCondition value="3" rule="greaterThan"/>
          </ByValueCondition>
        </Condition>"""
    )
    sut = SutConfig(takeover=Takeover.AFTER_INIT, desired_speed=10.0)
    report = run(cs.write(tmp_path, cs.follow_leading(stop=stop)), sut=sut, time_limit=40.0)
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
    assert report.outcome.metrics["simulatedSeconds"] > 5.0  # not 3 s


def test_the_ego_is_the_vehicle_typed_ego_vehicle(tmp_path: Path) -> None:
    # ScenarioRunner's ego vehicles are the vehicles with the property type=ego_vehicle
    # (OpenScenarioConfiguration._extract_vehicle_information), whatever their names; its
    # criteria judge them. Here the first vehicle is not the ego, the second is.
    from simtest_operator.openscenario import load_scenario
    from simtest_operator.sim.engine import pick_ego

    text = (
        cs.follow_leading()
        .replace('"hero"', '"first"')
        .replace('value="ego_vehicle"', 'value="was-ego"')
        .replace('value="simulation"', 'value="ego_vehicle"')
        .replace('value="was-ego"', 'value="simulation"')
    )
    scenario = load_scenario(cs.write(tmp_path, text))
    assert [obj.name for obj in scenario.entities][:2] == ["first", "adversary"]
    assert pick_ego(scenario, None, scenario_runner=True) == "adversary"
    assert pick_ego(scenario, None) == "first"  # esmini's rules: the first vehicle
    assert pick_ego(scenario, "first", scenario_runner=True) == "first"  # configured wins


def test_scenario_runner_reads_only_position_speed_and_controller_from_init(
    tmp_path: Path,
) -> None:
    # OpenScenarioConfiguration takes the start pose from the last Position below the entity's
    # Privates (here the AcquirePositionAction's) and the speed from the last
    # AbsoluteTargetSpeed, set at once; the Init's lane offset is never built.
    adversary_init = f"""
        <Private entityRef="adversary">{cs.ADVERSARY_AHEAD}
          <PrivateAction>{cs.speed(8, shape="linear", over=4)}</PrivateAction>
          <PrivateAction>{cs.lane_offset(1)}</PrivateAction>
          <PrivateAction><RoutingAction><AcquirePositionAction><Position>
            <LanePosition roadId="1" laneId="-1" s="120" offset="0"/>
          </Position></AcquirePositionAction></RoutingAction></PrivateAction>
        </Private>"""
    time_stop = """
        <Condition name="Late" delay="0" conditionEdge="rising"><ByValueCondition>
          <SimulationTimeCondition value="5" rule="greaterThan"/></ByValueCondition></Condition>"""
    carla = run(cs.write(tmp_path, cs.follow_leading(adversary_init=adversary_init)))
    assert carla.rules.startswith("ScenarioRunner"), carla.rules
    plain = cs.follow_leading(
        adversary_init=adversary_init, stop=time_stop, description="plain"
    ).replace("external_control", "some_driver")
    esmini = run(cs.write(tmp_path, plain, name="plain.xosc"))
    assert esmini.rules.startswith("OpenSCENARIO"), esmini.rules

    _, x, y, _, speed = at(carla.samples["adversary"], 0.0)
    assert (x, y, speed) == pytest.approx((120.0, -1.75, 8.0), abs=0.01)
    assert all(s[2] == pytest.approx(-1.75, abs=0.01) for s in carla.samples["adversary"])
    ignored = carla.outcome.ignored_elements
    assert any(e.startswith("Init LaneOffsetAction of 'adversary'") for e in ignored), ignored
    assert any(e.startswith("Init AcquirePositionAction of 'adversary'") for e in ignored)

    _, x, _, _, speed = at(esmini.samples["adversary"], 0.0)
    assert (x, speed) == pytest.approx((70.0, 0.0), abs=0.01)
    assert any(abs(s[2] + 1.75) > 0.3 for s in esmini.samples["adversary"])
