"""ScenarioRunner's lane and road criteria, followed tick by tick as ScenarioRunner follows them.

ScenarioRunner (``srunner/scenariomanager/scenarioatomics/atomic_criteria.py``) judges these
five tests on CARLA waypoints at every tick; :class:`LaneWatch` replays the same rules on the
stand-in's OpenDRIVE projection (docs/simulator.md, "ScenarioRunner audit"):

- ``KeepLaneTest`` is CARLA's lane-invasion sensor: a corner of the vehicle's box that crossed,
  since the previous tick, from one lane into another of the same road and lane section, or
  between a lane and the road's edge, outside junctions (CARLA's ``LaneCrossingCalculator``);
- ``WrongLaneTest``: on a change of (road, lane) outside a junction, the lane's direction turned
  by more than 150 deg from the previous lane's; right after a junction, the vehicle's heading is
  more than 120 deg off the new lane's direction;
- ``OnSidewalkTest``: the time spent with the centre on a sidewalk, or outside every lane (not
  saved by a corner on a driving lane), exceeds ``duration``;
- ``OffRoadTest``: the time spent with the centre on no driving or parking lane exceeds
  ``duration``;
- ``EndofRoadTest``: the vehicle left the road it started on and ``duration`` more seconds passed.

Times accumulate as ScenarioRunner's do: the first tick of a stretch only starts the clock, so
a single tick outside never fails a test with ``duration`` 0.
"""

from __future__ import annotations

import dataclasses
import math

from simtest_operator import geometry
from simtest_operator.opendrive import RoadCoord, RoadNetwork
from simtest_operator.snapshots import EntityState

WRONG_LANE_TURN = math.radians(150.0)
"""ScenarioRunner's ``MAX_WAYPOINT_ANGLE``: a lane-direction change beyond it is a wrong lane."""
WRONG_LANE_HEADING = math.radians(120.0)
"""ScenarioRunner's ``MAX_ALLOWED_ANGLE``: after a junction, heading this far off the lane."""
_ALLOWED = frozenset({"driving", "parking"})
"""Lane types ScenarioRunner's off-road and sidewalk tests accept (CARLA Driving, Parking)."""

_MARKED = frozenset({"driving", "bidirectional", "biking", "parking"})
"""Lane types CARLA's lane-crossing calculator finds road marks between (its ``FLAGS``)."""

_Corner = tuple[str, int, int | None]
"""Where a box corner is: road, lane section, lane id (None: off those lanes)."""


@dataclasses.dataclass(slots=True)
class _Clock:
    """Time spent in a state, counted as ScenarioRunner counts it (``_prev_time``)."""

    since: float | None = None
    total: float = 0.0

    def tick(self, time: float, active: bool) -> None:
        if not active:
            self.since = None
        elif self.since is None:
            self.since = time
        else:
            self.total += time - self.since
            self.since = time


class LaneWatch:
    """Follows the ego over the road network for ScenarioRunner's lane and road criteria."""

    __slots__ = (
        "_corners",
        "_durations",
        "_end_of_road",
        "_failures",
        "_in_lane",
        "_lane",
        "_left_road_at",
        "_off_road",
        "_roads",
        "_sidewalk",
        "_start_road",
    )

    def __init__(self, roads: RoadNetwork, durations: dict[str, float]) -> None:
        self._roads = roads
        self._durations = durations
        """Watched tests and their ``duration`` (0 for tests without one)."""
        self._failures: dict[str, tuple[float, str]] = {}
        self._corners: tuple[_Corner | None, ...] | None = None
        self._lane: tuple[RoadCoord, float] | None = None
        """Last driving lane under the ego and that lane's travel direction."""
        self._in_lane = True
        self._off_road = _Clock()
        self._sidewalk = _Clock()
        self._start_road: str | None = None
        self._left_road_at: float | None = None
        self._end_of_road = False

    def failure(self, name: str) -> tuple[float, str] | None:
        """When and how test ``name`` failed, or None."""
        return self._failures.get(name)

    def observe(self, time: float, ego: EntityState) -> None:
        coord = self._roads.to_road(
            ego.x, ego.y, self._lane[0] if self._lane else None, heading=ego.heading
        )
        if "KeepLaneTest" in self._durations:
            self._keep_lane(time, ego, coord)
        if "WrongLaneTest" in self._durations and coord is not None:
            self._wrong_lane(time, ego, coord)
        if "OffRoadTest" in self._durations:
            allowed = coord is not None and coord.on_road and coord.lane_type in _ALLOWED
            self._timed("OffRoadTest", self._off_road, time, not allowed, ego, "off the road")
        if "OnSidewalkTest" in self._durations:
            where = self._outside_lanes(ego, coord)
            self._timed("OnSidewalkTest", self._sidewalk, time, where is not None, ego, where or "")
        if "EndofRoadTest" in self._durations and coord is not None:
            self._end_road(time, ego, coord)

    def _fail(self, name: str, time: float, detail: str) -> None:
        self._failures.setdefault(name, (time, f"{detail} at t={time:.2f} s"))

    def _timed(
        self, name: str, clock: _Clock, time: float, active: bool, ego: EntityState, what: str
    ) -> None:
        clock.tick(time, active)
        duration = self._durations[name]
        if clock.total > duration:
            self._fail(name, time, f"{ego.name} {what} for {clock.total:.2f} s > {duration:g} s")

    # --- KeepLaneTest: CARLA's lane-invasion sensor ------------------------------------------

    def _corner(self, x: float, y: float, hint: RoadCoord | None) -> _Corner | None:
        coord = self._roads.to_road(x, y, hint)
        if coord is None:
            return None
        section = self._roads.lane_section_index(coord.road_id, coord.s)
        on_lane = coord.on_road and coord.lane_type in _MARKED
        return coord.road_id, section, coord.lane_id if on_lane else None

    def _keep_lane(self, time: float, ego: EntityState, coord: RoadCoord | None) -> None:
        corners = tuple(self._corner(x, y, coord) for x, y in geometry.box_corners(ego))
        previous, self._corners = self._corners, corners
        if previous is None:
            return
        for before, now in zip(previous, corners, strict=True):
            if before is None or now is None or before == now or before[:2] != now[:2]:
                continue  # another road or lane section: CARLA's calculator reports nothing
            if self._roads.road(now[0]).in_junction:
                continue
            self._fail(
                "KeepLaneTest",
                time,
                f"{ego.name} crossed from {_lane_name(before[2])} into {_lane_name(now[2])} "
                f"of road {now[0]}",
            )
            return

    # --- WrongLaneTest -------------------------------------------------------------------------

    def _travel(self, coord: RoadCoord) -> float:
        heading = coord.heading_of_road
        if self._roads.driving_direction(coord.road_id, coord.lane_id) < 0:
            heading += math.pi
        return heading

    def _wrong_lane(self, time: float, ego: EntityState, coord: RoadCoord) -> None:
        if coord.lane_id == 0 or coord.lane_type != "driving":
            return  # CARLA projects to the nearest driving lane: keep the last one
        travel = self._travel(coord)
        last, self._lane = self._lane, (coord, travel)
        if last is None:
            return
        before, before_travel = last
        if (before.road_id, before.lane_id) == (coord.road_id, coord.lane_id):
            return
        if self._roads.road(coord.road_id).in_junction:
            return
        turn = abs(math.remainder(travel - before_travel, math.tau))
        if turn > WRONG_LANE_TURN and self._in_lane:
            self._in_lane = False
            self._fail(
                "WrongLaneTest",
                time,
                f"{ego.name} entered lane {coord.lane_id} of road {coord.road_id} against its "
                "traffic",
            )
        else:
            self._in_lane = True
        if self._roads.road(before.road_id).in_junction:
            off = abs(math.remainder(ego.heading - travel, math.tau))
            if off > WRONG_LANE_HEADING:
                self._in_lane = False
                self._fail(
                    "WrongLaneTest",
                    time,
                    f"{ego.name} left a junction into lane {coord.lane_id} of road "
                    f"{coord.road_id} against its traffic",
                )

    # --- OnSidewalkTest ------------------------------------------------------------------------

    def _outside_lanes(self, ego: EntityState, coord: RoadCoord | None) -> str | None:
        """``on a sidewalk`` / ``outside the lanes`` as ScenarioRunner classifies the ego, or
        None while it is inside the driving lanes."""
        if coord is not None and coord.on_road:
            if coord.lane_type == "sidewalk":
                return "on a sidewalk"
            if coord.lane_type in _ALLOWED:
                return None
        types = []
        for x, y in geometry.box_corners(ego):
            corner = self._roads.to_road(x, y, coord)
            types.append(corner.lane_type if corner is not None and corner.on_road else "none")
        if "driving" in types:
            return None
        if "sidewalk" in types:
            return "on a sidewalk"
        if coord is None or not coord.on_road:
            return "outside the lanes"
        return None  # inside a shoulder or border lane

    # --- EndofRoadTest -------------------------------------------------------------------------

    def _end_road(self, time: float, ego: EntityState, coord: RoadCoord) -> None:
        if self._start_road is None:
            self._start_road = coord.road_id
            return
        if self._left_road_at is None:
            if coord.road_id != self._start_road:
                self._left_road_at = time
            return
        duration = self._durations["EndofRoadTest"]
        if time - self._left_road_at > duration:
            self._fail(
                "EndofRoadTest",
                time,
                f"{ego.name} left road {self._start_road} at t={self._left_road_at:.2f} s",
            )


def _lane_name(lane: int | None) -> str:
    return "the road's edge" if lane is None else f"lane {lane}"
