"""The road network facade the simulator uses: poses on roads and lanes, projection, lane graph.

It binds the parsed document to prepared evaluators (reference lines, lane layouts, the search
index, the lane graph), all built once per map. Coordinates follow OpenDRIVE: x/y/z in metres,
heading in radians counter-clockwise from +x, s along the reference line, t positive to the left.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection, Iterator, Mapping, Sequence
from pathlib import Path

from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import lanes, models, parsing, planview, projection, topology

DRIVABLE_LANE_TYPES = frozenset(
    {
        "driving", "entry", "exit", "onRamp", "offRamp", "connectingRamp", "bidirectional",
        "parking", "stop", "restricted", "mwyEntry", "mwyExit", "special1", "special2",
        "special3", "roadWorks", "slipLane", "bus", "taxi", "HOV",
    }
)  # fmt: skip
"""Lane types a vehicle may be on without being off road (OpenDRIVE 1.4-1.8 names)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Pose:
    """A world pose: position in metres, heading in radians (counter-clockwise from +x)."""

    x: float
    y: float
    z: float = 0.0
    heading: float = 0.0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RoadCoord:
    """A world point in road coordinates.

    ``lane_id`` is the lane containing ``t``, or the nearest lane when the point is off the road
    surface (``distance`` > 0 then says by how much); ``heading_of_road`` is the reference line's
    heading at ``s`` (direction of increasing s).
    """

    road_id: str
    s: float
    t: float
    lane_id: int
    heading_of_road: float
    lane_type: str = "none"
    distance: float = 0.0

    @property
    def on_road(self) -> bool:
        return self.distance <= 0.0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneLocation:
    """Where moving along lanes ended: ``direction`` is +1 if travel continues towards increasing
    s on ``road_id``, -1 otherwise; ``remaining`` is the distance that could not be travelled
    because the lane ends (0 when the whole distance was covered)."""

    road_id: str
    s: float
    lane_id: int
    direction: int
    remaining: float = 0.0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneStretch:
    """A piece of one lane (within one lane section) a walk along lanes passes: from ``s_from``
    to ``s_to`` on ``road_id`` (``direction`` +1 when s grows on the way), starting ``start``
    metres of s after the walk's start."""

    road_id: str
    lane_id: int
    s_from: float
    s_to: float
    direction: int
    start: float


class RoadNetwork:
    """An OpenDRIVE road network ready for geometric queries."""

    def __init__(self, document: models.OpenDrive) -> None:
        self.document = document
        self._roads = {road.id: road for road in document.roads}
        self._order = [road.id for road in document.roads]
        self._index_of = {road_id: k for k, road_id in enumerate(self._order)}
        self._lines = [
            planview.ReferenceLine(road.geometries, road.length) for road in document.roads
        ]
        self._layouts = [lanes.RoadLayout(road) for road in document.roads]
        self._elevations = [lanes.Piecewise(road.elevations) for road in document.roads]
        self._rolls = [lanes.Piecewise(road.superelevations) for road in document.roads]
        self._graph = topology.LaneGraph(document)
        self._index: projection.RoadIndex | None = None

    @classmethod
    def from_file(cls, path: Path) -> RoadNetwork:
        return cls(parsing.load(path))

    @classmethod
    def from_bytes(cls, data: bytes, *, source: str = "<xodr>") -> RoadNetwork:
        return cls(parsing.parse(data, source=source))

    # -- roads ---------------------------------------------------------------------------------

    @property
    def roads(self) -> Mapping[str, models.Road]:
        return self._roads

    def road(self, road_id: str) -> models.Road:
        try:
            return self._roads[road_id]
        except KeyError:
            raise ScenarioError(f"road {road_id!r} does not exist in the road network") from None

    def road_length(self, road_id: str) -> float:
        return self.road(road_id).length

    def _slot(self, road_id: str) -> int:
        try:
            return self._index_of[road_id]
        except KeyError:
            raise ScenarioError(f"road {road_id!r} does not exist in the road network") from None

    # -- poses ---------------------------------------------------------------------------------

    def reference_pose(self, road_id: str, s: float) -> Pose:
        """Pose on the reference line at ``s`` (clamped to the road), heading along +s."""
        k = self._slot(road_id)
        x, y, heading, _ = self._lines[k].at(s)
        return Pose(x=x, y=y, z=self._elevations[k].value(s), heading=heading)

    def road_pose(self, road_id: str, s: float, t: float) -> Pose:
        """Pose at lateral offset ``t`` from the reference line, heading along +s."""
        k = self._slot(road_id)
        x, y, heading, _ = self._lines[k].at(s)
        across, _, rise, forward = self._tilted(k, s, t, 0.0)
        return Pose(
            x=x - across * math.sin(heading) + forward * math.cos(heading),
            y=y + across * math.cos(heading) + forward * math.sin(heading),
            z=self._elevations[k].value(s) + rise,
            heading=heading,
        )

    def roll(self, road_id: str, s: float) -> float:
        """Superelevation (rad) of the road's cross-section at ``s`` (0: flat)."""
        return self._rolls[self._slot(road_id)].value(s)

    def banked(self, road_id: str) -> bool:
        """Whether the road has a superelevation profile."""
        return bool(self._rolls[self._slot(road_id)])

    def _tilted(
        self, k: int, s: float, t: float, slope: float
    ) -> tuple[float, float, float, float]:
        """(sideways offset, its rate along s, height, forward offset) of the point ``t`` across
        the road, where ``slope`` is dt/ds. OpenDRIVE's t axis rolls with the superelevation
        about the road's (pitched) tangent: on a banked road an offset reaches less far
        sideways, rises or falls, and on a slope also shifts along the road (as esmini)."""
        rolls = self._rolls[k]
        if not rolls:
            return t, slope, 0.0, 0.0
        roll, roll_rate = rolls.value_slope(s)
        pitch = math.atan(self._elevations[k].value_slope(s)[1])
        cos_r, sin_r = math.cos(roll), math.sin(roll)
        sideways = slope * cos_r - t * sin_r * roll_rate
        return t * cos_r, sideways, t * sin_r * math.cos(pitch), -t * sin_r * math.sin(pitch)

    def lane_pose(self, road_id: str, s: float, lane_id: int, offset: float = 0.0) -> Pose:
        """Pose at the centre of lane ``lane_id`` (+``offset``, positive to the left) at ``s``.

        The heading is the tangent of that offset lane line towards increasing s (it follows
        width changes); add pi for lanes driven against s (see :meth:`driving_direction`).
        Lane 0 is the centre lane (the reference line shifted by the lane offset).
        """
        k = self._slot(road_id)
        x, y, heading, curvature = self._lines[k].at(s)
        t, slope = self._lane_line(k, road_id, s, lane_id)
        across, rate, rise, forward = self._tilted(k, s, t + offset, slope)
        return Pose(
            x=x - across * math.sin(heading) + forward * math.cos(heading),
            y=y + across * math.cos(heading) + forward * math.sin(heading),
            z=self._elevations[k].value(s) + rise,
            heading=heading + math.atan2(rate, 1.0 - curvature * across),
        )

    def lane_stretch(self, road_id: str, s: float, lane_id: int, offset: float = 0.0) -> float:
        """Metres travelled along the lane line (centre + ``offset``) per metre of s.

        Lanes outside a curve are longer than the reference line (1 - curvature * t), and
        lanes that widen or shift run diagonally; divide a travelled distance by this to get ds.
        """
        k = self._slot(road_id)
        _, _, _, curvature = self._lines[k].at(s)
        t, slope = self._lane_line(k, road_id, s, lane_id)
        # (t across the surface, also on a banked road: esmini scales motion along s so)
        return math.hypot(1.0 - curvature * (t + offset), slope)

    def _lane_line(self, k: int, road_id: str, s: float, lane_id: int) -> tuple[float, float]:
        """Lateral position t of the lane's centre line (lane 0: the lane offset) and dt/ds."""
        layout = self._layouts[k]
        if lane_id == 0:
            return layout.offset(s)
        bounds = layout.lane_bounds(s, lane_id)
        if bounds is None:
            raise ScenarioError(f"road {road_id!r} has no lane {lane_id} at s={s:.2f}")
        return bounds.t_center, bounds.slope_center

    # -- lanes ---------------------------------------------------------------------------------

    def lane_bounds(self, road_id: str, s: float, lane_id: int) -> lanes.LaneBounds | None:
        """Lateral extent of a lane at ``s`` (None if the lane does not exist there)."""
        return self._layouts[self._slot(road_id)].lane_bounds(s, lane_id)

    def lane_width(self, road_id: str, s: float, lane_id: int) -> float:
        bounds = self.lane_bounds(road_id, s, lane_id)
        return bounds.width if bounds is not None else 0.0

    def lanes_at(self, road_id: str, s: float) -> list[lanes.LaneBounds]:
        """All lanes at ``s``, left outermost first."""
        return self._layouts[self._slot(road_id)].all_bounds(s)

    def lane_ids(self, road_id: str, s: float) -> tuple[int, ...]:
        return self._layouts[self._slot(road_id)].section_at(s).section.lane_ids

    def lane_section_index(self, road_id: str, s: float) -> int:
        return self._layouts[self._slot(road_id)].section_index(s)

    def driving_direction(self, road_id: str, lane_id: int) -> int:
        """+1 if traffic in the lane moves towards increasing s, else -1 (RHT: right lanes +1)."""
        forward = lane_id < 0
        if self.road(road_id).rule is models.TrafficRule.LHT:
            forward = not forward
        return 1 if forward else -1

    def next_lanes(
        self, road_id: str, lane_id: int, end: models.ContactPoint
    ) -> tuple[topology.LaneEntry, ...]:
        """Lanes entered when leaving road ``road_id`` through ``end`` in lane ``lane_id``."""
        return self._graph.next_lanes(road_id, lane_id, end)

    def successors(self, road_id: str, lane_id: int) -> tuple[topology.LaneEntry, ...]:
        """Lanes reached by following lane ``lane_id`` in its driving direction past the road."""
        forward = self.driving_direction(road_id, lane_id) > 0
        end = models.ContactPoint.END if forward else models.ContactPoint.START
        return self.next_lanes(road_id, lane_id, end)

    def predecessors(self, road_id: str, lane_id: int) -> tuple[topology.LaneEntry, ...]:
        """Lanes leading into lane ``lane_id`` (against its driving direction)."""
        forward = self.driving_direction(road_id, lane_id) > 0
        end = models.ContactPoint.START if forward else models.ContactPoint.END
        return self.next_lanes(road_id, lane_id, end)

    def advance(
        self,
        road_id: str,
        s: float,
        lane_id: int,
        ds: float,
        *,
        prefer_roads: Collection[str] = (),
        straightest: bool = False,
    ) -> LaneLocation:
        """Move ``ds`` metres of s along the lane (positive: towards increasing s on the start
        road), continuing through lane sections, linked roads and junctions. At a fork the first
        successor whose road is in ``prefer_roads`` is taken, else, with ``straightest``, the one
        that turns least (:meth:`_straightest`), else the first declared one."""
        road = self.road(road_id)
        direction = 1 if ds >= 0 else -1
        remaining = abs(ds)
        layout = self._layouts[self._slot(road_id)]
        for _ in range(10_000):
            section = layout.section_index(s)
            if direction > 0:
                end_s = (
                    layout.sections[section + 1].s
                    if section + 1 < len(layout.sections)
                    else road.length
                )
                room = end_s - s
            else:
                end_s = layout.sections[section].s
                room = s - end_s
            if remaining <= room:
                return LaneLocation(
                    road_id=road.id,
                    s=s + direction * remaining,
                    lane_id=lane_id,
                    direction=direction,
                )
            remaining -= max(room, 0.0)
            inner = section + 1 < len(layout.sections) if direction > 0 else section > 0
            if inner:
                next_lane = self._graph.next_section_lane(road, section, lane_id, direction > 0)
                if next_lane is None:
                    return self._stuck(road.id, end_s, lane_id, direction, remaining)
                lane_id = next_lane
                # Step just past the boundary so section lookup lands in the next section.
                s = end_s if direction > 0 else math.nextafter(end_s, -math.inf)
                continue
            end = models.ContactPoint.END if direction > 0 else models.ContactPoint.START
            entries = self._graph.next_lanes(road.id, lane_id, end)
            if not entries:
                return self._stuck(road.id, end_s, lane_id, direction, remaining)
            entry = self._preferred(entries, prefer_roads)
            if straightest and not prefer_roads and len(entries) > 1:
                entry = self._straightest(entries, road.id, end_s, direction)
            road = self._roads[entry.road_id]
            layout = self._layouts[self._slot(road.id)]
            lane_id = entry.lane_id
            if entry.contact_point is models.ContactPoint.START:
                direction, s = 1, 0.0
            else:
                direction, s = -1, road.length
        raise ScenarioError(f"lane walk from road {road_id!r} does not terminate")

    def walk(
        self,
        road_id: str,
        s: float,
        lane_id: int,
        distance: float,
        *,
        direction: int = 1,
        prefer_roads: Collection[str] = (),
    ) -> Iterator[LaneStretch]:
        """The lane stretches ahead of (road, s, lane) for ``distance`` metres of s travelling
        in ``direction``, through sections, links and junctions as :meth:`advance` goes (the
        route's ``prefer_roads`` first at forks); ends early where the lane ends. What lies
        ahead on a route (stop lines, ...) is looked up stretch by stretch."""
        road = self.road(road_id)
        layout = self._layouts[self._slot(road_id)]
        done = 0.0
        for _ in range(10_000):
            section = layout.section_index(s)
            if direction > 0:
                last = section + 1 >= len(layout.sections)
                end_s = road.length if last else layout.sections[section + 1].s
            else:
                end_s = layout.sections[section].s
            room = max((end_s - s) * direction, 0.0)
            reach = min(room, distance - done)
            yield LaneStretch(
                road_id=road.id,
                lane_id=lane_id,
                s_from=s,
                s_to=s + direction * reach,
                direction=direction,
                start=done,
            )
            done += reach
            if done >= distance:
                return
            inner = section + 1 < len(layout.sections) if direction > 0 else section > 0
            if inner:
                next_lane = self._graph.next_section_lane(road, section, lane_id, direction > 0)
                if next_lane is None:
                    return
                lane_id = next_lane
                s = end_s if direction > 0 else math.nextafter(end_s, -math.inf)
                continue
            end = models.ContactPoint.END if direction > 0 else models.ContactPoint.START
            entries = self._graph.next_lanes(road.id, lane_id, end)
            if not entries:
                return
            entry = self._preferred(entries, prefer_roads)
            road = self._roads[entry.road_id]
            layout = self._layouts[self._slot(road.id)]
            lane_id = entry.lane_id
            if entry.contact_point is models.ContactPoint.START:
                direction, s = 1, 0.0
            else:
                direction, s = -1, road.length

    def _preferred(
        self, entries: Sequence[topology.LaneEntry], prefer_roads: Collection[str]
    ) -> topology.LaneEntry:
        """The successor a route prefers: one on a preferred road, else one whose lane leads on
        to a preferred road (another connecting road of the junction that joins the same two
        roads: an entity in a lane the planned connector does not continue, as after a change
        onto the oncoming lane, still takes the junction towards its route), else the first
        declared one."""
        for entry in entries:
            if entry.road_id in prefer_roads:
                return entry
        if prefer_roads:
            for entry in entries:
                far = (
                    models.ContactPoint.END
                    if entry.contact_point is models.ContactPoint.START
                    else models.ContactPoint.START
                )
                onward = self._graph.next_lanes(entry.road_id, entry.lane_id, far)
                if any(after.road_id in prefer_roads for after in onward):
                    return entry
        return entries[0]

    def _straightest(
        self, entries: Sequence[topology.LaneEntry], road_id: str, s: float, direction: int
    ) -> topology.LaneEntry:
        """The successor whose road leaves in the direction closest to the one the lane arrives
        in (heading at the far end of the entered road against the heading at the end left),
        the first declared on a tie: what an entity without a route takes at a junction.
        esmini picks at random there unless told an angle (``junctionSelectorAngle``, 0 for
        straight on); a reproducible run needs one choice, and straight on is the one its
        unit test scenario of the junction selector and real traffic mostly take."""
        arrive = self.reference_pose(road_id, s).heading + (0.0 if direction > 0 else math.pi)

        def turn(entry: topology.LaneEntry) -> float:
            length = self.road_length(entry.road_id)
            forward = entry.contact_point is models.ContactPoint.START
            far = self.reference_pose(entry.road_id, length if forward else 0.0).heading
            leave = far + (0.0 if forward else math.pi)
            return abs(math.remainder(leave - arrive, math.tau))

        best = min(turn(entry) for entry in entries)
        return next(entry for entry in entries if turn(entry) <= best + 1e-6)

    @staticmethod
    def _stuck(
        road_id: str, s: float, lane_id: int, direction: int, remaining: float
    ) -> LaneLocation:
        return LaneLocation(
            road_id=road_id, s=s, lane_id=lane_id, direction=direction, remaining=remaining
        )

    # -- projection ----------------------------------------------------------------------------

    def _search_index(self) -> projection.RoadIndex:
        if self._index is None:
            self._index = projection.RoadIndex(self._lines, self._layouts, self._rolls)
        return self._index

    def to_road(
        self,
        x: float,
        y: float,
        hint: str | RoadCoord | None = None,
        *,
        heading: float | None = None,
    ) -> RoadCoord | None:
        """Road coordinates of the world point (None only for a network without roads).

        ``hint`` (the road, or last coordinates, of a tracked entity) keeps the answer on that
        road while the point is on it, which is both faster and stable where roads overlap;
        ``heading`` prefers roads aligned with it (either direction) among overlapping roads.
        """
        index = self._search_index()
        hint_road = hint.road_id if isinstance(hint, RoadCoord) else hint
        if hint_road is not None and hint_road in self._index_of:
            k = self._index_of[hint_road]
            if index.may_contain(k, x, y):
                start = hint.s if isinstance(hint, RoadCoord) else index.nearest_s(k, x, y)
                found = index.refine(k, x, y, start)
                line_length = self._lines[k].length
                if found.outside <= 0.0 and 0.0 < found.s < line_length:
                    return self._coord(found)
        results = [index.refine(k, x, y, s) for k, s in index.candidates(x, y)]
        if not results:
            return None
        best_outside = min(result.outside for result in results)
        close = [
            (result, self._coord(result))
            for result in results
            if result.outside <= best_outside + 1e-6
        ]
        return min(close, key=lambda pair: self._rank(pair[0], pair[1], hint_road, heading))[1]

    def _rank(
        self,
        result: projection.Projection,
        coord: RoadCoord,
        hint_road: str | None,
        heading: float | None,
    ) -> tuple[float, bool, float, float]:
        """Order among roads the point is equally on: the hinted road, then roads connected to
        it, then drivable lanes, then alignment with ``heading``, then closeness to the centre."""
        related = 0.0
        if hint_road is not None and coord.road_id != hint_road:
            related = 0.5 if coord.road_id in self._graph.connected_roads(hint_road) else 1.0
        misalignment = 0.0
        if heading is not None:
            misalignment = abs(math.remainder(heading - result.heading, math.pi))
        drivable = coord.lane_type in DRIVABLE_LANE_TYPES
        return (related, not drivable, misalignment, abs(result.t))

    def _coord(self, found: projection.Projection) -> RoadCoord:
        road_id = self._order[found.road_index]
        layout = self._layouts[found.road_index]
        lane = layout.lane_at(found.s, found.t)
        if lane is None:
            candidates = [bounds for bounds in layout.all_bounds(found.s) if bounds.width > 0]
            lane = min(
                candidates,
                key=lambda bounds: min(abs(found.t - bounds.t_min), abs(found.t - bounds.t_max)),
                default=None,
            )
        return RoadCoord(
            road_id=road_id,
            s=found.s,
            t=found.t,
            lane_id=lane.lane_id if lane is not None else 0,
            heading_of_road=found.heading,
            lane_type=lane.type if lane is not None else "none",
            distance=found.outside,
        )

    def is_on_road(
        self, x: float, y: float, hint: str | RoadCoord | None = None, *, drivable_only: bool = True
    ) -> bool:
        """Whether the point lies on a road surface (by default: on a drivable lane)."""
        coord = self.to_road(x, y, hint)
        if coord is None or not coord.on_road:
            return False
        return not drivable_only or coord.lane_type in DRIVABLE_LANE_TYPES
