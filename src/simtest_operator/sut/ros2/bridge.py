"""The ROS 2 bridge: an OSI-protocol SUT on the simulator's side, a DDS participant with ROS 2's
conventions on the stack's side, in lockstep.

Per step the bridge publishes the simulation time on ``/clock`` (``rosgraph_msgs/Clock``, for
nodes with ``use_sim_time``), the scenario's set speed when it changes, the other objects
(``derived_object_msgs/ObjectArray``) and the ego's odometry (``nav_msgs/Odometry``), then waits
for the stack's command for that time (``ackermann_msgs/AckermannDriveStamped`` stamped with it,
or a ``geometry_msgs/Twist[Stamped]``) and answers the simulator with the MotionRequest it
implies. The simulator does not advance meanwhile, so a run is as deterministic as the stack.
READY goes out only once the stack's nodes are there (a subscriber of the odometry and a
publisher of the command matched), so the simulator's start-up wait covers the stack's start.

Run it as the SUT's command (``python -m simtest_operator.sut.ros2``, ``simtest-ros2-bridge``);
docs/sut-interface.md ("A ROS 2 stack as the SUT") has the topics, types and QoS.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import signal
import socket
import sys
import time
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState
from simtest_operator.sut import framing, reference
from simtest_operator.sut.errors import SutError
from simtest_operator.sut.framing import Kind
from simtest_operator.sut.ros2 import converting, dds, interfaces
from simtest_operator.sut.ros2.interfaces import QosProfile

NAME = "simtest-ros2-bridge"
VERSION = "1.0.0"
DEADLINE_SHARE = 0.8
"""Share of the simulator's step deadline the bridge waits for the stack's command: a stack that
stays silent then ends the run with the bridge's precise reason, not a bare missed deadline."""


_NOWHERE = EntityState(
    id=0,
    name="warm-up",
    kind=EntityKind.VEHICLE,
    category="car",
    x=0.0,
    y=0.0,
    z=0.0,
    heading=0.0,
    speed=0.0,
    box=BoundingBox(length=1.0, width=1.0, height=1.0),
)


class StackError(ValueError):
    """The stack did not do its part (no command, a command for another time)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Topics:
    """The ROS 2 topics (absolute names) and the command's type."""

    clock: str = "/clock"
    odometry: str = "/simtest/ego/odometry"
    objects: str = "/simtest/objects"
    target_speed: str = "/simtest/ego/target_speed"
    command: str = "/simtest/ego/command"
    command_type: str = interfaces.ACKERMANN


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BridgeConfig:
    """How the bridge meets the stack."""

    domain_id: int = 0
    """ROS_DOMAIN_ID (the DDS domain)."""
    topics: Topics = Topics()
    frames: converting.Frames = dataclasses.field(default_factory=converting.Frames)
    sensor_qos: QosProfile = interfaces.SENSOR_DATA
    """Odometry and objects; ``--reliable-sensors`` for stacks subscribing with the default."""
    clock_qos: QosProfile = interfaces.CLOCK_QOS
    command_qos: QosProfile = interfaces.DEFAULT
    wheelbase: float = 2.8
    """Metres; turns an Ackermann steering angle into a yaw rate."""
    command_timeout: float = 0.08
    """Seconds to wait for a command when HELLO names no step deadline."""
    ready_timeout: float = 60.0
    """Seconds to wait for the stack's endpoints before answering HELLO with ERROR."""


class Endpoints:
    """The bridge's DDS participant, its writers and the command reader (live across runs)."""

    def __init__(self, config: BridgeConfig) -> None:
        topics = config.topics
        if topics.command_type not in interfaces.COMMAND_TYPES:
            raise ValueError(
                f"command type {topics.command_type} is not one of "
                + ", ".join(interfaces.COMMAND_TYPES)
            )
        self.participant = dds.Participant(config.domain_id)
        self.messages = converting.Messages(self.participant.store, config.frames)
        self.clock = self.participant.writer(topics.clock, interfaces.CLOCK, config.clock_qos)
        self.target_speed = self.participant.writer(
            topics.target_speed, interfaces.FLOAT64, interfaces.LATCHED
        )
        self.objects = self.participant.writer(
            topics.objects, interfaces.OBJECT_ARRAY, config.sensor_qos
        )
        self.odometry = self.participant.writer(
            topics.odometry, interfaces.ODOMETRY, config.sensor_qos
        )
        self.command = self.participant.reader(
            topics.command, topics.command_type, config.command_qos
        )
        self._warm_up()

    def _warm_up(self) -> None:
        """Encode and decode one message of each type now: rosbags compiles a type's codec on
        first use (about 0.1 s here), which must not eat into the first step's deadline."""
        store, m = self.participant.store, self.messages
        ego = reference.Perceived(state=_NOWHERE, vx=0.0, vy=0.0)
        for message, ros_type in (
            (m.clock(0), interfaces.CLOCK),
            (m.float64(0.0), interfaces.FLOAT64),
            (m.objects([ego], 0), interfaces.OBJECT_ARRAY),
            (m.odometry(ego, 0), interfaces.ODOMETRY),
            (m.command_sample(self.command.ros_type), self.command.ros_type),
        ):
            store.deserialize_cdr(store.serialize_cdr(message, ros_type), ros_type)


class Run:
    """One simulator connection: HELLO's settings and the lockstep exchange."""

    def __init__(
        self, endpoints: Endpoints, config: BridgeConfig, hello: Mapping[str, Any]
    ) -> None:
        self._e = endpoints
        self._config = config
        self.ego_id = int(hello.get("egoId", -1))
        self.dt = float(hello["step"])
        deadline = hello.get("stepDeadlineMilliseconds")
        self.timeout = (
            float(deadline) / 1000.0 * DEADLINE_SHARE
            if deadline is not None
            else config.command_timeout
        )
        endpoints.command.drain()  # a previous run's late commands are not this one's

    def target_speed(self, payload: bytes) -> None:
        """A TrafficCommand: the scenario's set speed, latched for the stack."""
        target = reference.parse_target_speed(payload, self.ego_id)
        if target is not None:
            self._e.target_speed.publish(self._e.messages.float64(target))

    def step(self, sensor_view: bytes) -> bytes:
        """Publish the step's inputs, wait for the stack's command, return the MotionRequest."""
        nanos, host_id, objects = reference.parse_sensor_view(sensor_view)
        ego = next((o for o in objects if o.state.id == host_id), None)
        if ego is None:
            raise ValueError(f"host vehicle {host_id} is not among the moving objects")
        e = self._e
        stamped = e.command.ros_type != interfaces.TWIST
        if not stamped:
            e.command.drain()  # an unstamped command counts only if it comes after the inputs
        e.clock.publish(e.messages.clock(nanos))
        e.objects.publish(e.messages.objects([o for o in objects if o is not ego], nanos))
        e.odometry.publish(e.messages.odometry(ego, nanos))
        wanted = self._command(nanos)
        speed, lateral = converting.next_motion(ego.state.speed, wanted, self.dt)
        yaw = ego.state.heading
        c, s = math.cos(yaw), math.sin(yaw)
        travelled = (ego.state.speed + speed) / 2.0 * self.dt
        return reference.motion_request(
            nanos=nanos + round(self.dt * 1e9),
            position=(
                ego.state.x + travelled * c - lateral * s,
                ego.state.y + travelled * s + lateral * c,
            ),
            yaw=yaw,
            speed=speed,
            acceleration=(speed - ego.state.speed) / self.dt,
        )

    def _command(self, nanos: int) -> converting.Command:
        reader = self._e.command
        deadline = time.monotonic() + self.timeout
        while True:
            found: converting.Command | None = None
            for raw in reader.take_raw():
                wanted = converting.command(
                    reader.decode(raw), reader.ros_type, wheelbase=self._config.wheelbase
                )
                if wanted.stamp is not None and wanted.stamp > nanos:
                    raise StackError(
                        f"the stack's command on {self._config.topics.command} is stamped "
                        f"{wanted.stamp / 1e9:.3f} s, ahead of the simulation time "
                        f"{nanos / 1e9:.3f} s"
                    )
                if wanted.stamp is None or wanted.stamp == nanos:
                    found = wanted
            if found is not None:
                return found
            left = deadline - time.monotonic()
            if left <= 0.0:
                raise StackError(
                    f"the ROS 2 stack published no command on {self._config.topics.command} "
                    f"({reader.ros_type}) for t={nanos / 1e9:.3f} s within "
                    f"{self.timeout * 1000:.0f} ms"
                )
            reader.wait(left)


def await_stack(endpoints: Endpoints, config: BridgeConfig) -> None:
    """Return once the stack subscribes to the odometry and publishes the command."""
    missing = dds.wait_matched(
        [endpoints.odometry, endpoints.command], timeout=config.ready_timeout
    )
    if missing:
        what = [
            f"no subscriber of {config.topics.odometry}"
            if m is endpoints.odometry
            else f"no publisher of {config.topics.command}"
            for m in missing
        ]
        raise StackError(
            f"the ROS 2 stack did not appear within {config.ready_timeout:g} s in DDS domain "
            f"{config.domain_id}: {' and '.join(what)}"
        )


def _log(line: str) -> None:
    """One line of the bridge's own log (stderr: beside the stack's in the scenario's sut.log)."""
    print(f"{NAME}: {line}", file=sys.stderr, flush=True)


def serve_connection(conn: socket.socket, endpoints: Endpoints, config: BridgeConfig) -> None:
    """Serve one run; returns on GOODBYE, a closed connection or an error it reported."""
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    run: Run | None = None
    scenario, steps = "?", 0
    while True:
        try:
            frame = framing.receive(conn)
        except SutError as exc:
            _log(f"run {scenario}: connection ended after {steps} steps ({exc})")
            return
        try:
            if frame.kind is Kind.HELLO:
                hello = json.loads(frame.payload)
                scenario = str(hello.get("scenario", "?"))
                run = Run(endpoints, config, hello)
                await_stack(endpoints, config)
                _log(f"run {scenario}: the stack is there (DDS domain {config.domain_id})")
                ready = {"protocol": framing.PROTOCOL_VERSION, "name": NAME, "version": VERSION}
                framing.send(conn, Kind.READY, 0, json.dumps(ready).encode())
            elif frame.kind is Kind.TRAFFIC_COMMAND and run is not None:
                run.target_speed(frame.payload)
            elif frame.kind is Kind.SENSOR_VIEW and run is not None:
                framing.send(conn, Kind.MOTION_REQUEST, frame.sequence, run.step(frame.payload))
                steps += 1
            elif frame.kind is Kind.GOODBYE:
                _log(f"run {scenario}: done after {steps} steps")
                return
            else:
                raise ValueError(f"unexpected {frame.kind.name} frame")
        except (ValueError, KeyError, TypeError) as exc:
            _log(f"run {scenario}: giving up at step {frame.sequence}: {exc}")
            framing.send(conn, Kind.ERROR, frame.sequence, str(exc).encode())
            return


def serve(host: str, port: int, config: BridgeConfig, *, once: bool = False) -> None:
    """Join the DDS domain, then serve runs one after the other."""
    endpoints = Endpoints(config)
    with socket.create_server((host, port)) as server:
        _log(f"{VERSION} listening on {host}:{port}, DDS domain {config.domain_id}")
        while True:
            conn, _ = server.accept()
            with conn:
                serve_connection(conn, endpoints, config)
            if once:
                return


def _profile(reliable: bool, profile: QosProfile) -> QosProfile:
    if not reliable:
        return profile
    return dataclasses.replace(profile, reliability=interfaces.Reliability.RELIABLE)


def parse_args(argv: Sequence[str] | None) -> tuple[argparse.Namespace, BridgeConfig]:
    defaults, tuning = Topics(), BridgeConfig()
    parser = argparse.ArgumentParser(
        description="Bridge the simtest OSI SUT protocol to a ROS 2 stack over DDS."
    )
    parser.add_argument("--host", default=os.environ.get("SIMTEST_SUT_HOST", "127.0.0.1"))
    parser.add_argument(
        "--port",
        type=int,
        default=int(os.environ.get("SIMTEST_SUT_PORT", reference.DEFAULT_PORT)),
    )
    parser.add_argument(
        "--domain-id",
        type=int,
        default=int(os.environ.get("ROS_DOMAIN_ID", "0")),
        help="DDS domain (default: $ROS_DOMAIN_ID, else 0)",
    )
    for name in ("clock", "odometry", "objects", "target_speed", "command"):
        parser.add_argument(f"--{name.replace('_', '-')}-topic", default=getattr(defaults, name))
    parser.add_argument(
        "--command-type", default=defaults.command_type, choices=interfaces.COMMAND_TYPES
    )
    parser.add_argument("--map-frame", default="map")
    parser.add_argument("--base-frame", default="base_link")
    parser.add_argument("--wheelbase", type=float, default=tuning.wheelbase)
    parser.add_argument(
        "--reliable-sensors",
        action="store_true",
        help="publish odometry, objects and /clock reliably (for stacks that subscribe with "
        "the default QoS; a reliable writer serves best-effort readers too)",
    )
    parser.add_argument("--command-timeout", type=float, default=tuning.command_timeout)
    parser.add_argument("--ready-timeout", type=float, default=tuning.ready_timeout)
    parser.add_argument("--once", action="store_true", help="serve one run, then exit")
    args = parser.parse_args(argv)
    config = BridgeConfig(
        domain_id=args.domain_id,
        topics=Topics(
            clock=args.clock_topic,
            odometry=args.odometry_topic,
            objects=args.objects_topic,
            target_speed=args.target_speed_topic,
            command=args.command_topic,
            command_type=args.command_type,
        ),
        frames=converting.Frames(map=args.map_frame, base=args.base_frame),
        sensor_qos=_profile(args.reliable_sensors, interfaces.SENSOR_DATA),
        clock_qos=_profile(args.reliable_sensors, interfaces.CLOCK_QOS),
        wheelbase=args.wheelbase,
        command_timeout=args.command_timeout,
        ready_timeout=args.ready_timeout,
    )
    for topic in (
        args.clock_topic,
        args.odometry_topic,
        args.objects_topic,
        args.target_speed_topic,
        args.command_topic,
    ):
        interfaces.dds_topic(topic)  # refuses a relative or malformed name up front
    return args, config


def main(argv: Sequence[str] | None = None) -> int:
    try:
        args, config = parse_args(argv)
    except ValueError as exc:
        print(f"{NAME}: {exc}", file=sys.stderr)
        return 2
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        serve(args.host, args.port, config, once=args.once)
    except OSError as exc:
        print(f"{NAME}: cannot listen on {args.host}:{args.port}: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0
    return 0
