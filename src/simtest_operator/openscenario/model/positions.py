"""Positions and routes of the scenario model (a tagged union of frozen dataclasses).

Positions are kept as written (road/lane coordinates, references to other entities): turning them
into world coordinates needs the road geometry and the live world, which is the engine's job.
Routes live here too because route positions and routes refer to each other.
"""

from __future__ import annotations

import dataclasses
import enum
from typing import TYPE_CHECKING

from simtest_operator.openscenario.model.common import Orientation, Unsupported

if TYPE_CHECKING:  # trajectories hold positions: the model modules import each other
    from simtest_operator.openscenario.model.trajectories import Trajectory


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
