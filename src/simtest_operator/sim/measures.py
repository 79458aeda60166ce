"""Distances between entities (and points) in the coordinate systems OpenSCENARIO names.

``entity``/``world`` measure in the first entity's frame or straight line (shared geometry);
``road``/``lane`` measure along the road (difference of s, in the first entity's travel
direction) when both are on the same road, falling back to the entity frame otherwise. Free-space
variants subtract the bounding boxes. Conditions and distance-keeping actions both use these.
"""

from __future__ import annotations

import math

from simtest_operator import geometry
from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import RoadCoord, RoadNetwork
from simtest_operator.openscenario import model
from simtest_operator.sim import route_planning
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState

_POINT_BOX = BoundingBox(length=0.0, width=0.0, height=0.0)


def point_state(x: float, y: float, heading: float = 0.0) -> EntityState:
    """A zero-size pseudo entity at a point, so points can use the entity geometry."""
    return EntityState(
        id=0,
        name="<point>",
        kind=EntityKind.MISC_OBJECT,
        category="point",
        x=x,
        y=y,
        heading=heading,
        box=_POINT_BOX,
    )


def _along_road(world: World, a: Actor, b: Actor) -> float | None:
    if (
        a.mode is Mode.ROAD
        and b.mode is Mode.ROAD
        and a.road_id is not None
        and a.road_id == b.road_id
    ):
        return (b.s - a.s) * a.direction
    return None


def longitudinal(
    world: World, a: Actor, b: Actor, *, freespace: bool, system: model.CoordinateSystem
) -> float:
    """Signed distance from ``a`` to ``b`` along ``a``'s travel (positive: ``b`` ahead)."""
    if system in (model.CoordinateSystem.ROAD, model.CoordinateSystem.LANE):
        ds = _along_road(world, a, b)
        if ds is not None:
            if not freespace:
                return ds
            a_front, a_rear = a.front_offset, a.box.length - a.front_offset
            b_front, b_rear = b.front_offset, b.box.length - b.front_offset
            same_way = a.direction == b.direction
            if ds >= 0:
                gap = ds - a_front - (b_rear if same_way else b_front)
                return max(gap, 0.0)
            gap = ds + a_rear + (b_front if same_way else b_rear)
            return min(gap, 0.0)
    return geometry.longitudinal_gap(world.state(a.name), world.state(b.name), freespace=freespace)


def lateral(
    world: World, a: Actor, b: Actor, *, freespace: bool, system: model.CoordinateSystem
) -> float:
    """Signed distance from ``a`` to ``b`` across ``a``'s travel (positive: ``b`` to the left)."""
    if (
        system in (model.CoordinateSystem.ROAD, model.CoordinateSystem.LANE)
        and not freespace
        and _along_road(world, a, b) is not None
        and a.road_id is not None
    ):
        ta = world.lane_t(a.road_id, a.s, a.lane_id) + a.offset
        tb = world.lane_t(a.road_id, b.s, b.lane_id) + b.offset
        return (tb - ta) * a.direction
    return geometry.lateral_gap(world.state(a.name), world.state(b.name), freespace=freespace)


def between(
    world: World,
    a: Actor,
    b: Actor,
    *,
    kind: model.RelativeDistanceType,
    freespace: bool,
    system: model.CoordinateSystem,
) -> float:
    """Distance from ``a`` to ``b`` of the requested kind (longitudinal/lateral are signed)."""
    if kind is model.RelativeDistanceType.LONGITUDINAL:
        return longitudinal(world, a, b, freespace=freespace, system=system)
    if kind is model.RelativeDistanceType.LATERAL:
        return lateral(world, a, b, freespace=freespace, system=system)
    sa, sb = world.state(a.name), world.state(b.name)
    return geometry.box_distance(sa, sb) if freespace else geometry.reference_distance(sa, sb)


def to_point(
    state: EntityState,
    point: EntityState,
    *,
    kind: model.RelativeDistanceType,
    freespace: bool,
) -> float:
    """Distance from an entity to a point of the requested kind."""
    if kind is model.RelativeDistanceType.LONGITUDINAL:
        return abs(geometry.longitudinal_gap(state, point, freespace=freespace))
    if kind is model.RelativeDistanceType.LATERAL:
        return abs(geometry.lateral_gap(state, point, freespace=freespace))
    if freespace:
        return geometry.box_distance(state, point)
    return geometry.reference_distance(state, point)


def closing_speed(a: EntityState, b: EntityState, kind: model.RelativeDistanceType) -> float:
    """How fast the distance of ``kind`` from ``a`` to ``b`` shrinks (positive: closing)."""
    avx, avy = a.velocity()
    bvx, bvy = b.velocity()
    rvx, rvy = bvx - avx, bvy - avy
    if kind is model.RelativeDistanceType.LONGITUDINAL:
        return -(rvx * math.cos(a.heading) + rvy * math.sin(a.heading))
    if kind is model.RelativeDistanceType.LATERAL:
        lateral_sign = 1.0 if geometry.lateral_gap(a, b, freespace=False) >= 0 else -1.0
        return -lateral_sign * (-rvx * math.sin(a.heading) + rvy * math.cos(a.heading))
    dx, dy = b.x - a.x, b.y - a.y
    norm = math.hypot(dx, dy)
    if norm < 1e-9:
        return 0.0
    return -(dx * rvx + dy * rvy) / norm


_STRIDE = 1.0
"""m of s between the samples that measure a lane's length."""


def _lane_length(roads: RoadNetwork, road_id: str, lane_id: int, s0: float, s1: float) -> float:
    """Length of the lane's centre line between ``s0`` and ``s1`` (the reference line's where the
    lane is missing), sampled every :data:`_STRIDE` m of s."""
    low, high = min(s0, s1), max(s0, s1)
    steps = max(1, math.ceil((high - low) / _STRIDE))
    ds = (high - low) / steps
    total = 0.0
    for k in range(steps):
        s = low + (k + 0.5) * ds
        try:
            total += roads.lane_stretch(road_id, s, lane_id) * ds
        except ScenarioError:
            total += ds
    return total


def along_lanes(roads: RoadNetwork, start: RoadCoord, goal: RoadCoord) -> float | None:
    """ScenarioRunner's ``alongRoute`` distance from ``start`` to ``goal``: the way along the
    lanes in their driving direction (its GlobalRoutePlanner's route between the two points'
    lane waypoints), lane centre lines on the two end roads and reference lines on the roads
    between. None when no such way leads to ``goal`` (a goal behind on the same road)."""
    lane = start.lane_id
    direction = roads.driving_direction(start.road_id, lane) if lane != 0 else 1
    if start.road_id == goal.road_id:
        if (goal.s - start.s) * direction < 0.0:
            return None
        return _lane_length(roads, start.road_id, lane, start.s, goal.s)
    path = route_planning.plan(roads, (start.road_id, direction), goal.road_id)
    if path is None:
        return None
    end = roads.road_length(start.road_id) if direction > 0 else 0.0
    total = _lane_length(roads, start.road_id, lane, start.s, end)
    total += sum(roads.road_length(road_id) for road_id, _ in path[1:-1])
    last_road, last_direction = path[-1]
    entry = 0.0 if last_direction > 0 else roads.road_length(last_road)
    return total + _lane_length(roads, last_road, goal.lane_id, entry, goal.s)
