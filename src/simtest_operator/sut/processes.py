"""Local SUT processes: started with their output kept (bounded), and kept warm by a worker.

Light on purpose (no simulator imports): a worker process creates its :class:`SutProcesses`
before it knows whether any scenario needs an external SUT.
"""

from __future__ import annotations

import os
import subprocess
from collections.abc import Mapping
from pathlib import Path

from simtest_operator.drivermodel import ExternalSut
from simtest_operator.sut.errors import SutError
from simtest_operator.sut.output import BoundedOutput

OUTPUT_TAIL = 400
"""Characters of the SUT's last output quoted in an error."""


class SutProcess:
    """A local SUT process with its output kept (bounded) for errors and the ``sut.log``."""

    def __init__(self, command: tuple[str, ...], env: Mapping[str, str], port: int) -> None:
        self.port = port
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
        tail = self.output.last(OUTPUT_TAIL)
        return f"the SUT process {how}" + (f": {tail}" if tail else "")

    def postmortem(self, wait: float = 1.0) -> str | None:
        """For an error: how the process ended, or, still running, what it said last."""
        fate = self.fate(wait)
        if fate is not None:
            return fate
        tail = self.output.last(OUTPUT_TAIL)
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


_Key = tuple[tuple[str, ...], tuple[tuple[str, str], ...]]


def _key(external: ExternalSut) -> _Key:
    return tuple(external.command), tuple(sorted(external.env.items()))


class SutProcesses:
    """The SUT processes one local worker keeps warm between its runs (``lifetime: worker``).

    A process serves the next run only if the last one ended cleanly and its READY said it
    resets (``"reset": true``: every HELLO starts from scratch); otherwise it is stopped and the
    next run starts a fresh one, so a warm run is judged exactly like a fresh one. Use as a
    context manager (or call :meth:`close`): the worker stops them before it exits.
    """

    __slots__ = ("_warm",)

    def __init__(self) -> None:
        self._warm: dict[_Key, SutProcess] = {}

    def take(self, external: ExternalSut) -> SutProcess | None:
        """The warm process for ``external``, if one is still running."""
        process = self._warm.pop(_key(external), None)
        if process is not None and process.fate() is not None:
            process.stop(None)
            return None
        return process

    def keep(self, external: ExternalSut, process: SutProcess) -> None:
        """Keep ``process`` warm for the next run of the same SUT."""
        stale = self._warm.pop(_key(external), None)
        if stale is not None:
            stale.stop(None)
        self._warm[_key(external)] = process

    def close(self) -> None:
        """Stop every warm process."""
        while self._warm:
            self._warm.popitem()[1].stop(None)

    def __enter__(self) -> SutProcesses:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


__all__ = ["OUTPUT_TAIL", "SutProcess", "SutProcesses"]
