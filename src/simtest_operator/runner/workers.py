"""Worker processes: long-lived, one scenario at a time, killable as a whole process group.

Why own processes rather than ``concurrent.futures``: libsumo is a per-process singleton, so a
worker may run only one scenario at a time; a hung simulator must be killed at its timeout without
breaking the pool (a ``ProcessPoolExecutor`` whose worker is killed is broken for good); and
imports (SUMO, lxml, numpy, protobuf) cost a second, so workers are reused across scenarios
instead of spawned per scenario. Each worker is started with the ``spawn`` method (no inherited
locks or libsumo state), moves itself into its own process group (so a kill also reaches the
tools it started, e.g. netconvert, and Ctrl-C at the terminal reaches only the parent, which stops
workers in order), and exits on its own when the parent disappears.

Inside a worker, each attempt's stdout/stderr (file descriptors, so SUMO's C++ output too) and
Python logging go to the scenario's log file.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import logging
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import threading
import time
import traceback
from collections.abc import Iterator
from multiprocessing.process import BaseProcess
from pathlib import Path
from typing import Any

from simtest_operator.errors import ScenarioError
from simtest_operator.runner import tasks
from simtest_operator.runner.tasks import ExecuteFn, ScenarioTask
from simtest_operator.sut.processes import SutProcesses
from simtest_operator.verdicts import ScenarioOutcome, Verdict

LOG_FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"
_READY = "ready"
_RESULT = "result"


@dataclasses.dataclass(slots=True, kw_only=True)
class Worker:
    """Parent-side handle of one worker process (mutable: owned by the executor's loop)."""

    process: BaseProcess
    conn: multiprocessing.connection.Connection
    created: float = dataclasses.field(default_factory=time.monotonic)
    """When the process was started (a worker must become ready within a limit)."""
    ready: bool = False
    task: ScenarioTask | None = None
    batch: int = 0
    deadline: float = 0.0
    started: float = 0.0
    """Monotonic time the current task was sent (for its deadline)."""
    sent_at: float = 0.0
    """Epoch time the current task was sent (for timelines)."""
    tasks_done: int = 0

    @classmethod
    def start(cls, execute: ExecuteFn) -> Worker:
        """Spawn a worker that will call ``execute`` for each task it receives."""
        context = multiprocessing.get_context("spawn")
        parent_end, child_end = context.Pipe(duplex=True)
        process = context.Process(
            target=serve, args=(child_end, execute, os.getpid()), name="simtest-worker"
        )
        process.start()
        child_end.close()
        return cls(process=process, conn=parent_end)

    @property
    def pid(self) -> int:
        """The worker's process id."""
        return self.process.pid or 0

    @property
    def busy(self) -> bool:
        """Whether a task is in flight."""
        return self.task is not None

    def send(self, task: ScenarioTask, *, batch: int, now: float, timeout: float) -> None:
        """Hand ``task`` to the (ready, idle) worker and start its clock; OSError when the
        worker is gone (the task then counts as in flight on a lost worker)."""
        self.task, self.batch, self.started, self.deadline = task, batch, now, now + timeout
        self.conn.send(task)

    def receive(self) -> tuple[str, Any] | None:
        """The next message, or None when the worker is gone."""
        try:
            message: tuple[str, Any] = self.conn.recv()
        except (EOFError, OSError):
            return None
        return message

    def kill(self) -> None:
        """Kill the worker and everything in its process group, and reap it."""
        pid = self.pid
        with contextlib.suppress(ProcessLookupError, PermissionError):
            if pid and os.getpgid(pid) == pid:
                os.killpg(pid, signal.SIGKILL)
        with contextlib.suppress(ProcessLookupError):
            self.process.kill()
        self.process.join(timeout=10)
        self.conn.close()

    def request_stop(self) -> None:
        """Ask an idle worker to exit (without waiting; see :meth:`stop`)."""
        with contextlib.suppress(OSError, ValueError):
            self.conn.send(None)

    def stop(self, *, grace: float = 5.0) -> None:
        """Ask an idle worker to exit; kill it if it does not within ``grace`` seconds."""
        self.request_stop()
        self.process.join(timeout=grace)
        if self.process.is_alive():
            self.kill()
        else:
            self.conn.close()

    def exit_description(self) -> str:
        """How the process ended, for an Error reason."""
        self.process.join(timeout=5)
        code = self.process.exitcode
        if code is None:
            return "still running"
        if code < 0:
            try:
                return f"killed by {signal.Signals(-code).name}"
            except ValueError:
                return f"killed by signal {-code}"
        return f"exit code {code}"


# --- inside the worker process ----------------------------------------------------------------


def serve(conn: multiprocessing.connection.Connection, execute: ExecuteFn, parent: int) -> None:
    """Worker main loop: receive tasks, run them, send outcomes (JSON dicts) back."""
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format=LOG_FORMAT)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    conn.send((_READY, os.getpid()))
    # SUT processes kept warm across this worker's scenarios (``lifetime: worker``); they share
    # the worker's process group, so a kill of the worker takes them down too.
    with SutProcesses() as processes:
        while True:
            try:
                task = conn.recv()
            except (EOFError, OSError):
                return
            if task is None:
                # Only the warm SUTs need stopping: skip interpreter finalisation (slow with the
                # simulator's modules loaded) so a retired worker frees its slot at once.
                processes.close()
                sys.stdout.flush()
                sys.stderr.flush()
                conn.close()
                os._exit(0)
            outcome = run_task(execute, task, processes)
            conn.send((_RESULT, outcome.to_json()))


def run_task(
    execute: ExecuteFn, task: ScenarioTask, processes: SutProcesses | None = None
) -> ScenarioOutcome:
    """Run one attempt with its output captured; map exceptions to Invalid or Error."""
    task.out_dir.mkdir(parents=True, exist_ok=True)
    for stale in (tasks.RESULT, tasks.RECORDING, tasks.ENGINE_LOG):
        (task.out_dir / stale).unlink(missing_ok=True)  # an attempt's artifacts are its own
    started = time.monotonic()
    with captured_output(task.log_path, attempt=task.attempt):
        try:
            outcome = execute(task, processes)
        except ScenarioError as exc:
            outcome = _outcome(task, Verdict.INVALID, str(exc), started)
        except Exception as exc:
            traceback.print_exc()
            reason = f"internal error: {type(exc).__name__}: {exc}"
            outcome = _outcome(task, Verdict.ERROR, reason, started)
    return dataclasses.replace(outcome, scenario_id=task.scenario_id, attempts=task.attempt)


def _outcome(task: ScenarioTask, verdict: Verdict, reason: str, started: float) -> ScenarioOutcome:
    return ScenarioOutcome(
        scenario_id=task.scenario_id,
        verdict=verdict,
        reason=reason.splitlines()[0] if reason else "",
        wall_seconds=time.monotonic() - started,
        attempts=task.attempt,
    )


@contextlib.contextmanager
def captured_output(log: Path, *, attempt: int) -> Iterator[None]:
    """Send fd 1 and 2 (Python and native writes) to ``log`` for the duration."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = (os.dup(1), os.dup(2))
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        now = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
        os.write(fd, f"--- attempt {attempt} started {now} (pid {os.getpid()}) ---\n".encode())
        yield
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for handle in (*saved, fd):
            os.close(handle)


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            # The parent died without stopping us: take our process group (and any simulator
            # tool we started) down with us rather than running on as an orphan.
            if os.getpgid(0) == os.getpid():
                with contextlib.suppress(OSError):
                    os.killpg(0, signal.SIGKILL)
            os._exit(1)
