"""Route legs: the stretches of road a route runs along, and positions along them.

A route's path starts at its first waypoint and runs in that waypoint's travel direction (the
driving direction of its lane, or the heading given); between waypoints it follows the road
sequence :mod:`~simtest_operator.sim.route_planning` finds; after the last waypoint it continues
to the end of that road. ``pathS`` of a RoutePosition is measured along these legs.
"""

from __future__ import annotations

import dataclasses
import math

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim import placements, route_planning
from simtest_operator.sim.world import World


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Leg:
    """A stretch of one road: from ``s_from`` towards ``s_to`` travelling ``direction``."""

    road_id: str
    direction: int
    s_from: float
    s_to: float

    @property
    def length(self) -> float:
        return abs(self.s_to - self.s_from)


def _anchor(
    world: World, position: model.Position, place: placements.Resolver
) -> tuple[str, float, int]:
    placement = place(position)
    if placement.lane is not None:
        lane = placement.lane
        return lane.road_id, lane.s, lane.direction
    coord = world.road_coord(placement.x, placement.y, placement.heading)
    if coord is None:
        raise ScenarioError("route waypoint is not on a road", element="Waypoint")
    aligned = math.cos(placement.heading - coord.heading_of_road) >= 0.0
    return coord.road_id, coord.s, 1 if aligned else -1


def legs(world: World, route: model.Route, place: placements.Resolver) -> list[Leg]:
    """The legs of ``route`` (at least one); ``place`` places its waypoints."""
    roads = world.roads
    if roads is None:
        raise ScenarioError("routes need a road network", element="Route", line=route.line)
    if not route.waypoints:
        raise ScenarioError("route has no waypoints", element="Route", line=route.line)
    road_id, s, direction = _anchor(world, route.waypoints[0].position, place)
    result: list[Leg] = []
    for waypoint in route.waypoints[1:]:
        goal_road, goal_s, goal_direction = _anchor(world, waypoint.position, place)
        if goal_road == road_id and (goal_s - s) * direction >= 0.0:
            result.append(Leg(road_id=road_id, direction=direction, s_from=s, s_to=goal_s))
            s = goal_s
            continue
        path = route_planning.plan(roads, (road_id, direction), goal_road, goal_direction)
        if path is None:
            path = route_planning.plan(roads, (road_id, direction), goal_road)
        if path is None:
            raise ScenarioError(
                f"no road path from road {road_id} to road {goal_road}",
                element="Waypoint",
                line=waypoint.line,
            )
        end = roads.road_length(road_id) if direction > 0 else 0.0
        result.append(Leg(road_id=road_id, direction=direction, s_from=s, s_to=end))
        for node_road, node_direction in path[1:-1]:
            length = roads.road_length(node_road)
            start, stop = (0.0, length) if node_direction > 0 else (length, 0.0)
            result.append(Leg(road_id=node_road, direction=node_direction, s_from=start, s_to=stop))
        road_id, direction = path[-1]
        s = 0.0 if direction > 0 else roads.road_length(road_id)
        result.append(Leg(road_id=road_id, direction=direction, s_from=s, s_to=goal_s))
        s = goal_s
    end = roads.road_length(road_id) if direction > 0 else 0.0
    result.append(Leg(road_id=road_id, direction=direction, s_from=s, s_to=end))
    return [leg for leg in result if leg.length > 0.0] or result[-1:]


def at_path_s(route_legs: list[Leg], path_s: float) -> tuple[str, float, int]:
    """(road, s, direction) at ``path_s`` metres along the legs (clamped to the ends)."""
    remaining = max(path_s, 0.0)
    for leg in route_legs:
        if remaining <= leg.length:
            return leg.road_id, leg.s_from + leg.direction * remaining, leg.direction
        remaining -= leg.length
    last = route_legs[-1]
    return last.road_id, last.s_to, last.direction


def resolve(
    world: World, position: model.RoutePosition, place: placements.Resolver
) -> placements.Placement:
    """World pose of a RoutePosition; ``place`` places the route's waypoints."""
    route = position.route
    if isinstance(route, model.Unsupported):
        raise placements.unsupported(route)
    where = position.in_route
    if isinstance(where, model.FromCurrentEntity):
        actor = world.actor(where.entity_ref)
        return placements.Placement(x=actor.x, y=actor.y, z=actor.z, heading=actor.heading)
    road_id, s, _ = at_path_s(legs(world, route, place), where.path_s)
    # As esmini places it (Position::SetRouteLanePosition): pathS picks the road and its s; lane
    # id, lane offset and t are that road's own, whichever way the route runs along it, and the
    # entity faces the lane's driving direction (a relative Orientation turns it from there).
    # So a parked car on a route's far arm stands in the road's lane -1 facing along its s.
    if isinstance(where, model.FromLaneCoordinates):
        return placements.lane_placement(
            world,
            road_id,
            where.lane_id,
            s,
            where.lane_offset,
            orientation=position.orientation,
            direction=None,
        )
    return placements.road_placement(world, road_id, s, where.t, None, position.orientation)
