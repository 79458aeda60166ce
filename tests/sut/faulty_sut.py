"""A SUT that misbehaves on purpose, for the fault tests: ``python faulty_sut.py MODE [STEP]``.

``python faulty_sut.py MODE STEP resets`` says ``"reset": true`` in READY and serves runs one
after the other (a warm SUT); without it, it serves one run and exits.

Modes: ``kill`` (SIGKILLed at STEP), ``slow`` (answers STEP after 1 s), ``garbage`` (answers STEP
with a malformed MotionRequest), ``refuse`` (reports an ERROR at STEP), ``exit`` (exits with
code 3 before listening), ``silent`` (listens but never answers HELLO), ``version`` (speaks
protocol 2). Until STEP it behaves like the reference SUT. It says what it does on stdout and
stderr, as a real SUT logs.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import sys
import time

from simtest_operator.sut import framing, reference
from simtest_operator.sut.framing import Kind


def main() -> None:
    mode = sys.argv[1]
    at = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    print(f"faulty SUT: mode {mode} at step {at}", flush=True)
    if mode == "exit":
        print("faulty SUT: licence server unreachable", file=sys.stderr)
        sys.exit(3)
    resets = len(sys.argv) > 3 and sys.argv[3] == "resets"
    port = int(os.environ["SIMTEST_SUT_PORT"])
    with socket.create_server(("127.0.0.1", port)) as server:
        while True:
            conn, _ = server.accept()
            with conn:
                serve(conn, mode, at, resets=resets)
            if not resets:
                return


def serve(conn: socket.socket, mode: str, at: int, *, resets: bool) -> None:
    session: reference.Session | None = None
    while True:
        frame = framing.receive(conn)
        if frame.kind is Kind.HELLO:
            if mode == "silent":
                time.sleep(60)
            hello = json.loads(frame.payload)
            print(f"faulty SUT: run {hello['scenario']}", flush=True)
            session = reference.Session(reference.config_from(hello), dt=hello["step"])
            ready = {"protocol": 2 if mode == "version" else 1, "name": "faulty", "reset": resets}
            framing.send(conn, Kind.READY, 0, json.dumps(ready).encode())
        elif frame.kind is Kind.SENSOR_VIEW and session is not None:
            if frame.sequence == at:
                if mode == "kill":
                    print(f"faulty SUT: crashing at step {at}", file=sys.stderr, flush=True)
                    os.kill(os.getpid(), signal.SIGKILL)
                if mode == "slow":
                    time.sleep(1.0)
                if mode == "garbage":
                    framing.send(conn, Kind.MOTION_REQUEST, at, b"\x22\x40\x00")
                    continue
                if mode == "refuse":
                    framing.send(conn, Kind.ERROR, at, b"planner diverged")
                    continue
            answer = session.answer(frame.payload)
            framing.send(conn, Kind.MOTION_REQUEST, frame.sequence, answer)
        elif frame.kind is Kind.GOODBYE:
            return


if __name__ == "__main__":
    main()
