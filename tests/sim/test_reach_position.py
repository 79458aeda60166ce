"""ReachPositionCondition as esmini reads it: within the tolerance of the position, and, when the
position is written with an ``Orientation``, also facing its heading within 0.05 rad
(esmini's TrigByReachPosition; ``traj-heading-trig.xosc`` stops on a heading this way)."""

from __future__ import annotations

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import REACH_HEADING_TOLERANCE, Conditions
from tests.sim.worlds import Bench, teleport


def reached(bench: Bench, position: model.Position) -> bool:
    bench.world.refresh()
    body = model.ByEntity(
        triggering_entities=("Car",),
        rule=model.TriggeringEntitiesRule.ANY,
        condition=model.ReachPositionCondition(position=position, tolerance=1.0),
    )
    return Conditions(bench.world, lambda *args: False)(body)[0]


def own_lane(h: float | None) -> model.RelativeLanePosition:
    """Where the car is (dLane 0, ds 0), facing ``h`` absolutely when given."""
    orientation = (
        model.Orientation(type=model.ReferenceContext.ABSOLUTE, h=h) if h is not None else None
    )
    return model.RelativeLanePosition(entity_ref="Car", d_lane=0, ds=0.0, orientation=orientation)


@pytest.fixture
def bench() -> Bench:
    bench = Bench("Car", road="arc.xodr")
    # heading 1 rad on the 50 m left arc, along s
    bench.start("Car", teleport(model.LanePosition(road_id="1", lane_id=-1, s=50.0)))
    return bench


def test_without_an_orientation_the_place_is_enough(bench: Bench) -> None:
    assert reached(bench, own_lane(None))


def test_an_orientation_must_be_faced_within_the_tolerance(bench: Bench) -> None:
    assert reached(bench, own_lane(1.0))
    assert reached(bench, own_lane(1.0 + REACH_HEADING_TOLERANCE * 0.9))
    assert not reached(bench, own_lane(1.0 + REACH_HEADING_TOLERANCE * 1.1))
    assert not reached(bench, own_lane(1.5))
