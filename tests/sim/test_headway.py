"""Time headway of the deprecated ``alongRoute="false"``: the straight distance between the
reference points (the chord across a curve, not the way along the road), defined only while the
reference is ahead; ScenarioRunner's time to arrival (distance over the speed difference)
instead, under its rules."""

from __future__ import annotations

import math

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import Conditions
from tests.sim.worlds import Bench, lane, speed, teleport

RADIUS = 50.0


def headway(bench: Bench) -> float:
    conditions = Conditions(bench.world, lambda *args: False)
    condition = model.TimeHeadwayCondition(
        entity_ref="Lead", value=1.0, rule=model.Rule.LESS_THAN, freespace=False, along_route=False
    )
    bench.world.refresh()
    return conditions._headway(bench.actor("Car"), condition)


def test_along_route_false_is_the_chord_across_the_curve() -> None:
    bench = Bench("Car", "Lead", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-1, 70.0)))
    chord = 2.0 * (RADIUS + 1.75) * math.sin(60.0 / RADIUS / 2.0)
    assert headway(bench) == pytest.approx(chord / 10.0, rel=1e-3)


def test_no_headway_to_a_reference_alongside() -> None:
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 50.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-2, 49.0)))
    assert math.isnan(headway(bench))


def arrival(bench: Bench, *, freespace: bool = False, along_route: bool = False) -> float:
    """ScenarioRunner's reading of a headway/TTC to ``Lead``: the time to arrival."""
    conditions = Conditions(bench.world, lambda *args: False, scenario_runner=True)
    condition = model.TimeHeadwayCondition(
        entity_ref="Lead",
        value=1.0,
        rule=model.Rule.LESS_THAN,
        freespace=freespace,
        along_route=along_route,
    )
    bench.world.refresh()
    return conditions._arrival(bench.actor("Car"), "Lead", condition)


def test_scenario_runner_reads_the_time_to_arrival() -> None:
    # 30 m apart, 10 m/s against 4 m/s: 30 / 6 = 5 s (esmini's headway would be 30 / 10 = 3 s).
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 20.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-1, 50.0)))
    bench.start("Lead", speed(4.0))
    assert arrival(bench) == pytest.approx(5.0, rel=1e-6)
    box = bench.world.state("Car").box.length
    assert arrival(bench, freespace=True) == pytest.approx((30.0 - box) / 6.0, rel=1e-6)
    # Alongside counts too (no "ahead" test): 1 m apart in the next lane.
    bench.start("Lead", teleport(lane(-2, 20.0)))
    assert math.isfinite(arrival(bench))


def test_scenario_runner_has_no_arrival_at_a_faster_entity() -> None:
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 20.0)))
    bench.start("Car", speed(5.0))
    bench.start("Lead", teleport(lane(-1, 50.0)))
    bench.start("Lead", speed(8.0))
    assert arrival(bench) == math.inf


def test_a_headway_condition_follows_the_rule_set() -> None:
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 20.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-1, 50.0)))
    bench.start("Lead", speed(4.0))
    bench.world.refresh()
    condition = model.TimeHeadwayCondition(
        entity_ref="Lead", value=4.0, rule=model.Rule.LESS_THAN, freespace=False
    )
    body = model.ByEntity(
        triggering_entities=("Car",), rule=model.TriggeringEntitiesRule.ANY, condition=condition
    )
    # esmini: 30 m / 10 m/s = 3 s < 4 s; ScenarioRunner: 30 m / 6 m/s = 5 s.
    assert Conditions(bench.world, lambda *args: False)(body)[0] is True
    assert Conditions(bench.world, lambda *args: False, scenario_runner=True)(body)[0] is False


def test_scenario_runner_along_route_is_the_way_along_the_lane() -> None:
    # InTimeToArrivalToVehicle with alongRoute: its route planner's way between the two lane
    # waypoints, 60 m of the reference arc on a lane centre 1.75 m further out; the chord
    # across the curve without it.
    bench = Bench("Car", "Lead", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-1, 70.0)))
    chord = 2.0 * (RADIUS + 1.75) * math.sin(60.0 / RADIUS / 2.0)
    along = 60.0 * (RADIUS + 1.75) / RADIUS
    assert arrival(bench) == pytest.approx(chord / 10.0, rel=1e-3)
    assert arrival(bench, along_route=True) == pytest.approx(along / 10.0, rel=2e-3)
    # No lane leads back to an entity behind: the straight distance stands in.
    bench.start("Lead", teleport(lane(-1, 5.0)))
    assert arrival(bench, along_route=True) == pytest.approx(arrival(bench), rel=1e-9)


def test_along_lanes_follows_the_lanes_onto_the_next_road() -> None:
    from simtest_operator.opendrive import RoadCoord, RoadNetwork
    from simtest_operator.sim.measures import along_lanes
    from tests.evaluation.test_lane_criteria import TWO_ROADS

    roads = RoadNetwork.from_bytes(TWO_ROADS)

    def at(road: str, s: float) -> RoadCoord:
        return RoadCoord(road_id=road, s=s, t=-1.75, lane_id=-1, heading_of_road=0.0)

    # 20 m to the end of road 1, then 30 m into road 2.
    assert along_lanes(roads, at("1", 80.0), at("2", 30.0)) == pytest.approx(50.0)
    assert along_lanes(roads, at("1", 10.0), at("1", 40.0)) == pytest.approx(30.0)
    # Against the lanes' direction there is no way.
    assert along_lanes(roads, at("2", 30.0), at("1", 80.0)) is None
    assert along_lanes(roads, at("1", 40.0), at("1", 10.0)) is None


def test_scenario_runner_distance_along_route_is_the_way_along_the_lane() -> None:
    # InTriggerDistanceToOSCPosition with alongRoute: 62.1 m along lane -1 of the arc to a point
    # 60 m of reference line ahead, not the 58.4 m chord; esmini's rules keep the chord here.
    bench = Bench("Car", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.world.refresh()
    condition = model.DistanceCondition(
        position=lane(-1, 70.0),
        value=60.0,
        rule=model.Rule.LESS_THAN,
        freespace=False,
        along_route=True,
    )
    body = model.ByEntity(
        triggering_entities=("Car",), rule=model.TriggeringEntitiesRule.ANY, condition=condition
    )
    assert Conditions(bench.world, lambda *args: False, scenario_runner=True)(body)[0] is False
    assert Conditions(bench.world, lambda *args: False)(body)[0] is True


def test_lateral_distance_to_a_position_in_road_coordinates_is_across_the_road() -> None:
    # esmini measures it as the difference of t, wherever along the road the position is: 3.5 m
    # between the centres of lanes -1 and 1 (in the car's own axes, a point 60 m further round
    # the arc is tens of metres to its side)
    bench = Bench("Car", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.world.refresh()

    def within(system: model.CoordinateSystem) -> bool | None:
        condition = model.DistanceCondition(
            position=lane(1, 70.0),
            value=3.6,
            rule=model.Rule.LESS_THAN,
            freespace=False,
            coordinate_system=system,
            relative_distance_type=model.RelativeDistanceType.LATERAL,
        )
        body = model.ByEntity(
            triggering_entities=("Car",),
            rule=model.TriggeringEntitiesRule.ANY,
            condition=condition,
        )
        return Conditions(bench.world, lambda *args: False)(body)[0]

    assert within(model.CoordinateSystem.ROAD) is True
    assert within(model.CoordinateSystem.LANE) is True
    assert within(model.CoordinateSystem.ENTITY) is False
