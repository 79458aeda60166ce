"""The local executor: a window of worker processes fed from the frozen list.

One scheduling loop in the parent keeps up to ``parallel`` scenarios in flight, refilling a slot
the moment it frees (or, with the barrier policy, only when the whole previous batch is done),
enforces each attempt's wall-clock limit by killing the worker's process group (verdict
``Timeout``), turns a worker that died into ``Error``, retries ``Error`` and nothing else up to
the policy's ``retries``, and reports every step through a callback. A stop event (Ctrl-C) kills
in-flight work and hands back what did not finish, so the caller can mark it as not run.

The loop owns all mutable state; workers are replaced rather than repaired.
"""

from __future__ import annotations

import collections
import dataclasses
import multiprocessing.connection
import threading
import time
from collections.abc import Callable, Sequence
from typing import Protocol

from simtest_operator.errors import SimulationError
from simtest_operator.runner.tasks import ExecuteFn, ScenarioTask
from simtest_operator.runner.workers import Worker
from simtest_operator.scenarios.batching import Batch, Dispatcher, ExecutionPolicy
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.verdicts import ScenarioOutcome, Verdict

POLL_SECONDS = 0.2
"""Longest wait between checks of the stop event and deadlines."""
STARTUP_TIMEOUT = 120.0
"""Seconds a new worker may take to import the engine and report ready."""
MAX_STARTUP_FAILURES = 3
"""Workers that may die before becoming ready, in a row, before the run gives up."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Started:
    """An attempt was handed to a worker."""

    scenario_id: str
    batch: int
    attempt: int
    pid: int


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Retrying:
    """An attempt ended with Error and will be tried again."""

    outcome: ScenarioOutcome
    batch: int


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Timing:
    """When the final attempt ran (epoch seconds) and on which worker process."""

    started: float
    finished: float
    pid: int


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Finished:
    """A scenario's final outcome."""

    outcome: ScenarioOutcome
    batch: int
    pinned: PinnedScenario
    timing: Timing | None = None
    """None when the scenario never reached a worker (its file could not be located)."""


Event = Started | Retrying | Finished
TaskFactory = Callable[[PinnedScenario, int], ScenarioTask]
"""Builds the task for (scenario, attempt number)."""


class Feed(Protocol):
    """Where the executor takes its work from: the frozen list's batches
    (:class:`~simtest_operator.scenarios.batching.Dispatcher`) or a search proposing as results
    come back (:class:`~simtest_operator.runner.searching.SearchFeed`)."""

    def next(self) -> tuple[int, PinnedScenario] | None:
        """The next scenario to start with its batch index, or None for now."""
        ...

    def done(self, batch: int) -> None:
        """A scenario of ``batch`` has its final outcome."""
        ...

    def drain(self) -> list[tuple[int, PinnedScenario]]:
        """Everything not handed out yet (to mark it as not run)."""
        ...

    @property
    def exhausted(self) -> bool:
        """Nothing more will be handed out, now or later."""
        ...


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ExecutionResult:
    """What the loop did."""

    finished: tuple[Finished, ...]
    unfinished: tuple[tuple[int, PinnedScenario], ...]
    """(batch, scenario) not finished because the run was stopped."""
    interrupted: bool
    workers_started: int


@dataclasses.dataclass(slots=True, kw_only=True)
class _Item:
    batch: int
    pinned: PinnedScenario
    attempt: int = 1


class Executor:
    """Runs batches of pinned scenarios on local worker processes."""

    def __init__(
        self,
        execute: ExecuteFn,
        *,
        policy: ExecutionPolicy,
        parallel: int,
        make_task: TaskFactory,
        on_event: Callable[[Event], None] = lambda event: None,
        stop: threading.Event | None = None,
        max_tasks_per_worker: int = 200,
        clock: Callable[[], float] = time.monotonic,
        wall_clock: Callable[[], float] = time.time,
        workers: Sequence[Worker] = (),
    ) -> None:
        """``workers`` may hand over processes started earlier (their imports then overlap with
        the caller's preparation); any beyond ``parallel`` are stopped."""
        if parallel < 1:
            raise ValueError("parallel must be at least 1")
        self._execute = execute
        self._policy = policy
        self._parallel = parallel
        self._make_task = make_task
        self._on_event = on_event
        self._stop = stop or threading.Event()
        self._max_tasks = max_tasks_per_worker
        self._clock = clock
        self._wall_clock = wall_clock
        self._workers: list[Worker] = list(workers[:parallel])
        self._retired: list[Worker] = list(workers[parallel:])
        for surplus in self._retired:
            surplus.request_stop()
        self._retries: collections.deque[_Item] = collections.deque()
        self._finished: list[Finished] = []
        self._started_workers = len(workers)
        self._startup_failures = 0
        self._pinned: dict[str, PinnedScenario] = {}

    def run(self, batches: Sequence[Batch]) -> ExecutionResult:
        """Run every scenario of ``batches``; returns when all finished or the stop event is set."""
        return self.run_feed(Dispatcher(tuple(batches), self._policy.policy))

    def run_feed(self, dispatcher: Feed) -> ExecutionResult:
        """Run what ``dispatcher`` hands out until it is exhausted and every scenario finished,
        or the stop event is set."""
        try:
            while not self._stop.is_set():
                self._fill(dispatcher)
                idle = not any(w.busy for w in self._workers) and not self._retries
                if idle and dispatcher.exhausted:
                    break
                self._wait_and_collect(dispatcher)
        finally:
            unfinished = self._shutdown(dispatcher)
        return ExecutionResult(
            finished=tuple(self._finished),
            unfinished=unfinished,
            interrupted=self._stop.is_set() and bool(unfinished),
            workers_started=self._started_workers,
        )

    # --- scheduling -----------------------------------------------------------------------------

    def _fill(self, dispatcher: Feed) -> None:
        busy = sum(1 for w in self._workers if w.busy)
        pending = len(self._retries) + (0 if dispatcher.exhausted else self._parallel)
        wanted = min(self._parallel, busy + pending)
        while len(self._workers) < wanted:
            self._workers.append(Worker.start(self._execute))
            self._started_workers += 1
        for worker in list(self._workers):
            if not worker.ready or worker.busy:
                continue
            item = self._next_item(dispatcher)
            if item is None:
                return
            task = self._make_task(item.pinned, item.attempt)
            now = self._clock()
            worker.sent_at = self._wall_clock()
            try:
                worker.send(task, batch=item.batch, now=now, timeout=self._policy.timeout_seconds)
            except OSError:
                self._lost(worker, dispatcher)
                continue
            started = Started(
                scenario_id=item.pinned.id, batch=item.batch, attempt=item.attempt, pid=worker.pid
            )
            self._on_event(started)

    def _next_item(self, dispatcher: Feed) -> _Item | None:
        if self._retries:
            return self._retries.popleft()
        handed = dispatcher.next()
        if handed is None:
            return None
        self._pinned[handed[1].id] = handed[1]
        return _Item(batch=handed[0], pinned=handed[1])

    def _wait_and_collect(self, dispatcher: Feed) -> None:
        now = self._clock()
        deadlines = [w.deadline for w in self._workers if w.busy]
        timeout = min([POLL_SECONDS, *(max(0.0, d - now) for d in deadlines)])
        handles = [w.conn for w in self._workers] + [w.process.sentinel for w in self._workers]
        ready = multiprocessing.connection.wait(handles, timeout=timeout)
        for worker in list(self._workers):
            if worker.conn in ready:
                message = worker.receive()
                if message is None:
                    self._lost(worker, dispatcher)
                elif message[0] == "ready":
                    worker.ready = True
                    self._startup_failures = 0
                else:
                    self._result(worker, ScenarioOutcome.from_json(message[1]), dispatcher)
            elif worker.process.sentinel in ready and not worker.conn.poll():
                self._lost(worker, dispatcher)
        now = self._clock()
        for worker in list(self._workers):
            if worker.busy and now >= worker.deadline:
                self._timed_out(worker, dispatcher)
            elif not worker.ready and time.monotonic() - worker.created > STARTUP_TIMEOUT:
                self._lost(worker, dispatcher)  # stuck while importing: counts as a failed start

    # --- outcomes -------------------------------------------------------------------------------

    def _result(self, worker: Worker, outcome: ScenarioOutcome, dispatcher: Feed) -> None:
        task, batch = worker.task, worker.batch
        assert task is not None
        worker.task = None
        worker.tasks_done += 1
        if outcome.verdict is Verdict.ERROR or worker.tasks_done >= self._max_tasks:
            self._retire(worker)  # an errored engine may be in a bad state: start afresh
        self._conclude(task, batch, outcome, dispatcher, self._timing(worker))

    def _lost(self, worker: Worker, dispatcher: Feed) -> None:
        task, batch = worker.task, worker.batch
        self._workers.remove(worker)
        description = worker.exit_description()
        worker.kill()
        if not worker.ready:
            self._startup_failures += 1
            if self._startup_failures >= MAX_STARTUP_FAILURES:
                raise SimulationError(
                    f"{self._startup_failures} worker processes in a row died while starting "
                    f"(last: {description}); see the messages above"
                )
        if task is None:
            return
        reason = f"simulator process {worker.pid} died ({description})"
        outcome = ScenarioOutcome(
            scenario_id=task.scenario_id,
            verdict=Verdict.ERROR,
            reason=reason,
            wall_seconds=self._clock() - worker.started,
            attempts=task.attempt,
        )
        self._conclude(task, batch, outcome, dispatcher, self._timing(worker))

    def _timed_out(self, worker: Worker, dispatcher: Feed) -> None:
        task, batch = worker.task, worker.batch
        assert task is not None
        self._workers.remove(worker)
        worker.kill()
        limit = self._policy.timeout_seconds
        outcome = ScenarioOutcome(
            scenario_id=task.scenario_id,
            verdict=Verdict.TIMEOUT,
            reason=f"no result within {limit:g} s wall time; simulator process {worker.pid} killed",
            wall_seconds=self._clock() - worker.started,
            attempts=task.attempt,
        )
        self._conclude(task, batch, outcome, dispatcher, self._timing(worker))

    def _timing(self, worker: Worker) -> Timing:
        return Timing(started=worker.sent_at, finished=self._wall_clock(), pid=worker.pid)

    def _conclude(
        self,
        task: ScenarioTask,
        batch: int,
        outcome: ScenarioOutcome,
        dispatcher: Feed,
        timing: Timing,
    ) -> None:
        pinned = self._pinned_of(task)
        if outcome.verdict.retriable and task.attempt <= self._policy.retries:
            self._on_event(Retrying(outcome=outcome, batch=batch))
            self._retries.append(_Item(batch=batch, pinned=pinned, attempt=task.attempt + 1))
            return
        dispatcher.done(batch)
        finished = Finished(outcome=outcome, batch=batch, pinned=pinned, timing=timing)
        self._finished.append(finished)
        self._on_event(finished)

    def _pinned_of(self, task: ScenarioTask) -> PinnedScenario:
        return self._pinned[task.scenario_id]

    def _retire(self, worker: Worker) -> None:
        self._workers.remove(worker)
        worker.request_stop()
        self._retired.append(worker)  # reaped at shutdown; it exits on its own right away

    # --- shutdown -------------------------------------------------------------------------------

    def _shutdown(self, dispatcher: Feed) -> tuple[tuple[int, PinnedScenario], ...]:
        unfinished: list[tuple[int, PinnedScenario]] = []
        for worker in self._workers:
            if worker.busy:
                assert worker.task is not None
                unfinished.append((worker.batch, self._pinned_of(worker.task)))
                worker.kill()
            else:
                worker.request_stop()
                self._retired.append(worker)
        for worker in self._retired:
            worker.stop()
        self._retired.clear()
        self._workers.clear()
        unfinished.extend((item.batch, item.pinned) for item in self._retries)
        self._retries.clear()
        unfinished.extend(dispatcher.drain())
        return tuple(unfinished)
