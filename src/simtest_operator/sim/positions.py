"""Positions: turn an OpenSCENARIO position into a world pose (and a lane, when it names one).

Heading defaults follow the reference player (esmini), checked against its output on the
development corpus: a LanePosition faces the lane's driving direction and a *relative*
orientation adds to that; RoadPosition likewise for the lane under the point; relative positions
(RelativeLane/RelativeRoad/RelativeObject/RelativeWorld) face the way the reference entity travels.
An *absolute* orientation replaces the heading. Lane arithmetic for ``dLane`` is on lane ids,
skipping the centre lane 0, as the standard defines it.
"""

from __future__ import annotations

import math

from simtest_operator.errors import ScenarioError, UnsupportedFeatureError
from simtest_operator.openscenario import model
from simtest_operator.sim import placements, route_legs, shapes
from simtest_operator.sim.world import World


def _require_roads(world: World, position: object) -> None:
    if world.roads is None:
        kind = type(position).__name__
        raise ScenarioError(f"{kind} needs a road network, the scenario has none", element=kind)


ROAD_END_TOLERANCE = 1.0
"""Metres an absolute ``s`` may lie beyond either end of its road (rounding in generated files)."""


def _check_along(world: World, position: model.LanePosition | model.RoadPosition) -> None:
    """Refuse an entity placed at an ``s`` off its road: clamping it put entities on one point at
    the road's end, and a collision there was blamed on the system under test (issue 29). Other
    uses (action targets, conditions) clamp, as esmini does with a warning."""
    roads = world.roads
    assert roads is not None
    length = roads.road_length(position.road_id)
    if not -ROAD_END_TOLERANCE <= position.s <= length + ROAD_END_TOLERANCE:
        raise ScenarioError(
            f"s={position.s:g} is off road {position.road_id!r}, which is {length:g} m long",
            element=type(position).__name__,
            line=position.line,
        )


def resolve(
    world: World, position: model.Position, *, placing: bool = False, mover: str | None = None
) -> placements.Placement:
    """World pose of ``position`` now; ``placing`` (a TeleportAction) refuses an ``s`` beyond
    the road's ends instead of clamping it. ``mover`` is the entity being placed: a relative
    position that runs past its reference road takes the junction exits of its route."""
    if isinstance(position, model.Unsupported):
        raise placements.unsupported(position)
    if isinstance(position, model.WorldPosition):
        return placements.Placement(
            x=position.x, y=position.y, z=position.z or 0.0, heading=position.h or 0.0
        )
    if isinstance(position, model.RelativeWorldPosition):
        ref = world.actor(position.entity_ref)
        return placements.Placement(
            x=ref.x + position.dx,
            y=ref.y + position.dy,
            z=ref.z + (position.dz or 0.0),
            heading=placements.orient(ref.heading, position.orientation),
        )
    if isinstance(position, model.RelativeObjectPosition):
        ref = world.actor(position.entity_ref)
        cos_h, sin_h = math.cos(ref.heading), math.sin(ref.heading)
        return placements.Placement(
            x=ref.x + position.dx * cos_h - position.dy * sin_h,
            y=ref.y + position.dx * sin_h + position.dy * cos_h,
            z=ref.z + (position.dz or 0.0),
            heading=placements.orient(ref.heading, position.orientation),
        )
    if isinstance(position, model.LanePosition):
        _require_roads(world, position)
        if placing:
            _check_along(world, position)
        return placements.lane_placement(
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
        if placing:
            _check_along(world, position)
        # A road position faces along the reference line (s), whatever lane it lies in.
        return placements.road_placement(
            world, position.road_id, position.s, position.t, 1, position.orientation
        )
    if isinstance(position, model.RelativeRoadPosition):
        _require_roads(world, position)
        return _relative_road(world, position, mover)
    if isinstance(position, model.RelativeLanePosition):
        _require_roads(world, position)
        return _relative_lane(world, position, mover)
    if isinstance(position, model.RoutePosition):
        _require_roads(world, position)
        return route_legs.resolve(world, position, lambda p: resolve(world, p))
    if isinstance(position, model.TrajectoryPosition):
        return _trajectory(world, position)
    raise UnsupportedFeatureError(f"position {type(position).__name__} is not supported")


def _trajectory(world: World, position: model.TrajectoryPosition) -> placements.Placement:
    """``s`` along the trajectory's shape, ``t`` to its left; facing along it."""
    trajectory = position.trajectory
    if isinstance(trajectory, model.Unsupported):
        raise placements.unsupported(trajectory)
    if _starts_at_an_entity(trajectory.shape):
        raise ScenarioError(
            f"TrajectoryPosition on trajectory {trajectory.name!r}, whose shape starts where the "
            "following entity is: give the shape a start position",
            element="TrajectoryPosition",
            line=position.line,
        )
    origin = placements.Placement(x=0.0, y=0.0, z=0.0, heading=0.0)  # never used: checked above
    path = shapes.sample(trajectory.shape, lambda p: resolve(world, p), origin)
    x, y, heading = path.at_distance(position.s)
    return placements.Placement(
        x=x - position.t * math.sin(heading),
        y=y + position.t * math.cos(heading),
        z=0.0,
        heading=placements.orient(heading, position.orientation),
    )


def _starts_at_an_entity(shape: model.Shape) -> bool:
    if isinstance(shape, model.Clothoid):
        return shape.position is None
    if isinstance(shape, model.ClothoidSpline):
        return not shape.segments or shape.segments[0].position_start is None
    return False


def _route_through(world: World, mover: str | None, ref: str) -> tuple[str, ...]:
    """Roads to prefer where a relative position continues through a junction: the route of
    the entity being placed, else the reference entity's (esmini; the first declared
    connection when neither has a route)."""
    own = world.actors[mover].route if mover is not None and mover in world.actors else ()
    return own or world.actor(ref).route


def _relative_road(
    world: World, position: model.RelativeRoadPosition, mover: str | None
) -> placements.Placement:
    roads = world.roads
    assert roads is not None
    ref = world.actor(position.entity_ref)
    road_id, s, t, direction = placements.road_coordinates(world, ref)
    # A relative orientation turns from the road's s direction (the standard's reference
    # context for road coordinates; esmini); without one it faces the way the reference travels.
    along_s = (
        position.orientation is not None
        and position.orientation.type is model.ReferenceContext.RELATIVE
    )
    target_s = s + position.ds
    if 0.0 <= target_s <= roads.road_length(road_id):
        return placements.road_placement(
            world,
            road_id,
            target_s,
            t + position.dt,
            1 if along_s else direction,
            position.orientation,
        )
    # Past the road's end: along the reference entity's lane through the links, keeping its
    # lateral place in that lane (plus dt).
    lane_id = world.current_lane(ref)
    location = roads.advance(
        road_id,
        s,
        lane_id,
        position.ds,
        prefer_roads=_route_through(world, mover, position.entity_ref),
    )
    return placements.lane_placement(
        world,
        location.road_id,
        location.lane_id,
        location.s,
        t + position.dt - world.lane_t(road_id, s, lane_id),
        orientation=position.orientation,
        direction=location.direction * (1 if position.ds >= 0 else -1) * direction,
    )


def _relative_lane(
    world: World, position: model.RelativeLanePosition, mover: str | None
) -> placements.Placement:
    roads = world.roads
    assert roads is not None
    ref = world.actor(position.entity_ref)
    road_id, s, _, direction = placements.road_coordinates(world, ref)
    lane_id = placements.add_lanes(world.current_lane(ref), position.d_lane)
    if position.ds is not None:
        target_s = s + position.ds
    else:
        target_s = s + direction * (position.ds_lane or 0.0)
    length = roads.road_length(road_id)
    if not 0.0 <= target_s <= length:
        # Continue along the lane graph past the end of the reference road. Along a route the
        # offset is to the left of the route's direction (esmini's route positions); without
        # one it keeps its side of the reference line, which flips where the roads meet head on.
        route = _route_through(world, mover, position.entity_ref)
        location = roads.advance(
            road_id, s, world.current_lane(ref), target_s - s, prefer_roads=route
        )
        sense = location.direction * (1 if target_s >= s else -1)
        return placements.lane_placement(
            world,
            location.road_id,
            placements.add_lanes(location.lane_id, position.d_lane * sense * direction),
            location.s,
            position.offset * (sense * direction if route else sense),
            orientation=position.orientation,
            direction=None,
        )
    offset = position.offset
    beyond = placements.lane_beyond(world, road_id, target_s, lane_id)
    if beyond is not None:
        # dLane past the road: on its edge (esmini: the lanes it lacks are 0 m wide)
        lane_id, edge = beyond
        offset += edge - world.lane_t(road_id, target_s, lane_id)
    return placements.lane_placement(
        world,
        road_id,
        lane_id,
        target_s,
        offset,
        orientation=position.orientation,
        direction=direction,
    )
