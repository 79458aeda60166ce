"""simtest-sut-python: a system under test in plain Python for simtest-operator's OSI SUT protocol.

An adaptive cruise control with emergency braking (IDM, latching AEB) that perceives the OSI
SensorView's ground truth and answers each step with an OSI MotionRequest — the same logic as
the Go example (deploy/sut-go). It is written from docs/sut-interface.md alone: OSI messages
through betterosi (the OSI bindings on PyPI), a TCP socket and a 16-byte frame header; it
imports nothing of simtest. Copy it as the start of your own SUT.

    pip install betterosi
    python sut.py [--host 127.0.0.1] [--port 7460]     # defaults: SIMTEST_SUT_HOST / _PORT

One run per connection; after GOODBYE (or a disconnect) it accepts the next run, so it also
serves as a sidecar. It logs one line per run on stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import socket
import struct
import sys
from dataclasses import dataclass, field
from typing import Any

import betterosi

# Frame kinds and header of protocol version 1 (docs/sut-interface.md, "Frames").
HELLO, READY, TRAFFIC_COMMAND, SENSOR_VIEW, MOTION_REQUEST, GOODBYE, ERROR = 1, 2, 3, 4, 5, 7, 8
PROTOCOL = 1
HEADER = struct.Struct(">4sHHII")  # magic, version, kind, sequence, payload length
MAX_PAYLOAD = 64 << 20

DEFAULTS: dict[str, Any] = {
    "desired_speed": None,
    "time_headway": 1.5,
    "min_gap": 2.0,
    "max_acceleration": 2.0,
    "comfortable_deceleration": 3.0,
    "max_deceleration": 8.0,
    "acc": True,
    "aeb": True,
    "aeb_ttc_threshold": 1.5,
    "aeb_deceleration": 8.0,
    "sensor_range": 200.0,
}


def read_exact(conn: socket.socket, size: int) -> bytes:
    data = bytearray()
    while len(data) < size:
        chunk = conn.recv(size - len(data))
        if not chunk:
            raise EOFError("the simulator closed the connection")
        data += chunk
    return bytes(data)


def read_frame(conn: socket.socket) -> tuple[int, int, bytes]:
    magic, version, kind, sequence, length = HEADER.unpack(read_exact(conn, HEADER.size))
    if magic != b"OSUT" or version != PROTOCOL or length > MAX_PAYLOAD:
        raise ValueError(f"bad frame header {magic!r} v{version} ({length} bytes)")
    return kind, sequence, read_exact(conn, length)


def send_frame(conn: socket.socket, kind: int, sequence: int, payload: bytes = b"") -> None:
    conn.sendall(HEADER.pack(b"OSUT", PROTOCOL, kind, sequence, len(payload)) + payload)


@dataclass
class Leader:
    gap: float
    speed: float


@dataclass
class Controller:
    """One run's state: the driver-model parameters, the set speed and the AEB latch."""

    params: dict[str, Any]
    dt: float
    ego_id: int
    set_speed: float = 0.0
    started: bool = False
    requested: float | None = None
    latched: bool = False
    steps: int = field(default=0)

    def perceive(self, view: Any) -> tuple[Any, Leader | None]:
        """The ego and the nearest object whose footprint overlaps the ego's lane ahead."""
        truth = view.global_ground_truth
        host = view.host_vehicle_id.value
        ego = next((o for o in truth.moving_object if o.id.value == host), None)
        if ego is None:
            raise ValueError(f"host vehicle {host} not among the moving objects")
        base = ego.base
        yaw = base.orientation.yaw
        cos, sin = math.cos(yaw), math.sin(yaw)
        best: Leader | None = None
        for other in truth.moving_object:
            if other is ego:
                continue
            ob = other.base
            dx, dy = ob.position.x - base.position.x, ob.position.y - base.position.y
            along, across = dx * cos + dy * sin, -dx * sin + dy * cos
            rel = ob.orientation.yaw - yaw
            half_l, half_w = ob.dimension.length / 2, ob.dimension.width / 2
            extent_along = abs(half_l * math.cos(rel)) + abs(half_w * math.sin(rel))
            extent_across = abs(half_l * math.sin(rel)) + abs(half_w * math.cos(rel))
            if abs(across) >= base.dimension.width / 2 + extent_across:
                continue
            gap = along - base.dimension.length / 2 - extent_along
            if along <= 0 or gap > self.params["sensor_range"] or (best and gap >= best.gap):
                continue
            speed = ob.velocity.x * cos + ob.velocity.y * sin
            best = Leader(gap=max(gap, 0.0), speed=speed)
        return ego, best

    def acceleration(self, speed: float, ahead: Leader | None) -> float:
        """IDM with ACC (cruise control without), overridden by a latching AEB."""
        p = self.params
        ratio = (max(speed, 0.0) / max(self.set_speed, 0.1)) ** 4
        a = p["max_acceleration"] * (1 - ratio)
        if ahead is not None and p["acc"]:
            closing = speed - ahead.speed
            braking = math.sqrt(p["max_acceleration"] * p["comfortable_deceleration"])
            wanted = p["min_gap"] + max(
                0.0, speed * p["time_headway"] + speed * closing / (2 * braking)
            )
            a = p["max_acceleration"] * (1 - ratio - (wanted / max(ahead.gap, 0.1)) ** 2)
        a = max(a, -p["max_deceleration"])
        if not p["aeb"] or speed <= 0:
            self.latched = False
            return a
        closing = speed - ahead.speed if ahead is not None else 0.0
        ttc = ahead.gap / closing if ahead is not None and closing > 0 else math.inf
        if ttc < p["aeb_ttc_threshold"]:
            self.latched = True
        elif self.latched and (ahead is None or closing <= 0):
            self.latched = False
        return min(a, -p["aeb_deceleration"]) if self.latched else a

    def answer(self, payload: bytes) -> bytes:
        view = betterosi.SensorView.from_binary(payload)
        ego, ahead = self.perceive(view)
        base = ego.base
        speed = math.hypot(base.velocity.x, base.velocity.y)
        if not self.started:
            self.started = True
            self.set_speed = speed if self.requested is None else self.requested
            if self.params["desired_speed"] is not None:
                self.set_speed = self.params["desired_speed"]
        a = self.acceleration(speed, ahead)
        following = max(speed + a * self.dt, 0.0)
        yaw = base.orientation.yaw
        cos, sin = math.cos(yaw), math.sin(yaw)
        travelled = (speed + following) / 2 * self.dt
        nanos = view.timestamp.seconds * 10**9 + view.timestamp.nanos + round(self.dt * 1e9)
        when = betterosi.Timestamp(seconds=nanos // 10**9, nanos=nanos % 10**9)
        request = betterosi.MotionRequest(
            version=view.version,
            timestamp=when,
            motion_request_type=betterosi.MotionRequest.MotionRequestType.DESIRED_STATE,
            desired_state=betterosi.MotionRequest.DesiredState(
                timestamp=when,
                position=betterosi.Vector3d(
                    x=base.position.x + travelled * cos, y=base.position.y + travelled * sin, z=0.0
                ),
                velocity=betterosi.Vector3d(x=following * cos, y=following * sin, z=0.0),
                acceleration=betterosi.Vector3d(x=a * cos, y=a * sin, z=0.0),
            ),
        )
        self.steps += 1
        return request.to_binary()

    def command(self, payload: bytes) -> None:
        """A SpeedAction for our ego changes the set speed (before the first step: its start)."""
        command = betterosi.TrafficCommand.from_binary(payload)
        if command.traffic_participant_id.value != self.ego_id:
            return
        for action in command.action:
            if action.has_field("speed_action"):
                target = action.speed_action.absolute_target_speed
                if self.started:
                    self.set_speed = target
                else:
                    self.requested = target


def serve(conn: socket.socket) -> None:
    """One run: HELLO/READY, then a MotionRequest per SensorView until GOODBYE."""
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    run: Controller | None = None
    scenario = "?"
    while True:
        try:
            kind, sequence, payload = read_frame(conn)
        except EOFError:
            return
        try:
            if kind == HELLO:
                hello = json.loads(payload)
                params = {
                    **DEFAULTS,
                    **{k: v for k, v in hello.get("driverModel", {}).items() if k in DEFAULTS},
                }
                run = Controller(params=params, dt=float(hello["step"]), ego_id=int(hello["egoId"]))
                scenario = str(hello.get("scenario", "?"))
                print(f"sut-python: run {scenario}", file=sys.stderr, flush=True)
                # reset: each HELLO builds a new Controller, so one process serves many runs.
                ready = {
                    "protocol": PROTOCOL,
                    "name": "simtest-sut-python",
                    "version": "1.0.0",
                    "reset": True,
                }
                send_frame(conn, READY, 0, json.dumps(ready).encode())
            elif kind == TRAFFIC_COMMAND and run is not None:
                run.command(payload)
            elif kind == SENSOR_VIEW and run is not None:
                send_frame(conn, MOTION_REQUEST, sequence, run.answer(payload))
            elif kind == GOODBYE:
                return
            else:
                raise ValueError(f"unexpected frame kind {kind}")
        except Exception as exc:  # tell the simulator why, then end the run
            print(f"sut-python: run {scenario}: {exc}", file=sys.stderr, flush=True)
            send_frame(conn, ERROR, sequence, str(exc).encode())
            return


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=os.environ.get("SIMTEST_SUT_HOST", "127.0.0.1"))
    parser.add_argument("--port", type=int, default=int(os.environ.get("SIMTEST_SUT_PORT", "7460")))
    args = parser.parse_args()
    with socket.create_server((args.host, args.port)) as server:
        print(f"sut-python: listening on {args.host}:{args.port}", file=sys.stderr, flush=True)
        while True:
            conn, _ = server.accept()
            with conn:
                serve(conn)


if __name__ == "__main__":
    raise SystemExit(main())
