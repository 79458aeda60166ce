"""RelativeClearanceCondition: is an area of lanes around an entity free of other entities?

The area is given in lanes relative to the entity's lane (0 its own lane, positive to its left
in its driving direction) and in metres along the road ahead and behind it. The area exists when
at least one lane of the range exists where the entity is (and runs the entity's way unless
``oppositeLanes``); where none does, it is not clear (the reference player waits on a 2+1 road
until the extra lane begins, and takes a range reaching past the road's edge as clear when one of
its lanes is there, as esmini's RelativeClearanceCondition does). Another entity is
in the area when it is on the same road, in one of the lanes, and its reference point (free
space: its bounding box) lies within the distances. Entities on other roads are not in the area.
"""

from __future__ import annotations

import math

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim import measures, placements
from simtest_operator.sim.actors import Actor
from simtest_operator.sim.lateral import lanes_between
from simtest_operator.sim.world import World


def is_clear(world: World, actor: Actor, condition: model.RelativeClearanceCondition) -> bool:
    """The condition's truth for ``actor`` as the triggering entity."""
    if world.roads is None:
        return True
    road_id, s, _, direction = placements.road_coordinates(world, actor)
    own_lane = world.current_lane(actor)
    if not _lanes_available(world, road_id, s, own_lane, direction, condition):
        return False
    names = condition.entity_refs or tuple(world.actors)
    ahead = condition.distance_forward if condition.distance_forward is not None else math.inf
    behind = condition.distance_backward if condition.distance_backward is not None else math.inf
    for name in names:
        other = world.actor(name)
        if other is actor or not other.placed:
            continue
        try:
            other_road, _, _, _ = placements.road_coordinates(world, other)
        except ScenarioError:
            continue  # not on any road: not in the area
        if other_road != road_id:
            continue
        lane = world.current_lane(other)
        if lane * own_lane < 0 and not condition.opposite_lanes:
            continue
        relative = lanes_between(own_lane, lane) * direction
        if condition.lane_ranges and not any(
            min(lo, hi) <= relative <= max(lo, hi) for lo, hi in condition.lane_ranges
        ):
            continue
        gap = measures.longitudinal(
            world,
            actor,
            other,
            freespace=condition.freespace,
            system=model.CoordinateSystem.ROAD,
        )
        if -behind <= gap <= ahead:
            return False
    return True


def _lanes_available(
    world: World,
    road_id: str,
    s: float,
    own_lane: int,
    direction: int,
    condition: model.RelativeClearanceCondition,
) -> bool:
    roads = world.roads
    assert roads is not None
    ids = sorted(i for i in roads.lane_ids(road_id, s) if i != 0)
    ordered = ids if direction > 0 else ids[::-1]  # rightmost to leftmost in travel direction
    if own_lane not in ordered:
        return False
    here = ordered.index(own_lane)
    for lo, hi in condition.lane_ranges:
        for relative in range(min(lo, hi), max(lo, hi) + 1):
            index = here + relative
            if 0 <= index < len(ordered) and (
                ordered[index] * own_lane > 0 or condition.opposite_lanes
            ):
                return True
    return not condition.lane_ranges
