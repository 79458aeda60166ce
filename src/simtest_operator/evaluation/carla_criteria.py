"""CARLA ScenarioRunner's test criteria, judged online over the run.

A file written for ScenarioRunner declares its pass/fail tests as ``criteria_<Test>`` conditions
in the storyboard's StopTrigger (the reader turns them into :class:`~.model.Criterion`). Each
maps to a check of the ego over every snapshot, in the stand-in's own terms:

============================  ====================================================================
ScenarioRunner criterion      Judged here as
============================  ====================================================================
``CollisionTest``             the ego's bounding box touched another entity's (as ``collision``)
``KeepLaneTest``              a corner of the ego's box lay in another lane of the ego's road
                              (CARLA: a lane-invasion event)
``WrongLaneTest``             the ego moved against the travel direction of the driving lane it
                              is on (by the road's rule; RHT: negative lane ids run along +s)
``OnSidewalkTest``            the ego's reference point was on a ``sidewalk`` lane
``DrivenDistanceTest``        the ego drove at least ``distance_success`` metres by the end
                              (``distance_acceptable``, if given, also passes)
``RunningRedLightTest``      the ego passed a traffic light's stop line while the scenario had set
                              that light red (not evaluated when it crossed a light whose state
                              the scenario never set: CARLA's own cycle is not modelled)
``RunningStopTest``           the ego passed a stop sign's stop line without standing still within
                              the stop's reach (see :mod:`.signal_criteria`)
============================  ====================================================================

An unknown criterion is listed as not evaluated (the reader reported it as a deviation).
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Sequence

from simtest_operator import geometry
from simtest_operator.evaluation.signal_criteria import Finding, SignalWatch
from simtest_operator.opendrive import RoadCoord, RoadNetwork, traffic_controls
from simtest_operator.openscenario import model
from simtest_operator.snapshots import EntityState

_LANE_CHECKS = frozenset({"KeepLaneTest", "WrongLaneTest", "OnSidewalkTest"})
_SIGNAL_CHECKS = frozenset({"RunningRedLightTest", "RunningStopTest"})
_MOVING = 0.1
"""m/s below which the ego is not driving in any direction (WrongLaneTest)."""


class Status(enum.StrEnum):
    """Outcome of one criterion."""

    PASSED = "passed"
    FAILED = "failed"
    NOT_EVALUATED = "not evaluated"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Outcome:
    """How one ScenarioRunner criterion ended."""

    name: str
    status: Status
    detail: str = ""
    time: float | None = None
    """When it failed (simulated seconds), for failures during the run."""

    def describe(self) -> str:
        """``KeepLaneTest failed (hero left lane -1 ... at t=3.20 s)``."""
        return f"{self.name} {self.status}" + (f" ({self.detail})" if self.detail else "")


@dataclasses.dataclass(slots=True)
class _Failure:
    time: float
    detail: str


class ScenarioCriteria:
    """The ScenarioRunner criteria of one scenario, observed on every snapshot of the ego."""

    __slots__ = ("_criteria", "_distance", "_failures", "_hint", "_last", "_roads", "_signals")

    def __init__(self, criteria: Sequence[model.Criterion], *, roads: RoadNetwork | None) -> None:
        self._criteria = tuple(criteria)
        self._roads = roads
        self._failures: dict[str, _Failure] = {}
        self._distance = 0.0
        self._last: tuple[float, float] | None = None
        self._hint: RoadCoord | None = None
        self._signals = (
            SignalWatch(traffic_controls(roads))
            if roads is not None and _SIGNAL_CHECKS.intersection(self.names)
            else None
        )

    @classmethod
    def of(cls, scenario: model.Scenario, *, roads: RoadNetwork | None) -> ScenarioCriteria | None:
        """The criteria of ``scenario``'s storyboard StopTrigger, or None when it has none."""
        stop = scenario.storyboard.stop_trigger
        if stop is None or not stop.criteria:
            return None
        return cls(stop.criteria, roads=roads)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.test for c in self._criteria)

    @property
    def driven_distance(self) -> float:
        """Metres the ego's reference point travelled so far."""
        return self._distance

    def observe(
        self, time: float, ego: EntityState | None, signals: Sequence[tuple[str, str]] = ()
    ) -> None:
        """Update with the ego as it is at ``time`` (None: the ego is not in the world) and the
        traffic signal states set so far (``(name, state)``)."""
        if self._signals is not None:
            self._signals.observe(time, ego, signals)
        if ego is None:
            self._last = None
            return
        if self._last is not None:
            self._distance += math.hypot(ego.x - self._last[0], ego.y - self._last[1])
        self._last = (ego.x, ego.y)
        if self._roads is None or not _LANE_CHECKS.intersection(self.names):
            return
        coord = self._roads.to_road(ego.x, ego.y, self._hint, heading=ego.heading)
        if coord is None or not coord.on_road:
            self._hint = None
            return
        self._hint = coord
        if "OnSidewalkTest" in self.names and coord.lane_type == "sidewalk":
            self._fail("OnSidewalkTest", time, f"{ego.name} on a sidewalk of road {coord.road_id}")
        if "WrongLaneTest" in self.names and self._against_traffic(ego, coord):
            self._fail(
                "WrongLaneTest",
                time,
                f"{ego.name} against the traffic of lane {coord.lane_id} of road {coord.road_id}",
            )
        if "KeepLaneTest" in self.names:
            invaded = self._invaded_lane(ego, coord)
            if invaded is not None:
                self._fail(
                    "KeepLaneTest",
                    time,
                    f"{ego.name} crossed from lane {coord.lane_id} into lane {invaded} of road "
                    f"{coord.road_id}",
                )

    def _invaded_lane(self, ego: EntityState, coord: RoadCoord) -> int | None:
        """The other lane of the same road and lane section a box corner lies in (lanes are
        renumbered across sections, and junction roads overlap: both are not invasions)."""
        roads = self._roads
        assert roads is not None
        section = roads.lane_section_index(coord.road_id, coord.s)
        for x, y in geometry.box_corners(ego):
            corner = roads.to_road(x, y, coord, heading=ego.heading)
            if (
                corner is not None
                and corner.on_road
                and corner.road_id == coord.road_id
                and corner.lane_id != coord.lane_id
                and roads.lane_section_index(corner.road_id, corner.s) == section
            ):
                return corner.lane_id
        return None

    def _against_traffic(self, ego: EntityState, coord: RoadCoord) -> bool:
        assert self._roads is not None
        if coord.lane_id == 0 or coord.lane_type != "driving" or ego.speed < _MOVING:
            return False
        travel = coord.heading_of_road
        if self._roads.driving_direction(coord.road_id, coord.lane_id) < 0:
            travel += math.pi
        return math.cos(ego.heading - travel) < 0.0

    def _fail(self, name: str, time: float, detail: str) -> None:
        if name not in self._failures:
            self._failures[name] = _Failure(time=time, detail=f"{detail} at t={time:.2f} s")

    def outcomes(
        self, *, ego: str | None, collided_with: Sequence[tuple[str, float]]
    ) -> tuple[Outcome, ...]:
        """Every criterion's outcome at the end of the run (``collided_with``: the ego's
        collisions, other entity and first time)."""
        return tuple(self._outcome(c, ego, collided_with) for c in self._criteria)

    def _outcome(
        self,
        criterion: model.Criterion,
        ego: str | None,
        collided_with: Sequence[tuple[str, float]],
    ) -> Outcome:
        name = criterion.test
        if not criterion.known:
            return Outcome(name=name, status=Status.NOT_EVALUATED, detail="unknown criterion")
        if ego is None:
            return Outcome(name=name, status=Status.NOT_EVALUATED, detail="the scenario has no ego")
        if name == "CollisionTest":
            if collided_with:
                other, time = collided_with[0]
                detail = f"{ego} collided with {other} at t={time:.2f} s"
                return Outcome(name=name, status=Status.FAILED, detail=detail, time=time)
            return Outcome(name=name, status=Status.PASSED)
        if name == "DrivenDistanceTest":
            return self._driven(criterion)
        if self._roads is None:
            return Outcome(name=name, status=Status.NOT_EVALUATED, detail="no road network")
        if self._signals is not None and name in _SIGNAL_CHECKS:
            found = (
                self._signals.red_light()
                if name == "RunningRedLightTest"
                else self._signals.stop_sign()
            )
            return _from_finding(name, found)
        failure = self._failures.get(name)
        if failure is not None:
            return Outcome(
                name=name, status=Status.FAILED, detail=failure.detail, time=failure.time
            )
        return Outcome(name=name, status=Status.PASSED)

    def _driven(self, criterion: model.Criterion) -> Outcome:
        name = criterion.test
        success = _number(criterion.argument("distance_success"))
        if success is None:
            return Outcome(
                name=name, status=Status.NOT_EVALUATED, detail="no numeric distance_success given"
            )
        acceptable = _number(criterion.argument("distance_acceptable"))
        driven = self._distance
        if driven >= success:
            return Outcome(
                name=name, status=Status.PASSED, detail=f"{driven:.1f} m >= {success:g} m"
            )
        if acceptable is not None and driven >= acceptable:
            detail = f"{driven:.1f} m >= acceptable {acceptable:g} m"
            return Outcome(name=name, status=Status.PASSED, detail=detail)
        return Outcome(name=name, status=Status.FAILED, detail=f"{driven:.1f} m < {success:g} m")


def _from_finding(name: str, found: Finding) -> Outcome:
    status = {True: Status.PASSED, False: Status.FAILED, None: Status.NOT_EVALUATED}[found.passed]
    return Outcome(name=name, status=status, detail=found.detail, time=found.time)


def _number(text: str | None) -> float | None:
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None
