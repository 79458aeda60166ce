"""Reaching an external SUT for one run: start it (local process) or find it (sidecar,
endpoint), wait until it is ready, hand out a connected :class:`RemotePilot`, clean up.

Readiness is two checks, no sleeps: the SUT accepts the TCP connection (polled) and answers the
HELLO with READY within the start-up timeout. A local process that exits while we wait ends the
wait at once with its exit code and the tail of its output; every SUT error quotes that tail,
and the process's whole output (bounded) becomes the scenario's ``sut.log``; in a pod, what the
sidecars printed during the run (:func:`~simtest_operator.sut.output.take_files`).
"""

from __future__ import annotations

import contextlib
import socket
import sys
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from simtest_operator.drivermodel import ExternalSut, Lifetime
from simtest_operator.settings import SUT_ENDPOINT
from simtest_operator.sut import client
from simtest_operator.sut.errors import SutError
from simtest_operator.sut.output import files_said, take_files
from simtest_operator.sut.processes import OUTPUT_TAIL, SutProcess, SutProcesses

if TYPE_CHECKING:
    from simtest_operator.opendrive import TrafficControl


def free_port() -> int:
    """A loopback port nobody listens on right now (the SUT binds it moments later)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


@contextlib.contextmanager
def open_pilot(
    external: ExternalSut,
    *,
    hello: Mapping[str, Any],
    map_reference: str = "map",
    log: Path | None = None,
    processes: SutProcesses | None = None,
    signals: Sequence[TrafficControl] = (),
) -> Iterator[client.RemotePilot]:
    """A connected, handshaken pilot for one run (SutError when the SUT cannot be reached).

    A SUT process started here leaves what it printed during the run in ``log`` (bounded), and
    so do a pod's sidecars that print into ``external.output_dir``. With ``processes`` and
    ``lifetime: worker`` it may be one already running, and may stay running.
    """
    process: SutProcess | None = None
    pilot: client.RemotePilot | None = None
    warm = processes is not None and external.lifetime is Lifetime.WORKER
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
            if warm and processes is not None:
                process = processes.take(external)
            if process is None:
                port = free_port()
                command = tuple(
                    part.replace("{port}", str(port)).replace("{python}", sys.executable)
                    for part in external.command
                )
                process = SutProcess(command, external.env, port)
            endpoint = f"127.0.0.1:{process.port}"
        try:
            sock = client.connect(
                endpoint,
                timeout=external.startup_timeout,
                alive=process.fate if process is not None else None,
            )
        except SutError as exc:
            if process is not None:
                said = process.output.last(OUTPUT_TAIL)
                if said and said not in str(exc):
                    raise SutError(f"{exc}; the SUT process said last: {said}") from exc
            elif external.output_dir is not None:
                sidecars = files_said(external.output_dir, OUTPUT_TAIL)
                if sidecars:
                    raise SutError(f"{exc}; {sidecars}") from exc
            raise
        pilot = client.RemotePilot(
            sock,
            step_deadline=external.step_deadline,
            perception_range=external.perception_range,
            map_reference=map_reference,
            signals=signals,
        )
        if process is not None:
            pilot.postmortem = process.postmortem
        elif external.output_dir is not None:
            folder = external.output_dir
            pilot.postmortem = lambda: files_said(folder, OUTPUT_TAIL)
        with pilot:
            pilot.handshake(hello, timeout=external.startup_timeout)
            yield pilot
    finally:
        if process is None and external.output_dir is not None and log is not None:
            take_files(external.output_dir, log)
        if process is not None:
            reusable = pilot is not None and not pilot.failed and pilot.identity.resets
            if warm and processes is not None and reusable and process.fate() is None:
                if log is not None:
                    process.output.write(log)
                processes.keep(external, process)
            else:
                process.stop(log)


def reference_command() -> tuple[str, ...]:
    """The command that starts the Python reference SUT with this interpreter."""
    return (sys.executable, "-m", "simtest_operator.sut.reference")


__all__ = ["SutProcesses", "free_port", "open_pilot", "reference_command"]
