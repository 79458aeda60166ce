"""OpenDRIVE document model: the parsed road network as immutable values.

The parser turns untrusted XML into these dataclasses once; geometry evaluation and the lane graph
work on them and never look at XML again. Only what the simulator and the evaluation need is kept
(road marks, objects and user data are dropped; signals keep their place, kind and the lanes they
govern). Polynomials keep OpenDRIVE's ``a + b*ds + c*ds^2 +
d*ds^3`` form with their start ``s`` (or ``sOffset`` inside a lane section).
"""

from __future__ import annotations

import dataclasses
import enum
import math


class ContactPoint(enum.StrEnum):
    """Which end of a road a link attaches to."""

    START = "start"
    END = "end"


class ElementType(enum.StrEnum):
    """What a road link points at."""

    ROAD = "road"
    JUNCTION = "junction"


class TrafficRule(enum.StrEnum):
    """Right-hand or left-hand traffic (``road/@rule``, OpenDRIVE 1.5+; RHT when absent)."""

    RHT = "RHT"
    LHT = "LHT"


class GeometryKind(enum.StrEnum):
    """planView geometry primitives."""

    LINE = "line"
    ARC = "arc"
    SPIRAL = "spiral"
    POLY3 = "poly3"
    PARAM_POLY3 = "paramPoly3"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Poly3:
    """A cubic ``a + b*ds + c*ds^2 + d*ds^3`` valid from ``s`` (absolute or section-relative)."""

    s: float
    a: float
    b: float = 0.0
    c: float = 0.0
    d: float = 0.0

    def value(self, s: float) -> float:
        ds = s - self.s
        return self.a + ds * (self.b + ds * (self.c + ds * self.d))

    def slope(self, s: float) -> float:
        ds = s - self.s
        return self.b + ds * (2.0 * self.c + ds * 3.0 * self.d)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Geometry:
    """One planView record: start pose, length and the primitive's parameters.

    ``curvature`` is used by arcs, ``curv_start``/``curv_end`` by spirals, ``u``/``v`` (a, b, c, d)
    by paramPoly3 and ``v`` alone by poly3 (``u`` is then the identity); ``normalized`` is
    paramPoly3's ``pRange="normalized"``.
    """

    kind: GeometryKind
    s: float
    x: float
    y: float
    heading: float
    length: float
    curvature: float = 0.0
    curv_start: float = 0.0
    curv_end: float = 0.0
    u: tuple[float, float, float, float] = (0.0, 1.0, 0.0, 0.0)
    v: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    normalized: bool = False


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RoadLink:
    """A road's predecessor or successor: another road (with contact point) or a junction."""

    element_type: ElementType
    element_id: str
    contact_point: ContactPoint | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Lane:
    """One lane of a lane section. ``widths`` are section-relative; ``borders`` is the 1.4+
    alternative (outer edge as a polynomial of the lateral position), used when ``widths`` is empty.
    """

    id: int
    type: str
    widths: tuple[Poly3, ...] = ()
    borders: tuple[Poly3, ...] = ()
    predecessors: tuple[int, ...] = ()
    successors: tuple[int, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneSection:
    """Lanes valid from ``s`` to the next section. Left lanes have ids > 0 ordered 1, 2, ...
    outwards; right lanes ids < 0 ordered -1, -2, ... outwards; the centre lane (id 0) has no width.
    """

    s: float
    left: tuple[Lane, ...] = ()
    right: tuple[Lane, ...] = ()
    single_side: bool = False

    def lane(self, lane_id: int) -> Lane | None:
        lanes = self.left if lane_id > 0 else self.right
        for lane in lanes:
            if lane.id == lane_id:
                return lane
        return None

    @property
    def lane_ids(self) -> tuple[int, ...]:
        """All non-centre lane ids, left to right (e.g. ``(2, 1, -1, -2)``)."""
        return tuple(lane.id for lane in reversed(self.left)) + tuple(
            lane.id for lane in self.right
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Validity:
    """The lanes ``from_lane`` to ``to_lane`` (inclusive, either order) a signal applies to."""

    from_lane: int
    to_lane: int

    @property
    def lane_ids(self) -> tuple[int, ...]:
        """The non-centre lane ids in the range."""
        low, high = sorted((self.from_lane, self.to_lane))
        return tuple(lane for lane in range(low, high + 1) if lane != 0)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Placement:
    """Where a signal, or a reference to one, applies: at ``s`` (``t`` beside the reference line)
    of ``road_id``, to the traffic it faces (``orientation`` ``+``: towards increasing s, ``-``:
    the other way, ``none``: both) in the lanes of its ``validities``."""

    road_id: str
    s: float
    t: float
    orientation: str
    validities: tuple[Validity, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Signal:
    """A ``<signal>`` of a road: what it is (``country``, ``type``, ``subtype``; e.g.
    ``OpenDRIVE``/``1000001`` a three-lamp traffic light, ``206`` a stop sign) and where."""

    id: str
    name: str
    dynamic: bool
    country: str
    type: str
    subtype: str
    placement: Placement


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SignalReference:
    """A ``<signalReference>``: signal ``signal_id`` (placed on another road) also applies here
    (CARLA's towns put them just inside the junction, where the stop line is)."""

    signal_id: str
    placement: Placement


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SpeedLimit:
    """A road type record's ``<speed max>``: the limit from ``s`` on, in m/s."""

    s: float
    max_speed: float


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Road:
    """An OpenDRIVE road. ``junction`` is ``"-1"`` for roads outside junctions."""

    id: str
    name: str
    length: float
    junction: str
    rule: TrafficRule
    predecessor: RoadLink | None
    successor: RoadLink | None
    geometries: tuple[Geometry, ...]
    elevations: tuple[Poly3, ...] = ()
    superelevations: tuple[Poly3, ...] = ()
    """Roll of the cross-section (rad, positive: the right side down) by ``s``."""
    lane_offsets: tuple[Poly3, ...] = ()
    lane_sections: tuple[LaneSection, ...] = ()
    signals: tuple[Signal, ...] = ()
    signal_references: tuple[SignalReference, ...] = ()
    speed_limits: tuple[SpeedLimit, ...] = ()
    """Sorted by ``s``; records without a finite limit (``no limit``) are left out."""

    @property
    def in_junction(self) -> bool:
        return self.junction not in ("-1", "")

    def speed_limit(self, s: float) -> float | None:
        """The limit (m/s) in force at ``s``, or None where the road sets none."""
        found = None
        for record in self.speed_limits:
            if record.s > s + 1e-9:
                break
            found = record.max_speed
        return found


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneLink:
    """Junction lane link: lane ``from_lane`` of the incoming road continues as ``to_lane`` of the
    connecting road."""

    from_lane: int
    to_lane: int


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Connection:
    """A junction connection from an incoming road into a connecting road (at its contact end)."""

    id: str
    incoming_road: str
    connecting_road: str
    contact_point: ContactPoint
    lane_links: tuple[LaneLink, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Junction:
    id: str
    name: str
    connections: tuple[Connection, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class HeaderOffset:
    """``<header><offset>`` (OpenDRIVE 1.5+): the map's inertial relocation.

    The spec translates the dataset by (x, y, z) and then rotates it by ``heading`` about the new
    origin. Roads and scenario world positions stay in the file's own frame (netconvert ignores
    the offset too, so SUMO's lanes coincide); only reported coordinates go through :meth:`apply`,
    as esmini reports them.
    """

    x: float
    y: float
    z: float
    heading: float

    def apply(self, x: float, y: float, heading: float) -> tuple[float, float, float]:
        """File-frame pose -> the relocated frame (heading in [-pi, pi))."""
        tx, ty = x + self.x, y + self.y
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        turned = (heading + self.heading + math.pi) % (2.0 * math.pi) - math.pi
        return tx * cos_h - ty * sin_h, tx * sin_h + ty * cos_h, turned


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class OpenDrive:
    """A whole parsed document."""

    rev_major: int
    rev_minor: int
    name: str
    roads: tuple[Road, ...]
    junctions: tuple[Junction, ...] = ()
    offset: HeaderOffset | None = None
    """The header offset; None when absent or the identity."""
