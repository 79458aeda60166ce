"""The reference SUT: the built-in driver model (IDM + ACC + AEB) behind the OSI SUT protocol.

It is the example to copy for a SUT of your own, and what proves the protocol carries all a
driver model needs: run it as a process (``python -m simtest_operator.sut.reference``, or the
``simtest-sut-reference`` entry in the runner image) and point ``spec.environment.sut.external``
at it. Perception comes from the SensorView's ground truth only: the nearest object ahead in the
ego's straight corridor within the sensor range (the in-process model also follows the road's
curvature through the simulator's lane coordinates, which the SensorView does not carry).
Laterally it holds the lane (the simulator's vehicle model follows the lane; no steering).

Configuration arrives in HELLO: ``driverModel`` holds
:class:`~simtest_operator.drivermodel.SutConfig` fields (snake_case) and overrides the defaults.
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
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator import geometry
from simtest_operator.drivermodel import DriverModel, Leader, SutConfig
from simtest_operator.recording import osiwire
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState
from simtest_operator.sut import framing
from simtest_operator.sut import protowire as pw
from simtest_operator.sut.errors import SutError
from simtest_operator.sut.framing import Kind

NAME = "simtest-reference-sut"
VERSION = "1.0.0"
DEFAULT_PORT = 7460


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Perceived:
    """One moving object of the SensorView's ground truth."""

    state: EntityState
    vx: float
    vy: float
    ax: float = 0.0
    ay: float = 0.0
    object_type: int = 0
    """OSI ``MovingObject.Type`` (2 vehicle, 3 pedestrian, 4 animal, 1 other)."""
    vehicle_class: int = 0
    """OSI ``VehicleClassification.Type`` of a vehicle (4 car, 7 heavy truck, ...)."""


def parse_sensor_view(payload: bytes) -> tuple[int, int, list[Perceived]]:
    """(timestamp ns, host vehicle id, moving objects) of a SensorView."""
    view = pw.message_fields(payload)
    nanos = pw.timestamp_nanos(pw.sub_message(view, 2)) or 0
    host = pw.sub_message(view, 8)
    truth = pw.sub_message(view, 7)
    if truth is None:
        raise ValueError("SensorView without global_ground_truth")
    fields = pw.message_fields(truth)
    if host is None:
        host = pw.sub_message(fields, 3)
    if host is None:
        raise ValueError("SensorView without host_vehicle_id")
    host_id = pw.integer(pw.message_fields(host), 1, 0)
    objects: list[Perceived] = []
    for raw in fields.get(5, []):
        if not isinstance(raw, bytes):
            raise ValueError("moving_object should be a message")
        moving = pw.message_fields(raw)
        ident = pw.sub_message(moving, 1)
        base = pw.sub_message(moving, 2)
        if ident is None or base is None:
            raise ValueError("moving_object without id or base")
        b = pw.message_fields(base)
        length, width, height = pw.vector(pw.sub_message(b, 1)) or (0.0, 0.0, 0.0)
        x, y, z = pw.vector(pw.sub_message(b, 2)) or (0.0, 0.0, 0.0)
        roll, pitch, yaw = pw.vector(pw.sub_message(b, 3)) or (0.0, 0.0, 0.0)
        vx, vy, _ = pw.vector(pw.sub_message(b, 4)) or (0.0, 0.0, 0.0)
        ax, ay, _ = pw.vector(pw.sub_message(b, 5)) or (0.0, 0.0, 0.0)
        object_id = pw.integer(pw.message_fields(ident), 1, 0)
        classification = pw.sub_message(moving, 6)
        state = EntityState(
            id=object_id,
            name=str(object_id),
            kind=EntityKind.VEHICLE,
            category="car",
            x=x,
            y=y,
            z=z,
            heading=yaw,
            roll=roll,
            pitch=pitch,
            speed=math.hypot(vx, vy),
            box=BoundingBox(length=length, width=width, height=height),
        )
        objects.append(
            Perceived(
                state=state,
                vx=vx,
                vy=vy,
                ax=ax,
                ay=ay,
                object_type=pw.integer(moving, 3, 0),
                vehicle_class=(
                    pw.integer(pw.message_fields(classification), 1, 0)
                    if classification is not None
                    else 0
                ),
            )
        )
    return nanos, host_id, objects


def parse_target_speed(payload: bytes, ego_id: int) -> float | None:
    """The last SpeedAction's target speed for the ego in a TrafficCommand, if any."""
    command = pw.message_fields(payload)
    participant = pw.sub_message(command, 3)
    if participant is not None and pw.integer(pw.message_fields(participant), 1, -1) != ego_id:
        return None
    target: float | None = None
    for raw in command.get(4, []):
        if not isinstance(raw, bytes):
            raise ValueError("action should be a message")
        speed = pw.sub_message(pw.message_fields(raw), 5)
        if speed is not None:
            target = pw.number(pw.message_fields(speed), 2, 0.0)
    return target


def leader(ego: Perceived, others: Sequence[Perceived], sensor_range: float) -> Leader | None:
    """The nearest object ahead in the ego's straight corridor (what a forward sensor sees)."""
    best: Leader | None = None
    c, s = math.cos(ego.state.heading), math.sin(ego.state.heading)
    for other in others:
        if not geometry.in_path(ego.state, other.state):
            continue
        if geometry.longitudinal_gap(ego.state, other.state, freespace=False) <= 0.0:
            continue
        gap = geometry.longitudinal_gap(ego.state, other.state, freespace=True)
        if gap > sensor_range or (best is not None and gap >= best.gap):
            continue
        best = Leader(gap=max(gap, 0.0), speed=other.vx * c + other.vy * s)
    return best


def motion_request(
    *, nanos: int, position: tuple[float, float], yaw: float, speed: float, acceleration: float
) -> bytes:
    """MotionRequest of type DESIRED_STATE for ``nanos``."""
    c, s = math.cos(yaw), math.sin(yaw)
    state = (
        osiwire.length_delimited(1, _timestamp(nanos))
        + osiwire.length_delimited(2, osiwire.triple(position[0], position[1], 0.0))
        + osiwire.length_delimited(3, osiwire.triple(0.0, 0.0, yaw))
        + osiwire.length_delimited(4, osiwire.triple(speed * c, speed * s, 0.0))
        + osiwire.length_delimited(5, osiwire.triple(acceleration * c, acceleration * s, 0.0))
    )
    return (
        osiwire.ground_truth_head(nanos=nanos)
        + osiwire.varint_field(3, 0)
        + osiwire.length_delimited(4, state)
    )


def _timestamp(nanos: int) -> bytes:
    seconds, rest = divmod(nanos, 1_000_000_000)
    return osiwire.varint_field(1, seconds) + osiwire.varint_field(2, rest)


def config_from(hello: Mapping[str, Any]) -> SutConfig:
    """The driver-model configuration a HELLO carries (unknown keys are an error)."""
    raw = hello.get("driverModel") or {}
    if not isinstance(raw, dict):
        raise ValueError("driverModel must be an object")
    known = {f.name for f in dataclasses.fields(SutConfig)} - {"external", "takeover"}
    unknown = sorted(set(raw) - known)
    if unknown:
        raise ValueError(f"unknown driverModel keys {', '.join(unknown)}")
    return SutConfig(**raw)


class Session:
    """The reference SUT's state for one run (one connection)."""

    __slots__ = ("config", "dt", "model", "target")

    def __init__(self, config: SutConfig, *, dt: float) -> None:
        self.config = config
        self.dt = dt
        self.model: DriverModel | None = None
        self.target: float | None = None

    def request(self, target: float) -> None:
        """A scenario speed request (TrafficCommand SpeedAction): the driver's new set speed;
        the first one, before the model exists, is the speed the model starts from (a configured
        desired speed takes precedence there, as in process)."""
        if self.model is None:
            self.target = target
        else:
            self.model.set_speed = target

    def answer(self, sensor_view: bytes) -> bytes:
        """The MotionRequest for one SensorView."""
        nanos, host_id, objects = parse_sensor_view(sensor_view)
        ego = next((o for o in objects if o.state.id == host_id), None)
        if ego is None:
            raise ValueError(f"host vehicle {host_id} is not among the moving objects")
        others = [o for o in objects if o is not ego]
        speed = ego.state.speed
        if self.model is None:
            start = self.target if self.target is not None else speed
            self.model = DriverModel(self.config, set_speed=start)
        command = self.model.command(
            speed=speed, leader=leader(ego, others, self.config.sensor_range)
        )
        dt = self.dt
        next_speed = max(speed + command.acceleration * dt, 0.0)
        yaw = ego.state.heading
        travelled = (speed + next_speed) / 2.0 * dt
        return motion_request(
            nanos=nanos + round(dt * 1e9),
            position=(
                ego.state.x + travelled * math.cos(yaw),
                ego.state.y + travelled * math.sin(yaw),
            ),
            yaw=yaw,
            speed=next_speed,
            acceleration=command.acceleration,
        )


def _log(line: str) -> None:
    """One line of the SUT's own log (stderr: the runner keeps it as the scenario's sut.log)."""
    print(f"reference SUT: {line}", file=sys.stderr, flush=True)


def serve_connection(conn: socket.socket, *, name: str = NAME, version: str = VERSION) -> None:
    """Serve one run; returns when the simulator says GOODBYE or disconnects."""
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    session: Session | None = None
    ego_id = -1
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
                session = Session(config_from(hello), dt=float(hello["step"]))
                ego_id = int(hello.get("egoId", -1))
                scenario = str(hello.get("scenario", "?"))
                _log(f"run {scenario}: ego {ego_id}, step {hello['step']} s")
                # reset: every HELLO builds a new Session, so one process may serve many runs.
                ready = {
                    "protocol": framing.PROTOCOL_VERSION,
                    "name": name,
                    "version": version,
                    "reset": True,
                }
                digest = os.environ.get("SIMTEST_SUT_DIGEST", "")
                if digest:
                    ready["digest"] = digest
                framing.send(conn, Kind.READY, 0, json.dumps(ready).encode())
            elif frame.kind is Kind.TRAFFIC_COMMAND and session is not None:
                target = parse_target_speed(frame.payload, ego_id)
                if target is not None:
                    session.request(target)
            elif frame.kind is Kind.SENSOR_VIEW and session is not None:
                framing.send(
                    conn, Kind.MOTION_REQUEST, frame.sequence, session.answer(frame.payload)
                )
                steps += 1
            elif frame.kind is Kind.GOODBYE:
                return
            else:
                raise ValueError(f"unexpected {frame.kind.name} frame")
        except (ValueError, KeyError, TypeError) as exc:
            _log(f"run {scenario}: giving up at step {frame.sequence}: {exc}")
            framing.send(conn, Kind.ERROR, frame.sequence, str(exc).encode())
            return


def serve(host: str, port: int, *, once: bool = False) -> None:
    """Accept runs one after the other (a sidecar serves every scenario of its pod)."""
    with socket.create_server((host, port), reuse_port=False) as server:
        _log(f"{NAME} {VERSION} listening on {host}:{port}")
        while True:
            conn, _ = server.accept()
            with conn:
                serve_connection(conn)
            if once:
                return


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="The simtest reference SUT (OSI protocol v1).")
    parser.add_argument("--host", default=os.environ.get("SIMTEST_SUT_HOST", "127.0.0.1"))
    parser.add_argument(
        "--port", type=int, default=int(os.environ.get("SIMTEST_SUT_PORT", DEFAULT_PORT))
    )
    parser.add_argument("--once", action="store_true", help="serve one run, then exit")
    args = parser.parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        serve(args.host, args.port, once=args.once)
    except OSError as exc:
        print(f"reference SUT: cannot listen on {args.host}:{args.port}: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
