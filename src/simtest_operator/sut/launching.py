"""Reaching an external SUT for one run: start it (local process) or find it (sidecar,
endpoint), wait until it is ready, hand out a connected :class:`RemotePilot`, clean up.

Readiness is two checks, no sleeps: the SUT accepts the TCP connection (polled) and answers the
HELLO with READY within the start-up timeout. A local process that exits while we wait ends the
wait at once with its exit code and the tail of its output; every SUT error quotes that tail,
and the process's whole output (bounded) becomes the scenario's ``sut.log``.
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from simtest_operator.drivermodel import ExternalSut
from simtest_operator.settings import SUT_ENDPOINT
from simtest_operator.sut import client
from simtest_operator.sut.errors import SutError
from simtest_operator.sut.output import BoundedOutput

_OUTPUT_TAIL = 400
"""Characters of the SUT's last output quoted in an error."""


def free_port() -> int:
    """A loopback port nobody listens on right now (the SUT binds it moments later)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class _Process:
    """A local SUT process with its output kept (bounded) for errors and the ``sut.log``."""

    def __init__(self, command: tuple[str, ...], env: Mapping[str, str], port: int) -> None:
        environment = {
            **os.environ,
            **env,
            "SIMTEST_SUT_HOST": "127.0.0.1",
            "SIMTEST_SUT_PORT": str(port),
        }
        try:
            self.process = subprocess.Popen(
                command,
                env=environment,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
            )
        except OSError as exc:
            raise SutError(f"cannot start the SUT {command[0]!r}: {exc.strerror or exc}") from exc
        self.output = BoundedOutput()
        assert self.process.stdout is not None
        self.output.follow(self.process.stdout)

    def fate(self, wait: float = 0.0) -> str | None:
        """None while it runs (after waiting up to ``wait`` s for it to end: a crashed SUT's
        socket closes a moment before its exit status is there); else how it ended and what
        it said last."""
        try:
            code = self.process.wait(timeout=wait) if wait > 0 else self.process.poll()
        except subprocess.TimeoutExpired:
            code = None
        if code is None:
            return None
        self.output.finish()
        how = f"killed by signal {-code}" if code < 0 else f"exited with code {code}"
        tail = self.output.last(_OUTPUT_TAIL)
        return f"the SUT process {how}" + (f": {tail}" if tail else "")

    def postmortem(self, wait: float = 1.0) -> str | None:
        """For an error: how the process ended, or, still running, what it said last."""
        fate = self.fate(wait)
        if fate is not None:
            return fate
        tail = self.output.last(_OUTPUT_TAIL)
        return f"the SUT process is running; it said last: {tail}" if tail else None

    def stop(self, log: Path | None) -> None:
        """End the process (TERM, then KILL after 3 s) and keep its output in ``log``."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=3)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.output.finish()
        if log is not None:
            self.output.write(log)


@contextlib.contextmanager
def open_pilot(
    external: ExternalSut,
    *,
    hello: Mapping[str, Any],
    map_reference: str = "map",
    log: Path | None = None,
) -> Iterator[client.RemotePilot]:
    """A connected, handshaken pilot for one run (SutError when the SUT cannot be reached).

    A SUT process started here leaves what it printed in ``log`` (bounded) when the run ends.
    """
    process: _Process | None = None
    # A pod's SIMTEST_SUT_ENDPOINT is already in ``endpoint``: the run request applied the
    # settings (runner.suts.reached_here); nothing here reads the environment.
    endpoint = external.endpoint
    try:
        if endpoint is None:
            if not external.command:
                raise SutError(
                    f"the {external.launch} SUT has no command to start here "
                    f"(and {SUT_ENDPOINT} is not set)"
                )
            port = free_port()
            command = tuple(
                part.replace("{port}", str(port)).replace("{python}", sys.executable)
                for part in external.command
            )
            process = _Process(command, external.env, port)
            endpoint = f"127.0.0.1:{port}"
        try:
            sock = client.connect(
                endpoint,
                timeout=external.startup_timeout,
                alive=process.fate if process is not None else None,
            )
        except SutError as exc:
            said = process.output.last(_OUTPUT_TAIL) if process is not None else ""
            if said and said not in str(exc):
                raise SutError(f"{exc}; the SUT process said last: {said}") from exc
            raise
        pilot = client.RemotePilot(
            sock,
            step_deadline=external.step_deadline,
            perception_range=external.perception_range,
            map_reference=map_reference,
        )
        if process is not None:
            pilot.postmortem = process.postmortem
        with pilot:
            pilot.handshake(hello, timeout=external.startup_timeout)
            yield pilot
    finally:
        if process is not None:
            process.stop(log)


def reference_command() -> tuple[str, ...]:
    """The command that starts the Python reference SUT with this interpreter."""
    return (sys.executable, "-m", "simtest_operator.sut.reference")


__all__ = ["free_port", "open_pilot", "reference_command"]
