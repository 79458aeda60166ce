"""RelativeClearanceCondition: a lane of the range must exist where the entity is (and run its
way unless opposite lanes count), and no other entity may be in them within the distances
ahead and behind (reference points, or bounding boxes with free space)."""

from __future__ import annotations

from simtest_operator.openscenario import model
from simtest_operator.sim.clearance import is_clear
from tests.sim.worlds import Bench, lane, teleport


def clearance(lo: int, hi: int, *, opposite: bool = False, freespace: bool = False) -> (
        model.RelativeClearanceCondition):  # fmt: skip
    return model.RelativeClearanceCondition(
        lane_ranges=((lo, hi),),
        entity_refs=(),
        opposite_lanes=opposite,
        freespace=freespace,
        distance_forward=40.0,
        distance_backward=20.0,
    )


def bench(other_lane: int, other_s: float) -> Bench:
    b = Bench("Car", "Other")
    b.start("Car", teleport(lane(-1, 100.0)))
    b.start("Other", teleport(lane(other_lane, other_s, h=0.0)))
    b.world.refresh()
    return b


def test_a_missing_or_oncoming_lane_is_not_clear() -> None:
    b = bench(-2, 500.0)
    car = b.actor("Car")
    assert not is_clear(b.world, car, clearance(-2, -2))  # no lane two to the right
    assert not is_clear(b.world, car, clearance(1, 1))  # lane 1 runs the other way
    assert is_clear(b.world, car, clearance(1, 1, opposite=True))


def test_an_entity_in_the_lanes_within_the_distances_blocks() -> None:
    b = bench(-2, 130.0)
    assert not is_clear(b.world, b.actor("Car"), clearance(-1, -1))
    b = bench(-2, 145.0)  # 45 m ahead: beyond 40 m
    assert is_clear(b.world, b.actor("Car"), clearance(-1, -1))
    b = bench(-2, 78.0)  # 22 m behind, but its box reaches within 20 m
    assert is_clear(b.world, b.actor("Car"), clearance(-1, -1))
    assert not is_clear(b.world, b.actor("Car"), clearance(-1, -1, freespace=True))


def test_entities_in_other_lanes_do_not_block() -> None:
    b = bench(-1, 110.0)  # same lane, not in the range -1..-1
    assert is_clear(b.world, b.actor("Car"), clearance(-1, -1))


def test_a_range_reaching_past_the_road_needs_one_of_its_lanes() -> None:
    # esmini's RelativeClearanceCondition: the area exists when any lane of the range does
    # (relative_clearance_oppositLane: -1..3 from the right lane of a two-lane road is clear)
    b = bench(-2, 500.0)
    car = b.actor("Car")
    assert is_clear(b.world, car, clearance(-2, -1))  # -1 (lane -2) exists, -2 does not
    assert is_clear(b.world, car, clearance(-1, 3))  # own lane and lane -2
    assert not is_clear(b.world, car, clearance(-4, -2))  # none of them
    assert not is_clear(b.world, car, clearance(1, 2))  # only oncoming lanes
