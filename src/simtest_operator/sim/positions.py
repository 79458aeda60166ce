"""Positions: turn an OpenSCENARIO position into a world pose (and a lane, when it names one).

Heading defaults follow the reference player (esmini), checked against its output on the
development corpus: a LanePosition faces the lane's driving direction and a *relative*
orientation adds to that; RoadPosition likewise for the lane under the point; relative positions
(RelativeLane/RelativeRoad/RelativeObject/RelativeWorld) face the way the reference entity travels.
An *absolute* orientation replaces the heading. Lane arithmetic for ``dLane`` is on lane ids,
skipping the centre lane 0, as the standard defines it.
"""

from __future__ import annotations

import dataclasses
import math

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


def unsupported(node: model.Unsupported) -> UnsupportedFeatureError:
    """The error that makes a run ``Invalid``, naming the element and its line."""
    return UnsupportedFeatureError(
        f"unsupported element: {node.reason}", file=node.file, element=node.element, line=node.line
    )


def _orient(base: float, orientation: model.Orientation | None) -> float:
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


def _require_roads(world: World, position: object) -> None:
    if world.roads is None:
        kind = type(position).__name__
        raise ScenarioError(f"{kind} needs a road network, the scenario has none", element=kind)


def resolve(world: World, position: model.Position) -> Placement:
    """World pose of ``position`` now."""
    if isinstance(position, model.Unsupported):
        raise unsupported(position)
    if isinstance(position, model.WorldPosition):
        return Placement(x=position.x, y=position.y, z=position.z or 0.0, heading=position.h or 0.0)
    if isinstance(position, model.RelativeWorldPosition):
        ref = world.actor(position.entity_ref)
        return Placement(
            x=ref.x + position.dx,
            y=ref.y + position.dy,
            z=ref.z + (position.dz or 0.0),
            heading=_orient(ref.heading, position.orientation),
        )
    if isinstance(position, model.RelativeObjectPosition):
        ref = world.actor(position.entity_ref)
        cos_h, sin_h = math.cos(ref.heading), math.sin(ref.heading)
        return Placement(
            x=ref.x + position.dx * cos_h - position.dy * sin_h,
            y=ref.y + position.dx * sin_h + position.dy * cos_h,
            z=ref.z + (position.dz or 0.0),
            heading=_orient(ref.heading, position.orientation),
        )
    if isinstance(position, model.LanePosition):
        _require_roads(world, position)
        return lane_placement(
            world,
            position.road_id,
            position.lane_id,
            position.s,
            position.offset,
            orientation=position.orientation,
            direction=None,
        )
    if isinstance(position, model.RoadPosition):
        _require_roads(world, position)
        # A road position faces along the reference line (s), whatever lane it lies in.
        return road_placement(
            world, position.road_id, position.s, position.t, 1, position.orientation
        )
    if isinstance(position, model.RelativeRoadPosition):
        _require_roads(world, position)
        ref = world.actor(position.entity_ref)
        road_id, s, t, direction = road_coordinates(world, ref)
        return road_placement(
            world, road_id, s + position.ds, t + position.dt, direction, position.orientation
        )
    if isinstance(position, model.RelativeLanePosition):
        _require_roads(world, position)
        return _relative_lane(world, position)
    if isinstance(position, model.RoutePosition):
        _require_roads(world, position)
        from simtest_operator.sim import routes

        return routes.resolve(world, position)
    if isinstance(position, model.TrajectoryPosition):
        return _trajectory(world, position)
    raise UnsupportedFeatureError(f"position {type(position).__name__} is not supported")


def _trajectory(world: World, position: model.TrajectoryPosition) -> Placement:
    """``s`` along the trajectory's shape, ``t`` to its left; facing along it."""
    trajectory = position.trajectory
    if isinstance(trajectory, model.Unsupported):
        raise unsupported(trajectory)
    if _starts_at_an_entity(trajectory.shape):
        raise ScenarioError(
            f"TrajectoryPosition on trajectory {trajectory.name!r}, whose shape starts where the "
            "following entity is: give the shape a start position",
            element="TrajectoryPosition",
            line=position.line,
        )
    from simtest_operator.sim import shapes

    origin = Placement(x=0.0, y=0.0, z=0.0, heading=0.0)  # never used: checked above
    path = shapes.sample(trajectory.shape, lambda p: resolve(world, p), origin)
    x, y, heading = path.at_distance(position.s)
    return Placement(
        x=x - position.t * math.sin(heading),
        y=y + position.t * math.cos(heading),
        z=0.0,
        heading=_orient(heading, position.orientation),
    )


def _starts_at_an_entity(shape: model.Shape) -> bool:
    if isinstance(shape, model.Clothoid):
        return shape.position is None
    if isinstance(shape, model.ClothoidSpline):
        return not shape.segments or shape.segments[0].position_start is None
    return False


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
    heading = _orient(pose.heading if travel > 0 else pose.heading + math.pi, orientation)
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
        heading = _orient(pose.heading if travel > 0 else pose.heading + math.pi, orientation)
        return Placement(x=pose.x, y=pose.y, z=pose.z, heading=heading)
    offset = t - world.lane_t(road_id, s, lane_id)
    return lane_placement(
        world, road_id, lane_id, s, offset, orientation=orientation, direction=direction
    )


def _relative_lane(world: World, position: model.RelativeLanePosition) -> Placement:
    roads = world.roads
    assert roads is not None
    ref = world.actor(position.entity_ref)
    road_id, s, _, direction = road_coordinates(world, ref)
    lane_id = add_lanes(world.current_lane(ref), position.d_lane)
    if position.ds is not None:
        target_s = s + position.ds
    else:
        target_s = s + direction * (position.ds_lane or 0.0)
    length = roads.road_length(road_id)
    if not 0.0 <= target_s <= length:
        # Continue along the lane graph past the end of the reference road.
        location = roads.advance(road_id, s, lane_id, target_s - s)
        return lane_placement(
            world,
            location.road_id,
            location.lane_id,
            location.s,
            position.offset,
            orientation=position.orientation,
            direction=location.direction * (1 if target_s >= s else -1) * direction,
        )
    return lane_placement(
        world,
        road_id,
        lane_id,
        target_s,
        position.offset,
        orientation=position.orientation,
        direction=direction,
    )
