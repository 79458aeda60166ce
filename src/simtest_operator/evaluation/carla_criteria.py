"""CARLA ScenarioRunner's test criteria, judged as ScenarioRunner judges them.

A file written for ScenarioRunner declares its pass/fail tests as ``criteria_<Test>`` conditions
in a StopTrigger (the reader turns them into :class:`~.model.Criterion`). ScenarioRunner builds
each as ``<Test>(ego, value)`` -- the ParameterCondition's ``value`` is the test's *second
positional argument*, whatever ``parameterRef`` says -- or ``<Test>(ego)`` when ``parameterRef``
is empty (``srunner/tools/openscenario_parser.py``, ``convert_condition_to_atomic``). So the value
is a distance for ``DrivenDistanceTest`` but the ``optional`` flag for ``KeepLaneTest``.
A run fails on every non-optional criterion that did not end in success
(``ScenarioManager.analyze_scenario``); docs/simulator.md, "ScenarioRunner audit", lists each
test with where ScenarioRunner decides it:

============================  ====================================================================
ScenarioRunner criterion      Judged here as
============================  ====================================================================
``CollisionTest``             the ego's bounding box touched another entity's while the ego moved
``KeepLaneTest``              CARLA's lane-invasion sensor (:mod:`.lane_criteria`)
``WrongLaneTest``             a lane change against the traffic (:mod:`.lane_criteria`)
``OnSidewalkTest``            time on a sidewalk or outside the lanes > ``duration``
``OffRoadTest``               time off the driving and parking lanes > ``duration``
``EndofRoadTest``             left the start road ``duration`` seconds ago
``DrivenDistanceTest``        the ego drove more than ``distance`` metres by the end
``AverageVelocityTest``       driven distance / run time > ``velocity`` at the end
``MaxVelocityTest``           the ego's speed at the last tick <= ``max_velocity``
``RunningRedLightTest``      the ego passed a traffic light's stop line while the scenario had set
                              that light red (not evaluated when it crossed a light whose state
                              the scenario never set: CARLA's own cycle is not modelled)
``RunningStopTest``           the ego passed a stop sign's stop line without standing still within
                              the stop's reach (see :mod:`.signal_criteria`)
============================  ====================================================================

A criterion ScenarioRunner cannot build from that call (an unknown or differently spelled name, a
test that needs more arguments, a missing or non-numeric value) makes ScenarioRunner refuse the
whole file ("The scenario cannot be loaded", ``scenario_runner.py``):
:attr:`ScenarioCriteria.refusal` says why, and the runner reports the run ``Invalid`` unrun.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Sequence

from simtest_operator.evaluation.lane_criteria import LaneWatch
from simtest_operator.evaluation.signal_criteria import Finding, SignalWatch
from simtest_operator.opendrive import RoadNetwork, traffic_controls
from simtest_operator.openscenario import model
from simtest_operator.snapshots import EntityState

_SECOND_ARGUMENT = {
    "CollisionTest": "other_actor",
    "KeepLaneTest": "optional",
    "WrongLaneTest": "optional",
    "OnSidewalkTest": "duration",
    "OffRoadTest": "duration",
    "EndofRoadTest": "duration",
    "DrivenDistanceTest": "distance",
    "AverageVelocityTest": "velocity",
    "MaxVelocityTest": "max_velocity",
    "RunningRedLightTest": "name",
    "RunningStopTest": "name",
}
"""The second positional parameter of each test's constructor in ScenarioRunner's
``atomic_criteria.py``: where the criterion's value lands."""
_REQUIRED = frozenset({"DrivenDistanceTest", "AverageVelocityTest", "MaxVelocityTest"})
"""Tests ScenarioRunner cannot build without a value (``parameterRef=""``)."""
_LANE_CHECKS = frozenset(
    {"KeepLaneTest", "WrongLaneTest", "OnSidewalkTest", "OffRoadTest", "EndofRoadTest"}
)
_SIGNAL_CHECKS = frozenset({"RunningRedLightTest", "RunningStopTest"})
_AT_FAULT = 0.1
"""m/s: CollisionTest ignores a collision taken while the ego was slower (its ``EPSILON``: the
collision is not the ego's fault)."""


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
    optional: bool = False
    """ScenarioRunner's ``optional``: reported, but not part of the verdict."""

    @property
    def decisive(self) -> bool:
        """Whether this outcome fails the run (a failed criterion that is not optional)."""
        return self.status is Status.FAILED and not self.optional

    def describe(self) -> str:
        """``KeepLaneTest failed (hero left lane -1 ... at t=3.20 s)``."""
        detail = "; ".join(part for part in (self.detail, "optional" * self.optional) if part)
        return f"{self.name} {self.status}" + (f" ({detail})" if detail else "")


@dataclasses.dataclass(frozen=True, slots=True)
class _Built:
    """A criterion as ScenarioRunner builds it: its value, or why it cannot be judged."""

    value: float | None
    problem: str = ""
    refused: bool = True
    """With a problem: ScenarioRunner raises while building it (it refuses the file); else it
    builds a test the stand-in cannot judge."""


def _build(criterion: model.Criterion) -> _Built:
    """The value ScenarioRunner passes as the test's second argument (None: called with the ego
    only), or the reason the call fails."""
    name = criterion.test
    if not criterion.known:
        return _Built(None, "ScenarioRunner has no such test")
    if not criterion.arguments:
        if name in _REQUIRED:
            return _Built(None, f"ScenarioRunner needs a value ({_SECOND_ARGUMENT[name]})")
        return _Built(None)
    text = criterion.arguments[0][1].strip()
    if not text:
        return _Built(0.0)
    try:
        value = float(text)  # as ScenarioRunner reads it: "inf" and "nan" build too
    except ValueError:
        return _Built(None, f"value {text!r} is not a number")
    if name == "CollisionTest" and value != 0.0:
        return _Built(
            None, "ScenarioRunner reads a non-zero value as the other actor", refused=False
        )
    return _Built(value)


class ScenarioCriteria:
    """The ScenarioRunner criteria of one scenario, observed on every snapshot of the ego."""

    __slots__ = (
        "_built",
        "_criteria",
        "_distance",
        "_lanes",
        "_last",
        "_roads",
        "_signals",
        "_speed",
        "_speeds",
        "_time",
    )

    def __init__(self, criteria: Sequence[model.Criterion], *, roads: RoadNetwork | None) -> None:
        self._criteria = tuple(criteria)
        self._built = tuple(_build(c) for c in self._criteria)
        self._roads = roads
        self._distance = 0.0
        self._last: tuple[float, float] | None = None
        self._speed: float | None = None
        self._speeds: dict[float, float] = {}
        """The ego's speed at each snapshot time, when CollisionTest needs it."""
        self._time = 0.0
        self._signals = (
            SignalWatch(traffic_controls(roads))
            if roads is not None and _SIGNAL_CHECKS.intersection(self.names)
            else None
        )
        durations = {
            c.test: (b.value or 0.0) if _SECOND_ARGUMENT.get(c.test) == "duration" else 0.0
            for c, b in zip(self._criteria, self._built, strict=True)
            if c.test in _LANE_CHECKS and not b.problem
        }
        self._lanes = LaneWatch(roads, durations) if roads is not None and durations else None

    @classmethod
    def of(cls, scenario: model.Scenario, *, roads: RoadNetwork | None) -> ScenarioCriteria | None:
        """The criteria of ``scenario``'s StopTriggers, or None when it has none."""
        criteria = scenario.criteria
        if not criteria:
            return None
        return cls(criteria, roads=roads)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.test for c in self._criteria)

    @property
    def ends_run(self) -> bool:
        """Whether ScenarioRunner would stop the run now: a failed EndofRoadTest. Its ``update``
        returns ``SUCCESS`` on failure (every other criterion it builds for a file returns
        ``RUNNING``: ``terminate_on_failure`` stays off), which ends its criteria group
        (``OpenScenario._create_test_criteria``: a ``SUCCESS_ON_ONE`` parallel) and with it the
        scenario tree (``SUCCESS_ON_ONE`` over behaviour, timeout and criteria)."""
        return (
            self._lanes is not None
            and "EndofRoadTest" in self.names
            and self._lanes.failure("EndofRoadTest") is not None
        )

    @property
    def refusal(self) -> str | None:
        """Why ScenarioRunner refuses to load the file (a test it cannot build: it raises while
        building its criteria, ``OpenScenarioParser.convert_condition_to_atomic``), or None."""
        for criterion, built in zip(self._criteria, self._built, strict=True):
            if built.problem and built.refused:
                where = f" (line {criterion.line})" if criterion.line is not None else ""
                return (
                    f"ScenarioRunner cannot load the file: criteria_{criterion.test}{where}: "
                    f"{built.problem}"
                )
        return None

    @property
    def driven_distance(self) -> float:
        """Metres the ego's reference point travelled so far."""
        return self._distance

    def observe(
        self, time: float, ego: EntityState | None, signals: Sequence[tuple[str, str]] = ()
    ) -> None:
        """Update with the ego as it is at ``time`` (None: the ego is not in the world) and the
        traffic signal states set so far (``(name, state)``)."""
        self._time = time
        if self._signals is not None:
            self._signals.observe(time, ego, signals)
        if ego is None:
            self._last = None
            return
        if self._last is not None:
            self._distance += math.hypot(ego.x - self._last[0], ego.y - self._last[1])
        self._last = (ego.x, ego.y)
        self._speed = ego.speed
        if "CollisionTest" in self.names:
            self._speeds[time] = ego.speed
        if self._lanes is not None:
            self._lanes.observe(time, ego)

    def outcomes(
        self, *, ego: str | None, collided_with: Sequence[tuple[str, float]]
    ) -> tuple[Outcome, ...]:
        """Every criterion's outcome at the end of the run (``collided_with``: the ego's
        collisions, other entity and first time)."""
        return tuple(
            self._outcome(c, b, ego, collided_with)
            for c, b in zip(self._criteria, self._built, strict=True)
        )

    def _outcome(
        self,
        criterion: model.Criterion,
        built: _Built,
        ego: str | None,
        collided_with: Sequence[tuple[str, float]],
    ) -> Outcome:
        name = criterion.test
        if built.problem:
            return Outcome(name=name, status=Status.NOT_EVALUATED, detail=built.problem)
        if ego is None:
            return Outcome(name=name, status=Status.NOT_EVALUATED, detail="the scenario has no ego")
        optional = _SECOND_ARGUMENT.get(name) == "optional" and bool(built.value)
        outcome = self._judge(name, built.value, ego, collided_with)
        return dataclasses.replace(outcome, optional=optional) if optional else outcome

    def _judge(
        self,
        name: str,
        value: float | None,
        ego: str,
        collided_with: Sequence[tuple[str, float]],
    ) -> Outcome:
        if name == "CollisionTest":
            for other, time in collided_with:
                if self._speeds.get(time, _AT_FAULT) < _AT_FAULT:
                    continue  # hit while (nearly) standing: not counted by ScenarioRunner
                detail = f"{ego} collided with {other} at t={time:.2f} s"
                return Outcome(name=name, status=Status.FAILED, detail=detail, time=time)
            if collided_with:
                detail = f"hit by {collided_with[0][0]} while standing (not the ego's fault)"
                return Outcome(name=name, status=Status.PASSED, detail=detail)
            return Outcome(name=name, status=Status.PASSED)
        if value is not None and name in _REQUIRED:
            return self._threshold(name, value)
        if self._roads is None:
            return Outcome(name=name, status=Status.NOT_EVALUATED, detail="no road network")
        if self._signals is not None and name in _SIGNAL_CHECKS:
            found = (
                self._signals.red_light()
                if name == "RunningRedLightTest"
                else self._signals.stop_sign()
            )
            return _from_finding(name, found)
        failure = self._lanes.failure(name) if self._lanes is not None else None
        if failure is not None:
            time, detail = failure
            return Outcome(name=name, status=Status.FAILED, detail=detail, time=time)
        return Outcome(name=name, status=Status.PASSED)

    def _threshold(self, name: str, value: float) -> Outcome:
        """The tests ScenarioRunner decides at the last tick: its comparisons are strict."""
        if name == "MaxVelocityTest":
            speed = self._speed or 0.0
            passed = not speed > value  # ScenarioRunner fails only on ``>`` (a NaN passes)
            detail = f"{speed:.2f} m/s at the end {'<=' if passed else '>'} {value:g} m/s"
        elif name == "AverageVelocityTest":
            speed = self._distance / self._time if self._time > 0.0 else 0.0
            passed = speed > value
            detail = f"average {speed:.2f} m/s {'>' if passed else '<='} {value:g} m/s"
        else:
            passed = self._distance > value
            detail = f"{self._distance:.1f} m {'>' if passed else '<='} {value:g} m"
        return Outcome(name=name, status=Status.PASSED if passed else Status.FAILED, detail=detail)


def _from_finding(name: str, found: Finding) -> Outcome:
    status = {True: Status.PASSED, False: Status.FAILED, None: Status.NOT_EVALUATED}[found.passed]
    return Outcome(name=name, status=status, detail=found.detail, time=found.time)
