"""Traffic lights and stop signs of a road network, as the stop lines a driver must respect.

A signal stands beside the road; what it governs is a line across each lane it applies to, where
a vehicle must stop. CARLA's towns (RoadRunner exports) put the signal on its pole and a
``<signalReference>`` for each lane of every junction road it controls, 0.6 m past the junction
entry: that is the stop line. So a signal with references is placed at its references only; one
without any (hand-written maps, esmini's) is placed where it stands. The lanes are the
``<validity>`` ranges, or, without one (or with CARLA's ``0..0``), every lane whose traffic the
signal faces (``orientation`` ``+``: traffic towards increasing s, ``-``: the other way, ``none``:
both). As in CARLA, only ``driving`` lanes get a line, 90 % of the lane wide.

Kinds (``type``, any ``country``): ``1000001`` a vehicle traffic light (OpenDRIVE's three-lamp
light, also CARLA's ``Signal_3Light_Post01``), ``206`` a stop sign (StVO 206, CARLA's
``Sign_Stop``). Other signals (yield, speed limits, pedestrian lights) are not stop lines.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Iterator, Mapping, Sequence

from simtest_operator.drivermodel import Aspect
from simtest_operator.opendrive import models
from simtest_operator.opendrive.network import Pose, RoadNetwork

POSITION_MATCH = 2.0
"""Metres within which a state action's ``pos=x,y`` names a light (ScenarioRunner's tolerance)."""
_LINE_SHARE = 0.9
"""Share of the lane width a stop line spans (CARLA's trigger boxes: 90 %, so that they do not
reach into the next lane)."""


class Control(enum.StrEnum):
    """What a signal asks of the traffic it faces."""

    TRAFFIC_LIGHT = "traffic light"
    STOP_SIGN = "stop sign"


_KINDS = {"1000001": Control.TRAFFIC_LIGHT, "206": Control.STOP_SIGN}


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StopLine:
    """A line across one lane, ``start`` to ``end`` (world x, y), crossed by traffic heading
    ``heading`` (radians, the lane's travel direction there)."""

    road_id: str
    lane_id: int
    s: float
    start: tuple[float, float]
    end: tuple[float, float]
    heading: float
    lane_width: float

    def crossed_by(self, before: tuple[float, float], after: tuple[float, float]) -> bool:
        """Whether a point moving from ``before`` to ``after`` passed the line in the travel
        direction (from behind it to on or beyond it, within its span)."""
        mid_x, mid_y = (self.start[0] + self.end[0]) / 2.0, (self.start[1] + self.end[1]) / 2.0
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        a0 = (before[0] - mid_x) * cos_h + (before[1] - mid_y) * sin_h
        a1 = (after[0] - mid_x) * cos_h + (after[1] - mid_y) * sin_h
        if not a0 < 0.0 <= a1:
            return False
        share = a0 / (a0 - a1)
        x = before[0] + share * (after[0] - before[0]) - mid_x
        y = before[1] + share * (after[1] - before[1]) - mid_y
        span_x, span_y = self.end[0] - self.start[0], self.end[1] - self.start[1]
        half = math.hypot(span_x, span_y) / 2.0
        return half > 0.0 and abs(x * span_x + y * span_y) / (2.0 * half) <= half


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficControl:
    """One traffic light or stop sign: where it stands and the stop lines it governs."""

    signal_id: str
    name: str
    control: Control
    position: Pose
    lines: tuple[StopLine, ...]


def kind_of(signal: models.Signal) -> Control | None:
    """The control a signal exerts, or None when it is no traffic light or stop sign."""
    return _KINDS.get(signal.type)


def traffic_controls(network: RoadNetwork) -> tuple[TrafficControl, ...]:
    """Every traffic light and stop sign of ``network`` with its stop lines (a signal whose lanes
    are all missing or not ``driving`` has none), in document order."""
    references: dict[str, list[models.Placement]] = {}
    for road in network.document.roads:
        for reference in road.signal_references:
            references.setdefault(reference.signal_id, []).append(reference.placement)
    result = []
    for road in network.document.roads:
        for signal in road.signals:
            control = kind_of(signal)
            if control is None:
                continue
            placements = references.get(signal.id) or [signal.placement]
            lines = tuple(line for place in placements for line in _lines(network, place))
            result.append(
                TrafficControl(
                    signal_id=signal.id,
                    name=signal.name,
                    control=control,
                    position=network.road_pose(
                        signal.placement.road_id, signal.placement.s, signal.placement.t
                    ),
                    lines=lines,
                )
            )
    return tuple(result)


def _lines(network: RoadNetwork, place: models.Placement) -> Iterator[StopLine]:
    road_id, s = place.road_id, place.s
    existing = network.lane_ids(road_id, s)
    named = {lane for validity in place.validities for lane in validity.lane_ids}
    if named:
        lanes = [lane for lane in existing if lane in named]
    else:
        lanes = [lane for lane in existing if _faces(network, road_id, lane, place.orientation)]
    reference = network.reference_pose(road_id, s)
    for lane_id in lanes:
        bounds = network.lane_bounds(road_id, s, lane_id)
        if bounds is None or bounds.type != "driving" or bounds.width <= 0.0:
            continue
        half = bounds.width * _LINE_SHARE / 2.0
        start = network.road_pose(road_id, s, bounds.t_center - half)
        end = network.road_pose(road_id, s, bounds.t_center + half)
        forward = network.driving_direction(road_id, lane_id) > 0
        yield StopLine(
            road_id=road_id,
            lane_id=lane_id,
            s=s,
            start=(start.x, start.y),
            end=(end.x, end.y),
            heading=math.remainder(reference.heading + (0.0 if forward else math.pi), math.tau),
            lane_width=bounds.width,
        )


def _faces(network: RoadNetwork, road_id: str, lane_id: int, orientation: str) -> bool:
    if orientation == "none":
        return True
    direction = network.driving_direction(road_id, lane_id)
    return direction > 0 if orientation == "+" else direction < 0


_WORDS = {
    "red": Aspect.RED,
    "stop": Aspect.RED,
    "redyellow": Aspect.RED,
    "yellow": Aspect.YELLOW,
    "amber": Aspect.YELLOW,
    "green": Aspect.GREEN,
    "go": Aspect.GREEN,
}


def aspect_of(state: str) -> Aspect:
    """The aspect a TrafficSignalStateAction's ``state`` shows: a word (``Red``, ``Yellow``,
    ``Green`` as ScenarioRunner writes them; red-and-yellow still means stop), or esmini's lamp
    list ``red;yellow;green`` of ``on``/``off`` (a lit red lamp wins). Off, flashing or anything
    else is UNKNOWN: the light does not regulate."""
    text = state.strip().lower()
    lamps = [lamp.strip() for lamp in text.split(";")]
    if len(lamps) >= 2:
        lit = [lamp == "on" for lamp in lamps[:3]]
        for on, aspect in zip(lit, (Aspect.RED, Aspect.YELLOW, Aspect.GREEN), strict=False):
            if on:
                return aspect
        return Aspect.UNKNOWN
    word = "".join(char for char in text if char.isalpha())
    return _WORDS.get(word, Aspect.UNKNOWN)


def light_named(lights: Sequence[TrafficControl], name: str) -> str | None:
    """The id of the light a TrafficSignalStateAction's ``name`` means: the OpenDRIVE signal id,
    ScenarioRunner's ``id=<id>``, or its ``pos=x,y`` (the light standing within
    :data:`POSITION_MATCH` of that point in CARLA's frame, y negated); None when none."""
    text = name.strip()
    ids = {light.signal_id for light in lights}
    if text in ids:
        return text
    if text.startswith("id=") and text[3:].strip() in ids:
        return text[3:].strip()
    if text.startswith("pos="):
        try:
            px, py = (float(part) for part in text[4:].split(","))
        except ValueError:
            return None
        best = min(
            lights,
            key=lambda light: math.hypot(light.position.x - px, -light.position.y - py),
            default=None,
        )
        if best is not None and (
            math.hypot(best.position.x - px, -best.position.y - py) <= POSITION_MATCH
        ):
            return best.signal_id
    return None


class SignalIndex:
    """A map's traffic controls, found by the lane their stop lines cross, and the light each
    state name means: what a driver looks up along its path every step."""

    __slots__ = ("_by_lane", "_names", "controls", "lights")

    def __init__(self, controls: Sequence[TrafficControl]) -> None:
        self.controls = tuple(controls)
        self.lights = tuple(c for c in self.controls if c.control is Control.TRAFFIC_LIGHT)
        self._by_lane: dict[tuple[str, int], list[tuple[StopLine, TrafficControl]]] = {}
        for control in self.controls:
            for line in control.lines:
                self._by_lane.setdefault((line.road_id, line.lane_id), []).append((line, control))
        self._names: dict[str, str | None] = {}

    def __bool__(self) -> bool:
        return bool(self._by_lane)

    def lines(self, road_id: str, lane_id: int) -> Sequence[tuple[StopLine, TrafficControl]]:
        """The stop lines across lane ``lane_id`` of road ``road_id``, with their controls."""
        return self._by_lane.get((road_id, lane_id), ())

    def light_of(self, name: str) -> str | None:
        """:func:`light_named`, remembered per name."""
        if name not in self._names:
            self._names[name] = light_named(self.lights, name)
        return self._names[name]

    def aspects(self, states: Mapping[str, str]) -> dict[str, Aspect]:
        """The aspect of every light whose state is set, by signal id (a light never set is
        absent: unknown)."""
        result: dict[str, Aspect] = {}
        for name, state in states.items():
            light = self.light_of(name)
            if light is not None:
                result[light] = aspect_of(state)
        return result
