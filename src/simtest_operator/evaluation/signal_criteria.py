"""RunningRedLightTest and RunningStopTest: the ego's path against the map's stop lines.

What ScenarioRunner checks, in the stand-in's terms (the stop lines come from the map's signals,
see :mod:`simtest_operator.opendrive.signals`):

- **RunningRedLightTest** fails when a point 1 m behind the ego's centre (ScenarioRunner tests the
  stretch 1 to 4 m behind the vehicle, so a nose over the line is no infraction) passes a traffic
  light's stop line in the lane's travel direction while that light is red. Light states are
  those the scenario sets (``TrafficSignalStateAction``, ``name`` the OpenDRIVE signal id,
  ScenarioRunner's ``id=<id>``, or ScenarioRunner's ``pos=x,y``: the light standing within 2 m
  of that point in CARLA's frame, y negated). ``red`` (any case), or esmini's lamp list with the
  first (red) lamp ``on``, is red. CARLA cycles a light the scenario leaves alone on its own
  timing, which depends on how long the world has run: a crossing of such a light is not judged,
  and the test is "not evaluated: no light states known" unless another crossing failed it.
- **RunningStopTest** fails when the ego's centre passes a stop sign's stop line without having
  stood still (speed < 0.1 m/s, ScenarioRunner's threshold) within the stop's reach: the 20 m
  ScenarioRunner looks ahead of the ego plus CARLA's stop box (90 % of the lane width) before
  the line.

A map without traffic lights (stop signs) passes the respective test, as in ScenarioRunner.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

from simtest_operator import opendrive
from simtest_operator.opendrive import Control, TrafficControl
from simtest_operator.snapshots import EntityState

STANDSTILL = 0.1
"""m/s below which the ego stands still (ScenarioRunner's RunningStopTest)."""
STOP_LOOKAHEAD = 20.0
"""Metres before a stop box where the stop already applies (ScenarioRunner: 20 waypoints 1 m
apart ahead of the ego)."""
STOP_BOX_SHARE = 0.9
"""CARLA's stop box is as long as 90 % of the lane width, ending at the stop line."""
TAIL = 1.0
"""Metres behind the ego's centre of the point that must not pass a red light's line."""
SAME_APPROACH = 10.0
"""Metres within which the lines of one signal count as one crossing: CARLA puts a reference in
each junction road a lane continues into, up to 4 m apart along the same path."""

Point = tuple[float, float]


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Finding:
    """A test's result: ``passed`` None when it could not be judged."""

    passed: bool | None
    detail: str
    time: float | None = None


@dataclasses.dataclass(frozen=True, slots=True)
class _Crossing:
    signal_id: str
    time: float
    note: str = ""


def is_red(state: str) -> bool:
    """Whether a TrafficSignalStateAction state shows red (``red``, or lamps ``on;...``)."""
    text = state.strip().lower()
    lamps = [lamp.strip() for lamp in text.split(";")]
    return text == "red" or (len(lamps) >= 2 and lamps[0] == "on")


class SignalWatch:
    """Follows the ego across the stop lines of one map's traffic lights and stop signs."""

    __slots__ = (
        "_centre",
        "_ego",
        "_judged",
        "_lights",
        "_names",
        "_odometer",
        "_ran",
        "_recent",
        "_red",
        "_since_standstill",
        "_stopped",
        "_stops",
        "_tail",
        "_unknown",
    )

    def __init__(self, controls: Sequence[TrafficControl]) -> None:
        self._lights = tuple(c for c in controls if c.control is Control.TRAFFIC_LIGHT and c.lines)
        self._stops = tuple(c for c in controls if c.control is Control.STOP_SIGN and c.lines)
        self._names: dict[str, str | None] = {}
        """TrafficSignalStateAction names and the light each means (None: no light)."""
        self._ego = "the ego"
        self._centre: Point | None = None
        self._tail: Point | None = None
        self._since_standstill = math.inf
        self._odometer = 0.0
        """Metres the ego's centre moved in all."""
        self._recent: dict[str, float] = {}
        """The odometer when the ego last crossed a line of each signal."""
        """Metres the ego's centre moved since it last stood still (inf: never)."""
        self._red: list[_Crossing] = []
        self._unknown: list[_Crossing] = []
        self._judged = 0
        self._ran: list[_Crossing] = []
        self._stopped = 0

    def observe(
        self, time: float, ego: EntityState | None, signals: Sequence[tuple[str, str]]
    ) -> None:
        """Update with the ego at ``time`` and the signal states set so far."""
        if ego is None:
            self._centre = self._tail = None
            return
        self._ego = ego.name
        x, y, _ = ego.box_center()
        centre = (x, y)
        tail = (x - TAIL * math.cos(ego.heading), y - TAIL * math.sin(ego.heading))
        moved = (
            math.hypot(x - self._centre[0], y - self._centre[1])
            if self._centre is not None
            else 0.0
        )
        self._odometer += moved
        if abs(ego.speed) < STANDSTILL:
            self._since_standstill = 0.0
        else:
            self._since_standstill += moved
        if self._tail is not None:
            self._check_lights(time, self._tail, tail, signals)
        if self._centre is not None:
            self._check_stops(time, self._centre, centre)
        self._centre, self._tail = centre, tail

    def _check_lights(
        self, time: float, before: Point, after: Point, signals: Sequence[tuple[str, str]]
    ) -> None:
        states: dict[str, str] | None = None
        for light in self._lights:
            if not self._crossed(light, before, after):
                continue
            if states is None:
                states = self._states(signals)
            state = states.get(light.signal_id)
            if state is None:
                self._unknown.append(_Crossing(light.signal_id, time))
            elif is_red(state):
                self._red.append(_Crossing(light.signal_id, time, state))
            else:
                self._judged += 1

    def _check_stops(self, time: float, before: Point, after: Point) -> None:
        for stop in self._stops:
            if not self._crossed(stop, before, after):
                continue
            width = max(line.lane_width for line in stop.lines)
            reach = STOP_LOOKAHEAD + STOP_BOX_SHARE * width
            if self._since_standstill > reach:
                self._ran.append(_Crossing(stop.signal_id, time, f"{reach:.1f}"))
            else:
                self._stopped += 1

    def _crossed(self, control: TrafficControl, before: Point, after: Point) -> bool:
        """Whether the ego just crossed a line of ``control`` on a new approach to it."""
        if not any(line.crossed_by(before, after) for line in control.lines):
            return False
        last = self._recent.get(control.signal_id)
        self._recent[control.signal_id] = self._odometer
        return last is None or self._odometer - last > SAME_APPROACH

    def _states(self, signals: Sequence[tuple[str, str]]) -> dict[str, str]:
        states: dict[str, str] = {}
        for name, state in signals:
            if name not in self._names:
                self._names[name] = self._light_named(name)
            light = self._names[name]
            if light is not None:
                states[light] = state
        return states

    def _light_named(self, name: str) -> str | None:
        return opendrive.light_named(self._lights, name)

    def red_light(self) -> Finding:
        """RunningRedLightTest's result so far."""
        if self._red:
            first = self._red[0]
            more = f"; {len(self._red)} red lights crossed" if len(self._red) > 1 else ""
            detail = f"{self._ego} crossed red light {first.signal_id} at t={first.time:.2f} s"
            return Finding(passed=False, detail=detail + more, time=first.time)
        if self._unknown:
            first = self._unknown[0]
            unmatched = sorted(name for name, light in self._names.items() if light is None)
            names = ", ".join(unmatched)
            hint = f"; TrafficSignalStateAction names matching no traffic light: {names}"
            return Finding(
                passed=None,
                detail=f"no light states known: {self._ego} crossed the stop line of traffic "
                f"light {first.signal_id} at t={first.time:.2f} s, whose state the scenario "
                f"never set{hint if unmatched else ''}",
            )
        if not self._lights:
            return Finding(passed=True, detail="the map has no traffic lights")
        if not self._judged:
            return Finding(passed=True, detail="crossed no traffic light's stop line")
        times = "1 time" if self._judged == 1 else f"{self._judged} times"
        return Finding(passed=True, detail=f"passed traffic lights {times}, never on red")

    def stop_sign(self) -> Finding:
        """RunningStopTest's result so far."""
        if self._ran:
            first = self._ran[0]
            detail = (
                f"{self._ego} ran stop sign {first.signal_id} at t={first.time:.2f} s "
                f"(no standstill within {first.note} m before its line)"
            )
            return Finding(passed=False, detail=detail, time=first.time)
        if not self._stops:
            return Finding(passed=True, detail="the map has no stop signs")
        if not self._stopped:
            return Finding(passed=True, detail="crossed no stop sign's stop line")
        return Finding(
            passed=True, detail=f"stood still before every stop line crossed ({self._stopped})"
        )
