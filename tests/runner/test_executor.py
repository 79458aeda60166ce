"""The local executor with the fake engine in real worker processes.

Covers: all verdict kinds come back with attempts and output captured in the log; work is spread
over ``parallel`` processes and workers are reused; a hung scenario ends as Timeout at the limit
and its worker process group (including a grandchild) is really killed; a crashing worker becomes
Error and the run continues; only Error is retried (up to ``retries``, then final), Failed and
Timeout never; the barrier policy never overlaps batches; the stop event kills in-flight work and
returns the rest as unfinished; workers that cannot even start abort the run after three tries.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from simtest_operator.errors import SimulationError
from simtest_operator.runner import fakes, scheduling
from simtest_operator.runner.tasks import ScenarioTask
from simtest_operator.scenarios import ExecutionPolicy, PinnedScenario, StartPolicy, batching
from simtest_operator.settings import Settings
from simtest_operator.verdicts import Verdict
from tests.runner.support import alive, write_scenarios

pytestmark = pytest.mark.timeout(60)


def factory(tmp_path: Path, pins: list[PinnedScenario]) -> scheduling.TaskFactory:
    paths = {p.id: Path(p.source.removeprefix("file://")) for p in pins}
    settings = Settings.from_env({"HOME": str(tmp_path)})

    def make(pinned: PinnedScenario, attempt: int) -> ScenarioTask:
        return ScenarioTask(
            scenario_id=pinned.id, scenario_path=paths[pinned.id],
            out_dir=tmp_path / "out" / pinned.id, attempt=attempt, settings=settings,
        )  # fmt: skip

    return make


def run(
    tmp_path: Path,
    behaviours: dict[str, str],
    *,
    parallel: int = 2,
    policy: ExecutionPolicy | None = None,
    stop: threading.Event | None = None,
) -> tuple[scheduling.ExecutionResult, list[scheduling.Event]]:
    pins = write_scenarios(tmp_path / "scenarios", behaviours)
    policy = policy or ExecutionPolicy(batch_size=10, timeout_seconds=20, retries=2)
    events: list[scheduling.Event] = []
    executor = scheduling.Executor(
        fakes.execute, policy=policy, parallel=parallel, make_task=factory(tmp_path, pins),
        on_event=events.append, stop=stop,
    )  # fmt: skip
    result = executor.run(batching.plan(pins, batch_size=policy.batch_size))
    return result, events


def verdicts(result: scheduling.ExecutionResult) -> dict[str, Verdict]:
    return {f.outcome.scenario_id.removesuffix(".xosc"): f.outcome.verdict for f in result.finished}


def test_verdicts_attempts_logs_and_worker_reuse(tmp_path: Path) -> None:
    behaviours = {"p1": "sleep:0.3", "p2": "sleep:0.3", "p3": "sleep:0.3", "p4": "sleep:0.3",
                  "f": "fail", "i": "invalid"}  # fmt: skip
    result, events = run(tmp_path, behaviours, parallel=2)
    assert verdicts(result) == {"p1": Verdict.PASSED, "p2": Verdict.PASSED, "p3": Verdict.PASSED,
                                "p4": Verdict.PASSED, "f": Verdict.FAILED,
                                "i": Verdict.INVALID}  # fmt: skip
    assert not result.interrupted and result.unfinished == ()
    assert result.workers_started == 2, "two workers served six scenarios"
    pids = {e.pid for e in events if isinstance(e, scheduling.Started)}
    assert len(pids) == 2
    invalid = next(f for f in result.finished if f.outcome.verdict is Verdict.INVALID)
    assert "unsupported element <FakeAction>" in invalid.outcome.reason
    log = (tmp_path / "out/p1.xosc/log.txt").read_text()
    assert "--- attempt 1 started" in log and "fake engine: p1.xosc attempt 1: sleep:0.3" in log
    assert (tmp_path / "out/p1.xosc/recording.mcap").exists()


def test_timeout_really_kills_the_process_group(tmp_path: Path) -> None:
    policy = ExecutionPolicy(batch_size=10, timeout_seconds=1.5, retries=2)
    started = time.monotonic()
    result, events = run(tmp_path, {"hang": "spawn-hang", "ok": "pass"}, policy=policy)
    elapsed = time.monotonic() - started
    assert verdicts(result) == {"hang": Verdict.TIMEOUT, "ok": Verdict.PASSED}
    timeout = next(f.outcome for f in result.finished if f.outcome.verdict is Verdict.TIMEOUT)
    assert "no result within 1.5 s" in timeout.reason and timeout.attempts == 1, "not retried"
    assert 1.4 <= timeout.wall_seconds < 5
    assert elapsed < 15
    worker_pid = next(e.pid for e in events if isinstance(e, scheduling.Started)
                      and e.scenario_id == "hang.xosc")  # fmt: skip
    child_pid = int((tmp_path / "out/hang.xosc/child.pid").read_text())
    deadline = time.monotonic() + 5
    while (alive(worker_pid) or alive(child_pid)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(worker_pid), "the hung worker is gone"
    assert not alive(child_pid), "and so is the process it started"


def test_crash_is_error_and_retries_only_error(tmp_path: Path) -> None:
    behaviours = {"crash": "crash", "flaky": "error-until:3", "broken": "error",
                  "fail": "fail", "ok": "pass"}  # fmt: skip
    result, events = run(tmp_path, behaviours)
    outcomes = {f.outcome.scenario_id.removesuffix(".xosc"): f.outcome for f in result.finished}
    assert outcomes["crash"].verdict is Verdict.ERROR
    assert "died (exit code 70)" in outcomes["crash"].reason
    assert outcomes["crash"].attempts == 3
    assert (outcomes["flaky"].verdict, outcomes["flaky"].attempts) == (Verdict.PASSED, 3)
    assert (outcomes["broken"].verdict, outcomes["broken"].attempts) == (Verdict.ERROR, 3)
    assert (outcomes["fail"].verdict, outcomes["fail"].attempts) == (Verdict.FAILED, 1)
    retried = [e.outcome.scenario_id for e in events if isinstance(e, scheduling.Retrying)]
    assert sorted(retried) == sorted(["crash.xosc"] * 2 + ["flaky.xosc"] * 2 + ["broken.xosc"] * 2)
    assert outcomes["ok"].verdict is Verdict.PASSED
    log = (tmp_path / "out/flaky.xosc/log.txt").read_text()
    assert [f"--- attempt {n} started" in log for n in (1, 2, 3)] == [True, True, True]


def test_barrier_policy_never_overlaps_batches(tmp_path: Path) -> None:
    behaviours = {f"s{i}": "sleep:0.2" for i in range(6)}
    policy = ExecutionPolicy(batch_size=3, policy=StartPolicy.BARRIER, timeout_seconds=20)
    result, events = run(tmp_path, behaviours, parallel=2, policy=policy)
    assert all(v is Verdict.PASSED for v in verdicts(result).values())
    open_batches: dict[int, int] = {}
    for event in events:
        if isinstance(event, scheduling.Started):
            assert all(n == 0 for b, n in open_batches.items() if b != event.batch), event
            open_batches[event.batch] = open_batches.get(event.batch, 0) + 1
        elif isinstance(event, scheduling.Finished):
            open_batches[event.batch] -= 1


def test_stop_event_kills_and_returns_unfinished(tmp_path: Path) -> None:
    stop = threading.Event()
    behaviours = {"a": "pass", "b": "hang", "c": "hang", "d": "pass", "e": "pass"}
    pins_started: list[int] = []

    def stopper() -> None:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not (tmp_path / "out/c.xosc/log.txt").exists():
            time.sleep(0.05)
        time.sleep(0.3)
        stop.set()

    thread = threading.Thread(target=stopper)
    thread.start()
    result, events = run(tmp_path, behaviours, parallel=2, stop=stop)
    thread.join()
    assert result.interrupted
    assert verdicts(result) == {"a": Verdict.PASSED}
    assert sorted(p.id for _, p in result.unfinished) == ["b.xosc", "c.xosc", "d.xosc", "e.xosc"]
    pins_started = [e.pid for e in events if isinstance(e, scheduling.Started)]
    time.sleep(0.2)
    assert not any(alive(pid) for pid in pins_started), "no worker outlives the run"


def test_workers_that_cannot_start_abort_the_run(tmp_path: Path) -> None:
    from tests.runner import broken_engine

    pins = write_scenarios(tmp_path / "scenarios", {"a": "pass"})
    executor = scheduling.Executor(
        broken_engine.execute, policy=ExecutionPolicy(), parallel=1,
        make_task=factory(tmp_path, pins),
    )  # fmt: skip
    with pytest.raises(SimulationError, match="3 worker processes in a row died while starting"):
        executor.run(batching.plan(pins, batch_size=10))
