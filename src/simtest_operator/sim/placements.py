"""Placements: world poses on the road network, and the lane a pose lies on.

The building blocks that every position kind resolves to (:mod:`~simtest_operator.sim.positions`
dispatches on the kind; :mod:`~simtest_operator.sim.route_legs` and
:mod:`~simtest_operator.sim.shapes` place along routes and trajectory shapes). They live apart
from the dispatch so those modules can use them without importing it back.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

from simtest_operator.errors import ScenarioError, UnsupportedFeatureError
from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneRef:
    """A lane location a resolved position lies on."""

    road_id: str
    lane_id: int
    s: float
    offset: float
    direction: int


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Placement:
    """A resolved position: world pose of the reference point, plus its lane when known."""

    x: float
    y: float
    z: float
    heading: float
    lane: LaneRef | None = None


Resolver = Callable[[model.Position], Placement]
"""Places a position now (:func:`simtest_operator.sim.positions.resolve` bound to a world)."""


def unsupported(node: model.Unsupported) -> UnsupportedFeatureError:
    """The error that makes a run ``Invalid``, naming the element and its line."""
    return UnsupportedFeatureError(
        f"unsupported element: {node.reason}", file=node.file, element=node.element, line=node.line
    )


def orient(base: float, orientation: model.Orientation | None) -> float:
    """``base`` turned by a relative orientation, or replaced by an absolute one."""
    if orientation is None:
        return base
    if orientation.type is model.ReferenceContext.ABSOLUTE:
        return orientation.h
    return base + orientation.h


def add_lanes(lane_id: int, delta: int) -> int:
    """``lane_id`` + ``delta`` on OpenDRIVE lane ids, skipping the centre lane 0."""
    if delta == 0:
        return lane_id
    target = lane_id + delta
    if lane_id < 0 <= target or target <= 0 < lane_id:
        target += 1 if delta > 0 else -1
    return target


def lane_beyond(world: World, road_id: str, s: float, lane_id: int) -> tuple[int, float] | None:
    """For a lane past the road's outermost one on its side at ``s``: that outermost lane and
    the t of the road's outer edge there; on a side without lanes (a one-way connector), the
    innermost lane of the other side and the centre line (None when the road has the lane, or
    no lanes at all). esmini counts lanes a road does not have as 0 m wide, so such a lane's
    centre is the edge: relative lanes and lane changes past the road end there."""
    roads = world.roads
    assert roads is not None
    lanes = [b for b in roads.lanes_at(road_id, s) if b.lane_id != 0]
    side = [b for b in lanes if b.lane_id * lane_id > 0]
    if any(b.lane_id == lane_id for b in side) or not lanes:
        return None
    if not side:
        innermost = min(lanes, key=lambda b: abs(b.lane_id))
        return innermost.lane_id, innermost.t_inner
    outermost = max(side, key=lambda b: abs(b.lane_id))
    return outermost.lane_id, outermost.t_outer


def road_coordinates(world: World, actor: Actor) -> tuple[str, float, float, int]:
    """(road, s, t, direction) of an actor, projecting it onto the roads when not lane-bound."""
    if actor.mode is Mode.ROAD and actor.road_id is not None:
        t = world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset
        return actor.road_id, actor.s, t, actor.direction
    coord = world.road_coord(actor.x, actor.y, actor.heading)
    if coord is None:
        raise ScenarioError(f"entity {actor.name!r} is not on any road")
    aligned = math.cos(actor.heading - coord.heading_of_road) >= 0.0
    return coord.road_id, coord.s, coord.t, 1 if aligned else -1


def lane_placement(
    world: World,
    road_id: str,
    lane_id: int,
    s: float,
    offset: float,
    *,
    orientation: model.Orientation | None,
    direction: int | None,
) -> Placement:
    """Pose at a lane position; ``direction`` None means the lane's driving direction."""
    roads = world.roads
    assert roads is not None
    length = roads.road_length(road_id)
    s = min(max(s, 0.0), length)
    pose = roads.lane_pose(road_id, s, lane_id, offset)
    travel = roads.driving_direction(road_id, lane_id) if direction is None else direction
    heading = orient(pose.heading if travel > 0 else pose.heading + math.pi, orientation)
    heading = math.remainder(heading, 2.0 * math.pi)
    along = 1 if math.cos(heading - pose.heading) >= 0.0 else -1
    return Placement(
        x=pose.x,
        y=pose.y,
        z=pose.z,
        heading=heading,
        lane=LaneRef(road_id=road_id, lane_id=lane_id, s=s, offset=offset, direction=along),
    )


def road_placement(
    world: World,
    road_id: str,
    s: float,
    t: float,
    direction: int | None,
    orientation: model.Orientation | None,
) -> Placement:
    roads = world.roads
    assert roads is not None
    s = min(max(s, 0.0), roads.road_length(road_id))
    lane_id = 0
    for bounds in roads.lanes_at(road_id, s):
        if bounds.lane_id != 0 and bounds.t_min <= t <= bounds.t_max and bounds.width > 0:
            lane_id = bounds.lane_id
    if lane_id == 0:
        pose = roads.road_pose(road_id, s, t)
        travel = direction if direction is not None else 1
        heading = orient(pose.heading if travel > 0 else pose.heading + math.pi, orientation)
        return Placement(x=pose.x, y=pose.y, z=pose.z, heading=heading)
    offset = t - world.lane_t(road_id, s, lane_id)
    return lane_placement(
        world, road_id, lane_id, s, offset, orientation=orientation, direction=direction
    )
