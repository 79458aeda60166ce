"""A map's traffic lights and stop signs as OSI 3.7.0 GroundTruth ``traffic_light`` (field 7)
and ``traffic_sign`` (field 6) messages, so recordings and the SUT's SensorView carry them.

OSI describes a light bulb by bulb: a three-lamp light is three ``osi3.TrafficLight`` messages
(red on top, yellow, green), each with its colour and the mode it is in now (CONSTANT lit, OFF,
FLASHING; UNKNOWN while the scenario never set the light). A stop sign is an
``osi3.TrafficSign`` whose main sign is of type STOP. Each message names its OpenDRIVE signal
in ``source_reference`` (type ``net.asam.opendrive``, identifier the signal id), as OSI
recommends. Heads stand at nominal heights above the signal's road position (the map model
keeps no mounting heights), facing the traffic they govern.

The bytes are appended to a GroundTruth (protobuf fields may come in any order); they change
only when a light does, so each set of states is encoded once.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence

from simtest_operator.drivermodel import Aspect
from simtest_operator.opendrive import Control, SignalIndex, TrafficControl, aspect_of
from simtest_operator.recording import osiwire

LIGHT_ID_BASE = 3_000_000_000
"""OSI ids of bulbs: ``LIGHT_ID_BASE + 3 * k + bulb`` for the k-th light (bulb 0 red, 1 yellow,
2 green), clear of entity ids and the recorder's reissued ones."""
SIGN_ID_BASE = 3_500_000_000
"""OSI ids of stop signs: ``SIGN_ID_BASE + k`` for the k-th sign."""
BULB_HEIGHTS = (2.9, 2.6, 2.3)
"""Metres above the road of the red, yellow and green bulbs (a nominal pole-mounted head)."""
BULB_SIZE = (0.1, 0.3, 0.3)
SIGN_HEIGHT = 2.0
SIGN_SIZE = (0.05, 0.75, 0.75)


class Mode(enum.IntEnum):
    """osi3.TrafficLight.Classification.Mode."""

    UNKNOWN = 0
    OFF = 2
    CONSTANT = 3
    FLASHING = 4


class Color(enum.IntEnum):
    """osi3.TrafficLight.Classification.Color of the three bulbs, top to bottom."""

    RED = 2
    YELLOW = 3
    GREEN = 4


_ICON_NONE = 2
_SIGN_VARIABILITY_FIXED = 2
_SIGN_TYPE_STOP = 17
_SIGN_DIRECTION_NONE = 2
_LAMP_MODES = {"on": Mode.CONSTANT, "off": Mode.OFF, "flashing": Mode.FLASHING}
_ASPECT_MODES = {
    Aspect.RED: (Mode.CONSTANT, Mode.OFF, Mode.OFF),
    Aspect.YELLOW: (Mode.OFF, Mode.CONSTANT, Mode.OFF),
    Aspect.GREEN: (Mode.OFF, Mode.OFF, Mode.CONSTANT),
}


def bulb_modes(state: str | None) -> tuple[Mode, Mode, Mode]:
    """The modes of the red, yellow and green bulbs for a TrafficSignalStateAction ``state``
    (None: never set, all UNKNOWN): esmini's lamp list lamp by lamp, else the word's aspect
    (``off`` all OFF, a flashing yellow FLASHING, red-and-yellow both lit)."""
    unknown = (Mode.UNKNOWN, Mode.UNKNOWN, Mode.UNKNOWN)
    if state is None:
        return unknown
    text = state.strip().lower()
    lamps = [lamp.strip() for lamp in text.split(";")]
    if len(lamps) >= 2:
        modes = [_LAMP_MODES.get(lamp, Mode.UNKNOWN) for lamp in lamps[:3]]
        modes += [Mode.UNKNOWN] * (3 - len(modes))
        return modes[0], modes[1], modes[2]
    word = "".join(char for char in text if char.isalpha())
    if word == "off":
        return Mode.OFF, Mode.OFF, Mode.OFF
    if "flash" in word or "blink" in word:
        yellow = Mode.FLASHING if "yellow" in word or "amber" in word else Mode.UNKNOWN
        return Mode.OFF, yellow, Mode.OFF
    if word == "redyellow":
        return Mode.CONSTANT, Mode.CONSTANT, Mode.OFF
    return _ASPECT_MODES.get(aspect_of(state), unknown)


def _facing(control: TrafficControl) -> float:
    """Yaw of the head's view normal: towards the traffic it governs."""
    heading = control.lines[0].heading if control.lines else control.position.heading
    return math.remainder(heading + math.pi, math.tau)


def _base(x: float, y: float, z: float, yaw: float, size: tuple[float, float, float]) -> bytes:
    """osi3.BaseStationary: dimension(1), position(2), orientation(3)."""
    return (
        osiwire.length_delimited(1, osiwire.triple(*size))
        + osiwire.length_delimited(2, osiwire.triple(x, y, z))
        + osiwire.length_delimited(3, osiwire.triple(0.0, 0.0, yaw))
    )


def _source(signal_id: str) -> bytes:
    """osi3.ExternalReference to the OpenDRIVE signal: type(2), identifier(3)."""
    return osiwire.length_delimited(2, b"net.asam.opendrive") + osiwire.length_delimited(
        3, signal_id.encode()
    )


def _bulb(osi_id: int, control: TrafficControl, bulb: int, mode: Mode) -> bytes:
    """One osi3.TrafficLight: id(1), base(2), classification(3), source_reference(5)."""
    pose = control.position
    classification = (
        osiwire.varint_field(1, Color.RED + bulb)
        + osiwire.varint_field(2, _ICON_NONE)
        + osiwire.varint_field(3, mode)
        + osiwire.double_field(4, 0.0)
        + osiwire.varint_field(6, 0)
    )
    body = (
        osiwire.length_delimited(1, osiwire.identifier(osi_id))
        + osiwire.length_delimited(
            2, _base(pose.x, pose.y, pose.z + BULB_HEIGHTS[bulb], _facing(control), BULB_SIZE)
        )
        + osiwire.length_delimited(3, classification)
        + osiwire.length_delimited(5, _source(control.signal_id))
    )
    return osiwire.length_delimited(7, body)


def _stop_sign(osi_id: int, control: TrafficControl) -> bytes:
    """One osi3.TrafficSign: id(1), main_sign(2) {base(1), classification(2)}, source(4)."""
    pose = control.position
    classification = (
        osiwire.varint_field(1, _SIGN_VARIABILITY_FIXED)
        + osiwire.varint_field(2, _SIGN_TYPE_STOP)
        + osiwire.varint_field(4, _SIGN_DIRECTION_NONE)
        + osiwire.varint_field(6, 0)
        + osiwire.varint_field(7, 0)
    )
    main = osiwire.length_delimited(
        1, _base(pose.x, pose.y, pose.z + SIGN_HEIGHT, _facing(control), SIGN_SIZE)
    ) + osiwire.length_delimited(2, classification)
    body = (
        osiwire.length_delimited(1, osiwire.identifier(osi_id))
        + osiwire.length_delimited(2, main)
        + osiwire.length_delimited(4, _source(control.signal_id))
    )
    return osiwire.length_delimited(6, body)


class SignalWire:
    """Encodes the traffic lights (with their current states) and stop signs of one map."""

    __slots__ = ("_cache", "_index", "_signs")

    def __init__(self, controls: Sequence[TrafficControl]) -> None:
        self._index = SignalIndex(controls)
        stops = [c for c in self._index.controls if c.control is Control.STOP_SIGN]
        self._signs = b"".join(
            _stop_sign(SIGN_ID_BASE + k, control) for k, control in enumerate(stops)
        )
        self._cache: dict[tuple[tuple[str, str], ...], bytes] = {}

    def __bool__(self) -> bool:
        return bool(self._index.controls)

    def encode(self, signals: Sequence[tuple[str, str]]) -> bytes:
        """GroundTruth fields 6 and 7 for the signal states ``(name, state)`` set so far."""
        key = tuple(signals)
        cached = self._cache.get(key)
        if cached is not None:
            return cached
        states: dict[str, str] = {}
        for name, state in key:
            light = self._index.light_of(name)
            if light is not None:
                states[light] = state
        lights = b"".join(
            _bulb(LIGHT_ID_BASE + 3 * k + bulb, control, bulb, mode)
            for k, control in enumerate(self._index.lights)
            for bulb, mode in enumerate(bulb_modes(states.get(control.signal_id)))
        )
        encoded = self._signs + lights
        if len(self._cache) < 256:
            self._cache[key] = encoded
        return encoded
