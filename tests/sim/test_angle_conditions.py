"""AngleCondition and RelativeAngleCondition on the 50 m radius left arc: in the ``entity`` and
``world`` frames the world heading (s/50 along the arc), in ``road``/``lane`` the heading from
the road's direction of increasing s at the entity (0 driving along s, pi against it); angles
compare round the circle, within the tolerance."""

from __future__ import annotations

import math

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import Conditions
from tests.sim.worlds import Bench, lane, teleport

RADIUS = 50.0
ENTITY, ROAD, LANE = (model.CoordinateSystem.ENTITY, model.CoordinateSystem.ROAD,
                      model.CoordinateSystem.LANE)  # fmt: skip


def holds(bench: Bench, condition: model.EntityCondition, name: str = "Car") -> bool:
    bench.world.refresh()
    body = model.ByEntity(
        triggering_entities=(name,),
        rule=model.TriggeringEntitiesRule.ANY,
        condition=condition,
    )
    return Conditions(bench.world, lambda *args: False)(body)[0]


def heading(angle: float, tolerance: float = 0.01,
            system: model.CoordinateSystem = ENTITY) -> model.AngleCondition:  # fmt: skip
    return model.AngleCondition(
        angle_type=model.AngleType.HEADING, angle=angle, tolerance=tolerance,
        coordinate_system=system,
    )  # fmt: skip


@pytest.fixture
def bench() -> Bench:
    bench = Bench("Car", "Other", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 50.0)))  # heading 1 rad, along s
    bench.start("Other", teleport(lane(1, 100.0)))  # heading 2 rad + pi, against s
    return bench


def test_world_heading_within_the_tolerance(bench: Bench) -> None:
    assert holds(bench, heading(1.0))
    assert holds(bench, heading(1.0 + 2 * math.pi))
    assert holds(bench, heading(1.009))
    assert not holds(bench, heading(1.02))
    assert not holds(bench, heading(-1.0))


def test_heading_wraps_round_the_circle(bench: Bench) -> None:
    # Other faces 2 + pi, which is 2 - pi (-1.14 rad) round the circle: both spellings match
    assert holds(bench, heading(2.0 + math.pi), name="Other")
    assert holds(bench, heading(2.0 - math.pi), name="Other")


def test_road_and_lane_frames_measure_from_the_roads_direction(bench: Bench) -> None:
    assert holds(bench, heading(0.0, system=ROAD))
    assert not holds(bench, heading(1.0, system=ROAD))
    assert holds(bench, heading(math.pi, system=LANE), name="Other")
    assert holds(bench, heading(-math.pi, system=ROAD), name="Other")


def test_pitch_and_roll_of_a_flat_road_are_zero(bench: Bench) -> None:
    for kind in (model.AngleType.PITCH, model.AngleType.ROLL):
        assert holds(bench, model.AngleCondition(angle_type=kind, angle=0.0, tolerance=1e-6))


def test_relative_angle_is_the_difference_to_the_reference(bench: Bench) -> None:
    def relative(angle: float, system: model.CoordinateSystem) -> model.RelativeAngleCondition:
        return model.RelativeAngleCondition(
            entity_ref="Other", angle_type=model.AngleType.HEADING, angle=angle, tolerance=0.01,
            coordinate_system=system,
        )  # fmt: skip

    # world: 1 - (2 + pi) = -1 - pi, i.e. pi - 1 round the circle
    assert holds(bench, relative(math.pi - 1.0, ENTITY))
    assert not holds(bench, relative(-1.0, ENTITY))
    # road: 0 - pi
    assert holds(bench, relative(math.pi, ROAD))
    assert not holds(bench, relative(math.pi - 1.0, ROAD))


def test_an_unplaced_reference_does_not_hold(bench: Bench) -> None:
    bench = Bench("Car", "Other", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 50.0)))
    condition = model.RelativeAngleCondition(
        entity_ref="Other", angle_type=model.AngleType.HEADING, angle=0.0, tolerance=10.0
    )
    assert not holds(bench, condition)
