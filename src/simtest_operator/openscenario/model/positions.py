"""Positions, routes and trajectories of the scenario model (tagged unions of frozen dataclasses).

Positions are kept as written (road/lane coordinates, references to other entities): turning them
into world coordinates needs the road geometry and the live world, which is the engine's job.
Routes and trajectories live here too because they hold positions and positions refer to them
(RoutePosition, TrajectoryPosition). Trajectory shapes (polyline, clothoid, clothoid spline and
NURBS) are kept as the file gives them; sampling them into paths is the engine's job.
"""

from __future__ import annotations

import dataclasses
import enum

from simtest_operator.openscenario.model.common import Orientation, Unsupported


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class WorldPosition:
    """Absolute world coordinates; ``None`` means not given (z/p/r on the road surface)."""

    x: float
    y: float
    z: float | None = None
    h: float | None = None
    p: float | None = None
    r: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeWorldPosition:
    """Offset from an entity's reference point in world axes."""

    entity_ref: str
    dx: float
    dy: float
    dz: float | None = None
    orientation: Orientation | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeObjectPosition:
    """Offset from an entity's reference point in the entity's own axes."""

    entity_ref: str
    dx: float
    dy: float
    dz: float | None = None
    orientation: Orientation | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RoadPosition:
    """Road reference-line coordinates (s along the road, t lateral, left positive)."""

    road_id: str
    s: float
    t: float
    orientation: Orientation | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeRoadPosition:
    """Offset from an entity in road coordinates."""

    entity_ref: str
    ds: float
    dt: float
    orientation: Orientation | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LanePosition:
    """Lane coordinates: road, OpenDRIVE lane id, s, lateral offset from the lane centre."""

    road_id: str
    lane_id: int
    s: float
    offset: float = 0.0
    orientation: Orientation | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeLanePosition:
    """Offset from an entity in lanes: ``d_lane`` lanes over, ``ds`` (along the reference line)
    or ``ds_lane`` (along the lane centre) ahead, ``offset`` from the target lane centre."""

    entity_ref: str
    d_lane: int
    ds: float | None = None
    ds_lane: float | None = None
    offset: float = 0.0
    orientation: Orientation | None = None
    line: int | None = None


class RouteStrategy(enum.StrEnum):
    """How to get to a waypoint."""

    FASTEST = "fastest"
    SHORTEST = "shortest"
    LEAST_INTERSECTIONS = "leastIntersections"
    RANDOM = "random"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Waypoint:
    """One route waypoint."""

    position: Position
    route_strategy: RouteStrategy
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Route:
    """A route (inline or resolved from a Route catalog)."""

    name: str
    closed: bool
    waypoints: tuple[Waypoint, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FromCurrentEntity:
    """In-route position: where the entity currently is on the route."""

    entity_ref: str
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FromRoadCoordinates:
    """In-route position: route path s and road t."""

    path_s: float
    t: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FromLaneCoordinates:
    """In-route position: route path s, a lane id and an offset within that lane."""

    path_s: float
    lane_id: int
    lane_offset: float = 0.0
    line: int | None = None


InRoutePosition = FromCurrentEntity | FromRoadCoordinates | FromLaneCoordinates


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RoutePosition:
    """A position along a route."""

    route: Route | Unsupported
    in_route: InRoutePosition
    orientation: Orientation | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrajectoryPosition:
    """A position along a trajectory (1.1+): ``s`` along its shape, ``t`` to its left."""

    trajectory: Trajectory | Unsupported
    s: float
    t: float = 0.0
    orientation: Orientation | None = None
    line: int | None = None


Position = (
    WorldPosition
    | RelativeWorldPosition
    | RelativeObjectPosition
    | RoadPosition
    | RelativeRoadPosition
    | LanePosition
    | RelativeLanePosition
    | RoutePosition
    | TrajectoryPosition
    | Unsupported
)
"""Any position; GeoPosition arrives as :class:`Unsupported`."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Vertex:
    """A polyline vertex, optionally with the time at which it should be reached."""

    position: Position
    time: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Polyline:
    """Straight segments between vertices."""

    vertices: tuple[Vertex, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Clothoid:
    """A clothoid (curvature changing linearly) from ``position`` (or the entity's position)."""

    curvature: float
    curvature_prime: float
    """Rate of curvature change (1/m^2); 1.0's ``curvatureDot`` lands here too."""
    length: float
    start_time: float | None = None
    stop_time: float | None = None
    position: Position | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClothoidSplineSegment:
    """One segment of a clothoid spline (1.3)."""

    curvature_start: float
    curvature_end: float
    length: float
    h_offset: float = 0.0
    time_start: float | None = None
    position_start: Position | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClothoidSpline:
    """A chain of clothoid segments (1.3)."""

    segments: tuple[ClothoidSplineSegment, ...]
    time_end: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ControlPoint:
    """A NURBS control point."""

    position: Position
    time: float | None = None
    weight: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Nurbs:
    """A non-uniform rational B-spline of ``order`` with control points and knot vector."""

    order: int
    control_points: tuple[ControlPoint, ...]
    knots: tuple[float, ...]
    line: int | None = None


Shape = Polyline | Clothoid | ClothoidSpline | Nurbs | Unsupported


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Trajectory:
    """A named trajectory (inline or resolved from a Trajectory catalog)."""

    name: str
    closed: bool
    shape: Shape
    line: int | None = None
