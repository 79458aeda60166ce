"""Traffic lights and stop signs in OSI: the recording's GroundTruth and the SUT's SensorView.

On ``carla/crossing.xodr`` (light 10, stop sign 20) a run whose controller shows red for 14 s,
then green, records light 10 as three bulbs (red, yellow, green) whose modes follow the phase,
and stop sign 20 as a STOP sign, each naming its OpenDRIVE signal; the SensorView an external
SUT gets carries the same. How states map to bulb modes (words, esmini's lamp lists, never set)
is checked on its own.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import betterosi
import pytest
from mcap.reader import make_reader

from simtest_operator import opendrive
from simtest_operator.recording import signalwire
from simtest_operator.recording.signalwire import Mode
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, WorldSnapshot
from simtest_operator.sut import messages
from tests.sim import carla_scenarios as cs
from tests.sim import test_signal_obedience as obey

osi = betterosi.v3_7_0
Light = osi.TrafficLight.Classification
CROSSING = cs.HERE / "crossing.xodr"


def bulbs(gt: osi.GroundTruth) -> list[tuple[str, int, int]]:
    """(signal id, colour, mode) of every bulb, in order."""
    return [
        (
            light.source_reference[0].identifier[0],
            int(light.classification.color),
            int(light.classification.mode),
        )
        for light in gt.traffic_light
    ]


def lit(red: Mode, yellow: Mode, green: Mode) -> list[tuple[str, int, int]]:
    return [("10", 2, red), ("10", 3, yellow), ("10", 4, green)]


def test_recorded_ground_truth_carries_lights_and_stop_signs(tmp_path: Path) -> None:
    shutil.copy(CROSSING, tmp_path / "crossing.xodr")
    path = tmp_path / "obey.xosc"
    path.write_text(obey.scenario(signals=obey.RED_THEN_GREEN, end=16.0), encoding="utf-8")
    out = tmp_path / "out"
    cs.run(path, out=out)
    frames: dict[float, osi.GroundTruth] = {}
    with (out / "recording.mcap").open("rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages():
            if channel.topic == "ground_truth":
                gt = osi.GroundTruth.from_binary(message.data)
                frames[gt.timestamp.seconds + gt.timestamp.nanos / 1e9] = gt
    red, green = frames[5.0], frames[15.0]
    assert bulbs(red) == lit(Mode.CONSTANT, Mode.OFF, Mode.OFF)
    assert bulbs(green) == lit(Mode.OFF, Mode.OFF, Mode.CONSTANT)
    assert [light.base.position.z for light in red.traffic_light] == list(signalwire.BULB_HEIGHTS)
    # the head stands where the signal does (s=96, t=-8.5) and faces the oncoming traffic
    head = red.traffic_light[0].base
    assert (head.position.x, head.position.y) == pytest.approx((96.0, -8.5))
    assert head.orientation.yaw == pytest.approx(3.14159265, abs=1e-6)
    assert red.traffic_light[0].source_reference[0].type == "net.asam.opendrive"
    assert len({light.id.value for light in red.traffic_light}) == 3
    (sign,) = red.traffic_sign
    assert sign.source_reference[0].identifier == ["20"]
    classification = sign.main_sign.classification
    assert classification.type == osi.TrafficSign.MainSign.Classification.Type.STOP
    assert (sign.main_sign.base.position.x, sign.main_sign.base.position.y) == (200.0, -8.5)
    # the moving objects are untouched
    assert [mv.id.value for mv in red.moving_object] == [0]


def test_sensor_view_carries_the_lights_as_set() -> None:
    controls = opendrive.traffic_controls(opendrive.RoadNetwork.from_file(CROSSING))
    encoder = messages.SensorViewEncoder(perception_range=None, signals=controls)
    ego = EntityState(
        id=0, name="hero", kind=EntityKind.VEHICLE, category="car", x=50.0, y=-1.75,
        heading=0.0, speed=10.0, box=BoundingBox(center_x=1.5, length=4.5, width=2.1),
    )  # fmt: skip
    for state, expected in [
        ("on;off;off", lit(Mode.CONSTANT, Mode.OFF, Mode.OFF)),
        ("Yellow", lit(Mode.OFF, Mode.CONSTANT, Mode.OFF)),
    ]:
        snapshot = WorldSnapshot(time=1.0, entities=(ego,), signals=(("id=10", state),))
        view = betterosi.SensorView.from_binary(encoder.encode(snapshot, ego))
        assert bulbs(view.global_ground_truth) == expected
        assert len(view.global_ground_truth.traffic_sign) == 1
        assert [mv.id.value for mv in view.global_ground_truth.moving_object] == [0]


@pytest.mark.parametrize(
    ("state", "modes"),
    [
        (None, (Mode.UNKNOWN, Mode.UNKNOWN, Mode.UNKNOWN)),
        ("Red", (Mode.CONSTANT, Mode.OFF, Mode.OFF)),
        ("green", (Mode.OFF, Mode.OFF, Mode.CONSTANT)),
        ("red-yellow", (Mode.CONSTANT, Mode.CONSTANT, Mode.OFF)),
        ("Off", (Mode.OFF, Mode.OFF, Mode.OFF)),
        ("yellow flashing", (Mode.OFF, Mode.FLASHING, Mode.OFF)),
        ("off;on;off", (Mode.OFF, Mode.CONSTANT, Mode.OFF)),
        ("off;flashing;off", (Mode.OFF, Mode.FLASHING, Mode.OFF)),
        ("purple", (Mode.UNKNOWN, Mode.UNKNOWN, Mode.UNKNOWN)),
    ],
)
def test_bulb_modes(state: str | None, modes: tuple[Mode, Mode, Mode]) -> None:
    assert signalwire.bulb_modes(state) == modes


@pytest.mark.parametrize(
    ("state", "aspect"),
    [
        ("Red", "red"),
        ("red-yellow", "red"),
        ("on;off;off", "red"),
        ("YELLOW", "yellow"),
        ("off;on;off", "yellow"),
        ("Green", "green"),
        ("off;off;on", "green"),
        ("Off", "unknown"),
        ("off;off;off", "unknown"),
        ("yellow flashing", "unknown"),
    ],
)
def test_aspect_of(state: str, aspect: str) -> None:
    assert opendrive.aspect_of(state) == aspect
