"""A documented test double of the scenario engine, for executor and CLI tests.

:func:`execute` has the engine's signature and runs in worker processes like the real one, but its
behaviour is written into the scenario file itself, as a FileHeader property
``simtest:fake`` (read with the same safe header reader the selection uses)::

    pass                  -> Passed
    fail                  -> Failed (reason names a criterion)
    invalid               -> raises ScenarioError (the executor maps it to Invalid)
    error                 -> Error on every attempt
    error-until:N         -> Error on attempts < N, then Passed (exercises retries)
    crash                 -> the process exits hard (os._exit) mid-run
    hang                  -> sleeps far past any timeout (the executor must kill it)
    sleep:S               -> sleeps S seconds, then Passed
    spawn-hang            -> starts a child process that would outlive a plain kill, then hangs

A missing property means ``pass``. Every run writes a small recording file and log lines, so
output layout and artifact handling are exercised too. The process id is reported as metric
``pid``, so tests can check that a killed worker is really gone and that tasks are spread over
processes. Not for production: the real engine is :mod:`simtest_operator.runner.scenario_execution`.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import headers
from simtest_operator.runner.tasks import ScenarioTask
from simtest_operator.sut.processes import SutProcesses
from simtest_operator.verdicts import ScenarioOutcome, Verdict

PROPERTY = "simtest:fake"


def behaviour(task: ScenarioTask) -> str:
    """The behaviour written in the task's scenario file (default ``pass``)."""
    header = headers.read_header(task.scenario_path)
    return header.properties.get(PROPERTY, "pass").strip()


def execute(task: ScenarioTask, processes: SutProcesses | None = None) -> ScenarioOutcome:
    """Act out the scenario's ``simtest:fake`` behaviour (see the module docstring; it starts no
    SUT, so ``processes`` stays unused)."""
    started = time.monotonic()
    what = behaviour(task)
    sys.stdout.write(f"fake engine: {task.scenario_id} attempt {task.attempt}: {what}\n")
    sys.stdout.flush()
    verdict, reason = Verdict.PASSED, ""
    if what == "fail":
        verdict, reason = Verdict.FAILED, "minTTC 0.80 s < 1.50 s at t=4.20 s"
    elif what == "invalid":
        raise ScenarioError("unsupported element <FakeAction>", file=str(task.scenario_path))
    elif what == "error":
        verdict, reason = Verdict.ERROR, "simulator backend lost its connection"
    elif what.startswith("error-until:"):
        if task.attempt < int(what.split(":", 1)[1]):
            verdict, reason = Verdict.ERROR, f"transient failure on attempt {task.attempt}"
    elif what == "crash":
        sys.stdout.flush()
        os._exit(70)
    elif what == "hang":
        time.sleep(3600)
    elif what.startswith("sleep:"):
        time.sleep(float(what.split(":", 1)[1]))
    elif what == "spawn-hang":
        child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(3600)"])
        (task.out_dir / "child.pid").write_text(str(child.pid))
        time.sleep(3600)
    elif what != "pass":
        raise ScenarioError(f"unknown fake behaviour {what!r}", file=str(task.scenario_path))
    if task.record:
        task.recording_path.write_bytes(b"fake recording of " + task.scenario_id.encode())
    return ScenarioOutcome(
        scenario_id=task.scenario_id,
        verdict=verdict,
        reason=reason,
        metrics={"pid": float(os.getpid()), "minTTC": 2.5},
        simulated_seconds=10.0,
        wall_seconds=time.monotonic() - started,
        attempts=task.attempt,
        versions={"engine": "fake"},
    )
