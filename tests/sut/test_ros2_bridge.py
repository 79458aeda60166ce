"""A ROS 2 stack as the SUT through the bridge: an independent DDS participant (tests/sut/
ros2_stack.py: its own IDL types, rosbags' CDR, no bridge code) drives the ego in lockstep; the
smoke campaign gives the verdicts of the same logic behind the OSI protocol; what travels is
rosbags' CDR under ROS 2's names with ROS 2's QoS; a silent stack ends the run Error saying so.

DDS stays on this machine: Cyclone DDS is configured for the loopback interface, without
multicast, with 127.0.0.1 as the only peer, and every test has a domain id of its own.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import json
import math
import os
import re
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner
from cyclonedds.qos import Policy

from simtest_operator.cli.main import cli
from simtest_operator.drivermodel import ExternalSut, Launch, SutConfig
from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState
from simtest_operator.sut.reference import Perceived
from simtest_operator.sut.ros2 import bridge, converting, dds, interfaces
from simtest_operator.verdicts import Verdict

REPO = Path(__file__).resolve().parents[2]
STACK = Path(__file__).parent / "ros2_stack.py"
SCENARIO = Path(__file__).parents[1] / "sim" / "data" / "hard_braking_lead.xosc"
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
    manifest["spec"]["execution"]["retries"] = 0  # an Error must show, not be retried away
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
    timing = ("wallSeconds", "realTimeFactor", "loopRealTimeFactor", "sutRoundTrip")
    for scenario, result in behind_ros.items():  # min TTC, THW, deceleration, ...: the same
        expected = behind_osi[scenario]["metrics"]
        measured = {k: v for k, v in result["metrics"].items() if not k.startswith(timing)}
        assert measured == {k: v for k, v in expected.items() if not k.startswith(timing)}
    for result in behind_ros.values():
        assert result["versions"]["sut.reported"] == "simtest-ros2-bridge 1.0.0"
        assert result["metrics"]["sutSteps"] > 40


def test_the_bridge_publishes_rosbags_cdr_under_ros2_names_with_ros2_qos(domain: int) -> None:
    """A participant subscribing like a ROS 2 node gets, byte for byte, what rosbags
    serialises, and discovers the bridge's endpoints with the rmw profiles' QoS."""
    endpoints = bridge.Endpoints(bridge.BridgeConfig(domain_id=domain))
    store = interfaces.typestore()
    node = dds.Participant(domain)
    clock = node.reader("/clock", interfaces.CLOCK, interfaces.CLOCK_QOS)
    odometry = node.reader("/simtest/ego/odometry", interfaces.ODOMETRY, interfaces.SENSOR_DATA)
    objects = node.reader("/simtest/objects", interfaces.OBJECT_ARRAY, interfaces.SENSOR_DATA)
    target = node.reader("/simtest/ego/target_speed", interfaces.FLOAT64, interfaces.LATCHED)
    command = node.writer("/simtest/ego/command", interfaces.ACKERMANN, interfaces.DEFAULT)
    everything = [clock, odometry, objects, target, command]
    assert dds.wait_matched(everything, timeout=10) == []
    assert endpoints.odometry.writer.topic.name == "rt/simtest/ego/odometry"
    assert endpoints.odometry.writer.topic.typename == "nav_msgs::msg::dds_::Odometry_"
    assert endpoints.objects.writer.topic.typename == (
        "derived_object_msgs::msg::dds_::ObjectArray_"
    )
    assert endpoints.command.reader.topic.typename == (
        "ackermann_msgs::msg::dds_::AckermannDriveStamped_"
    )

    def discovered(reader: dds.Reader) -> object:
        (handle,) = reader.reader.get_matched_publications()
        return reader.reader.get_matched_publication_data(handle).qos

    best_effort, volatile = Policy.Reliability.BestEffort, Policy.Durability.Volatile
    sensors = ((clock, endpoints.clock, 1), (odometry, endpoints.odometry, 5))
    for reader, writer, depth in (*sensors, (objects, endpoints.objects, 5)):
        seen = discovered(reader)  # what the bridge's writer announced in discovery
        assert best_effort in seen and volatile in seen, seen
        assert writer.writer.get_qos()[Policy.History] == Policy.History.KeepLast(depth)
    assert Policy.Durability.TransientLocal in discovered(target)
    command_qos = endpoints.command.reader.get_qos()
    assert Policy.Reliability.Reliable in command_qos and volatile in command_qos
    assert command_qos[Policy.History] == Policy.History.KeepLast(10)

    stamp = endpoints.messages.clock(1_250_000_000)
    endpoints.clock.publish(stamp)
    assert clock.wait(5)
    (raw,) = clock.take_raw()
    assert raw == bytes(store.serialize_cdr(stamp, interfaces.CLOCK))  # 12 bytes: no padding
    assert raw == bytes.fromhex("000100000100000080b2e60e")  # CDR LE, 1 s, 250,000,000 ns


EGO = Perceived(
    state=EntityState(
        id=7,
        name="7",
        kind=EntityKind.VEHICLE,
        category="car",
        x=12.5,
        y=-3.25,
        z=0.75,
        heading=0.3,
        speed=20.0,
        box=BoundingBox(length=4.5, width=1.8, height=1.5),
    ),
    vx=20.0 * math.cos(0.3),
    vy=20.0 * math.sin(0.3),
    object_type=2,
    vehicle_class=4,
)


def rtps_payloads(sock: socket.socket, *, seconds: float) -> list[bytes]:
    """Serialised payloads of the RTPS DATA submessages captured on ``lo`` for ``seconds``."""
    found: list[bytes] = []
    end = time.monotonic() + seconds
    while (left := end - time.monotonic()) > 0:
        sock.settimeout(left)
        try:
            frame = sock.recv(65535)
        except TimeoutError:
            break
        ip = frame[14:]  # lo frames carry a zeroed Ethernet header
        if len(ip) < 28 or ip[0] >> 4 != 4 or ip[9] != 17:  # IPv4, UDP
            continue
        rtps = ip[(ip[0] & 0x0F) * 4 + 8 :]
        if rtps[:4] != b"RTPS":
            continue
        at = 20
        while at + 4 <= len(rtps):
            kind, flags = rtps[at], rtps[at + 1]
            order = "<" if flags & 1 else ">"
            (size,) = struct.unpack(order + "H", rtps[at + 2 : at + 4])
            body = rtps[at + 4 : at + 4 + size] if size else rtps[at + 4 :]
            if kind == 0x15 and flags & 0x04:  # DATA with a serialised payload
                start = 4 + struct.unpack(order + "H", body[2:4])[0]
                if flags & 0x02:  # inline QoS: a parameter list up to PID_SENTINEL
                    while body[start : start + 2] not in (b"\x01\x00", b"\x00\x01"):
                        (length,) = struct.unpack(order + "H", body[start + 2 : start + 4])
                        start += 4 + length
                    start += 4
                found.append(bytes(body[start:]))
            if not size:
                break
            at += 4 + size
    return found


@pytest.mark.skipif(os.geteuid() != 0, reason="capturing on lo needs CAP_NET_RAW")
def test_the_bytes_on_the_wire_are_what_rosbags_serialises(domain: int, tmp_path: Path) -> None:
    """Captured off the loopback interface (the subscriber is another process, so Cyclone DDS
    sends UDP): each DATA submessage's payload is rosbags' CDR."""
    store = interfaces.typestore()
    other = dataclasses.replace(EGO, state=dataclasses.replace(EGO.state, id=8, x=40.0))
    with stack(domain, tmp_path):
        endpoints = bridge.Endpoints(bridge.BridgeConfig(domain_id=domain))
        assert dds.wait_matched([endpoints.odometry, endpoints.objects], timeout=20) == []
        objects = endpoints.messages.objects([other], 3_000_000_000)
        odometry = endpoints.messages.odometry(EGO, 3_000_000_000)
        with socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003)) as sock:
            sock.bind(("lo", 0))
            endpoints.objects.publish(objects)
            endpoints.odometry.publish(odometry)
            captured = rtps_payloads(sock, seconds=1.0)
    expected = {
        "objects": bytes(store.serialize_cdr(objects, interfaces.OBJECT_ARRAY)),
        "odometry": bytes(store.serialize_cdr(odometry, interfaces.ODOMETRY)),
    }
    for name, payload in expected.items():
        assert payload in captured, name  # both end 4-byte aligned: nothing padded
        assert payload[:4] == b"\x00\x01\x00\x00"  # CDR, little-endian, no options
    decoded = store.deserialize_cdr(expected["odometry"], interfaces.ODOMETRY)
    assert decoded.pose.pose.position.x == EGO.state.x
    assert decoded.twist.twist.linear.x == pytest.approx(20.0)  # forward, in base_link
    assert decoded.twist.twist.linear.y == pytest.approx(0.0, abs=1e-12)


def run_one(
    domain: int, *options: str, module: str = "simtest_operator.sut.ros2"
) -> scenario_execution.RunReport:
    """The hard-braking scenario with the bridge (or another SUT module) as a local process."""
    external = ExternalSut(
        launch=Launch.LOCAL,
        command=(sys.executable, "-m", module, *options),
        env={"ROS_DOMAIN_ID": str(domain), "CYCLONEDDS_URI": LOOPBACK},
        step_deadline=0.5,
        startup_timeout=30.0,
    )
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO,
            nets_dir=Path(),
            sut=SutConfig(external=external),
            backend=BackendChoice.MEMORY,
            simulation=SimulationSettings(),
        )
    )


def test_a_missing_or_silent_stack_ends_the_run_error_saying_which_topic(domain: int) -> None:
    missing = run_one(domain, "--ready-timeout", "1")
    assert missing.outcome.verdict is Verdict.ERROR
    assert (
        f"the ROS 2 stack did not appear within 1 s in DDS domain {domain}: no subscriber of "
        "/simtest/ego/odometry and no publisher of /simtest/ego/command"
    ) in missing.outcome.reason
    node = dds.Participant(domain)  # subscribes and advertises a command, never sends one
    listening = node.reader("/simtest/ego/odometry", interfaces.ODOMETRY, interfaces.SENSOR_DATA)
    silent = node.writer("/simtest/ego/command", interfaces.ACKERMANN, interfaces.DEFAULT)
    silent_run = run_one(domain)
    assert silent_run.outcome.verdict is Verdict.ERROR
    assert re.search(
        r"the ROS 2 stack published no command on /simtest/ego/command "
        r"\(ackermann_msgs/msg/AckermannDriveStamped\) for t=\d+\.\d{3} s within 400 ms",
        silent_run.outcome.reason,
    ), silent_run.outcome.reason
    assert listening.take_raw()  # it did get the odometry
    del silent


@pytest.mark.slow
def test_a_stack_answering_with_unstamped_twists_drives_like_the_osi_sut(
    domain: int, tmp_path: Path
) -> None:
    twist = "geometry_msgs/msg/Twist"
    behind_osi = run_one(domain, module="simtest_operator.sut.reference")
    with stack(domain, tmp_path, "--command-type", twist) as log:
        behind_ros = run_one(domain, "--command-type", twist)
    assert "Traceback" not in log.read_text()
    assert behind_ros.outcome.verdict is behind_osi.outcome.verdict, behind_ros.outcome.reason
    assert behind_ros.outcome.reason == behind_osi.outcome.reason
    assert behind_ros.outcome.metrics["sutSteps"] == behind_osi.outcome.metrics["sutSteps"] > 50


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
