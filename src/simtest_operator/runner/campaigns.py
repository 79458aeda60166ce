"""A whole campaign on this machine: the action behind ``simtest run``.

Steps: read and validate the manifest (as the API server would) -> take the frozen list (resolve
the sources, or reuse ``--frozen``, an earlier run's failures, or this output folder's own list
when resuming) -> locate every scenario file and verify its sha256 -> open the results store ->
run the scenarios on worker processes (:mod:`scheduling`) writing each final result as it arrives
-> mark what did not run -> write JUnit and the HTML report. The CLI only parses options, shows
progress from the events and prints the returned :class:`LocalRunResult`.
"""

from __future__ import annotations

import dataclasses
import datetime
import os
import resource
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from simtest_operator import recording
from simtest_operator.errors import ResultsError, ScenarioError, SimtestError, SourceError
from simtest_operator.results import details, dsn, publishing, reportmodel
from simtest_operator.runner import (
    localsearch,
    outputs,
    scheduling,
    searchresults,
    storing,
    summaries,
    tasks,
)
from simtest_operator.runner import preparing as prep
from simtest_operator.runner.workers import Worker
from simtest_operator.scenarios import batching
from simtest_operator.scenarios.locating import Locator
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.verdicts import ScenarioOutcome, Verdict

NOT_RUN_REASON = "not run: the campaign was interrupted before this scenario finished"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Prepared:
    """Event: the run is about to start."""

    campaign: str
    output: Path
    total: int
    finished: int
    """Scenarios already finished (resumed run)."""
    parallel: int
    store: str
    notes: tuple[str, ...]
    resumed: bool


Event = Prepared | scheduling.Event


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LocalRunResult:
    """What the run produced."""

    output: Path
    summary: summaries.Summary
    interrupted: bool
    parallel: int
    wall_seconds: float
    worker_cpu_seconds: float
    """CPU time of the worker processes (user + system), for utilisation figures."""
    engine_seconds: float
    """Sum of the attempts' wall times as measured inside the workers (this run only)."""
    scenarios_run: int
    """Attempts made by this invocation (0 when everything had finished before)."""
    run_key: str
    report: Path | None
    junit: Path | None
    warnings: tuple[str, ...]
    not_passed: tuple[ScenarioOutcome, ...]
    """Final outcomes other than Passed, in frozen-list order (including earlier runs')."""
    search: localsearch.Searched | None = None
    """What the search found (``spec.search``)."""


def run(
    request: prep.LocalRunRequest,
    *,
    on_event: Callable[[Event], None] = lambda event: None,
    stop: threading.Event | None = None,
    now: Callable[[], datetime.datetime] = lambda: datetime.datetime.now(datetime.UTC),
) -> LocalRunResult:
    """Run the campaign; raises ScenarioError (bad manifest, sources, output folder) before
    anything runs."""
    stop = stop or threading.Event()
    started = time.monotonic()
    # Start the workers first: their imports (the simulator stack, about a second) overlap with
    # reading the manifest and resolving the sources.
    early = [Worker.start(request.execute) for _ in range(request.parallel or request.cpu_count)]
    try:
        return _run(request, on_event=on_event, stop=stop, now=now, started=started, early=early)
    finally:
        for worker in early:  # only those the executor never took over are still open
            if worker.process.is_alive() and not worker.conn.closed:
                worker.stop()


def _run(
    request: prep.LocalRunRequest,
    *,
    on_event: Callable[[Event], None],
    stop: threading.Event,
    now: Callable[[], datetime.datetime],
    started: float,
    early: list[Worker],
) -> LocalRunResult:
    if request.database:
        dsn.classify(request.database)  # refuse an ambiguous --db before the output is written
    plan = prep.prepare(request, now=now())
    try:
        return _run_planned(request, plan, on_event=on_event, stop=stop, now=now, started=started,
                            early=early)  # fmt: skip
    except SimtestError as exc:
        # The output exists by now: campaign.json must not keep saying "running" (issue 12: an
        # unreachable results database did that). The same command resumes once it is fixed.
        _write_failure(plan, str(exc), now())
        raise


def _run_planned(
    request: prep.LocalRunRequest,
    plan: prep.Plan,
    *,
    on_event: Callable[[Event], None],
    stop: threading.Event,
    now: Callable[[], datetime.datetime],
    started: float,
    early: list[Worker],
) -> LocalRunResult:
    out = plan.output
    notes = list(plan.notes)
    parallel = _parallel(request, plan)
    paths, unreachable = _locate(plan)
    results: dict[str, ScenarioOutcome] = dict(plan.previous)
    tally = _Tally()
    with storing.ResultWriter.open(
        plan,
        database=request.database,
        secrets=request.secrets,
        paths=paths,
        now=now,
        parallel=parallel,
        notes=notes,
    ) as store:
        on_event(
            Prepared(
                campaign=plan.name,
                output=out.root,
                total=len(plan.frozen.scenarios)
                if plan.search is None
                else plan.search.spec.budget,
                finished=len(plan.finished),
                parallel=parallel,
                store=store.description,
                notes=tuple(notes),
                resumed=plan.resumed,
            )
        )
        for batch, pinned, reason in unreachable:
            failed = ScenarioOutcome(scenario_id=pinned.id, verdict=Verdict.ERROR, reason=reason)
            results[pinned.id] = _finish(out, store, pinned, batch, failed, on_event)

        search = None
        if plan.search is not None:
            search = localsearch.LocalSearch.start(plan, plan.search, store, paths, results,
                                                 parallel=parallel)  # fmt: skip

        def forward(event: scheduling.Event) -> None:
            if isinstance(event, scheduling.Retrying):
                tally.add(event.outcome)
                store.attempt(plan.by_id[event.outcome.scenario_id], event.outcome)
                on_event(event)
            elif isinstance(event, scheduling.Finished):
                tally.add(event.outcome)
                results[event.pinned.id] = _finish(
                    out, store, event.pinned, event.batch, event.outcome, on_event, event.timing
                )
                if search is not None:
                    search.feed.tell(event.pinned, event.outcome)
            else:
                on_event(event)

        not_runnable = frozenset(s.id for s in plan.frozen.scenarios) - frozenset(paths)
        cpu_before = _children_cpu()
        executor = scheduling.Executor(
            request.execute,
            policy=plan.policy,
            parallel=parallel,
            make_task=prep.task_factory(plan, paths),
            workers=early,
            on_event=forward,
            stop=stop,
        )
        if search is None:
            batches = batching.plan(plan.frozen.scenarios, batch_size=plan.policy.batch_size)
            execution = executor.run(batching.without(batches, not_runnable))
        else:
            execution = executor.run_feed(search.feed)
        listed = plan.frozen if search is None else search.frozen
        worker_cpu = _children_cpu() - cpu_before
        for batch, pinned in execution.unfinished:
            skipped = ScenarioOutcome(
                scenario_id=pinned.id, verdict=Verdict.SKIPPED, reason=NOT_RUN_REASON
            )
            out.write_result(pinned, batch, skipped)
            results[pinned.id] = skipped
        ids = [s.id for s in listed.scenarios]
        summary = summaries.summarise(ids, results, interrupted=execution.interrupted)
        searched = None if search is None else search.finish(results)
        store.finish(
            summary.phase,
            finished_at=now(),
            search=None if searched is None else searched.record,
        )
        wall = time.monotonic() - started
        _write_state(out, plan, store, summary, parallel, wall, now(), execution.interrupted)
    section = None if searched is None else searchresults.section(searched.search)
    report, junit = _publish(out, store, now(), notes, section)
    return LocalRunResult(
        output=out.root,
        summary=summary,
        interrupted=execution.interrupted,
        parallel=parallel,
        wall_seconds=wall,
        worker_cpu_seconds=worker_cpu,
        engine_seconds=tally.engine_seconds,
        scenarios_run=tally.attempts,
        run_key=store.run_key,
        report=report,
        junit=junit,
        warnings=tuple(notes),
        not_passed=tuple(
            results[i] for i in ids if i in results and results[i].verdict is not Verdict.PASSED
        ),
        search=searched,
    )


@dataclasses.dataclass(slots=True)
class _Tally:
    attempts: int = 0
    engine_seconds: float = 0.0

    def add(self, outcome: ScenarioOutcome) -> None:
        self.attempts += 1
        self.engine_seconds += outcome.wall_seconds


def _locate(
    plan: prep.Plan,
) -> tuple[dict[str, Path], list[tuple[int, PinnedScenario, str]]]:
    """Fetch and verify every scenario still to run; unreachable ones become Error up front."""
    locator = Locator(plan.fetch, graphql_sources=plan.graphql_sources)
    paths: dict[str, Path] = {}
    unreachable: list[tuple[int, PinnedScenario, str]] = []
    for batch, pinned in _todo(plan):
        try:
            paths[pinned.id] = locator.locate(pinned)
        except SourceError as exc:
            unreachable.append((batch, pinned, str(exc)))
    return paths, unreachable


def _todo(plan: prep.Plan) -> list[tuple[int, PinnedScenario]]:
    size = plan.policy.batch_size
    return [
        (batching.batch_index(position, batch_size=size), pinned)
        for position, pinned in enumerate(plan.frozen.scenarios)
        if pinned.id not in plan.finished
    ]


def _parallel(request: prep.LocalRunRequest, plan: prep.Plan) -> int:
    parallel = request.parallel or request.cpu_count
    if request.parallel is None and plan.policy.max_parallel is not None:
        parallel = min(parallel, plan.policy.max_parallel)
    listed = len(plan.frozen.scenarios) if plan.search is None else plan.search.spec.budget
    remaining = listed - len(plan.finished)
    return max(1, min(parallel, remaining))


def _finish(
    out: outputs.OutputDir,
    store: storing.ResultWriter,
    pinned: PinnedScenario,
    batch: int,
    outcome: ScenarioOutcome,
    on_event: Callable[[Event], None],
    timing: scheduling.Timing | None = None,
) -> ScenarioOutcome:
    outcome = dataclasses.replace(outcome, artifacts=_artifacts(out, pinned))
    out.write_result(pinned, batch, outcome, timing=_timing_json(timing))
    store.attempt(pinned, outcome)
    on_event(scheduling.Finished(outcome=outcome, batch=batch, pinned=pinned, timing=timing))
    return outcome


def _timing_json(timing: scheduling.Timing | None) -> dict[str, object] | None:
    if timing is None:
        return None

    def iso(epoch: float) -> str:
        return datetime.datetime.fromtimestamp(epoch, datetime.UTC).isoformat(
            timespec="milliseconds"
        )

    return {"started": iso(timing.started), "finished": iso(timing.finished), "pid": timing.pid}


def _artifacts(out: outputs.OutputDir, pinned: PinnedScenario) -> Mapping[str, str]:
    """Artifact paths relative to the output folder, so the folder can be moved or archived."""
    folder = out.scenario_dir(pinned.id)
    found = {
        name: (folder / filename).relative_to(out.root).as_posix()
        for name, filename in tasks.ARTIFACT_FILES.items()
        if (folder / filename).is_file()
    }
    found["result"] = (folder / tasks.RESULT).relative_to(out.root).as_posix()
    return found


def _write_state(
    out: outputs.OutputDir,
    plan: prep.Plan,
    store: storing.ResultWriter,
    summary: summaries.Summary,
    parallel: int,
    wall: float,
    finished_at: datetime.datetime,
    interrupted: bool,
) -> None:
    out.write_state(
        outputs.RunState(
            campaign=plan.name,
            manifest_sha256=plan.manifest_sha256,
            state="interrupted" if interrupted else "finished",
            started_at=plan.started_at.isoformat(),
            finished_at=finished_at.isoformat(),
            run_key=store.run_key,
            store=store.description,
            parallel=parallel,
            counts={v.value: n for v, n in summary.counts.items()},
            wall_seconds=wall,
            exit_code=summary.exit_code,
            reason=summary.reason,
        )
    )


def _write_failure(plan: prep.Plan, reason: str, finished_at: datetime.datetime) -> None:
    previous = plan.output.read_state() if plan.output.exists() else None
    plan.output.write_state(
        outputs.RunState(
            campaign=plan.name,
            manifest_sha256=plan.manifest_sha256,
            state="failed",
            started_at=plan.started_at.isoformat(),
            finished_at=finished_at.isoformat(),
            run_key=previous.run_key if previous is not None else "",
            store=previous.store if previous is not None else "",
            exit_code=summaries.EXIT_ERROR,
            reason=reason,
        )
    )


def _publish(
    out: outputs.OutputDir,
    store: storing.ResultWriter,
    now: datetime.datetime,
    warnings: list[str],
    search: reportmodel.SearchSection | None = None,
) -> tuple[Path | None, Path | None]:
    """Write the HTML report and JUnit XML from the store (a failure is a warning: the results
    themselves are safe in the store and the result files)."""
    try:
        published = publishing.publish(
            publishing.RunRef(target=store.target, run_key=store.key, base_dir=out.root),
            now=now,
            report_path=out.report,
            junit_path=out.junit,
            read_trajectories=read_recording,
            hostname=os.uname().nodename,
            search=search,
        )
    except (ResultsError, ScenarioError) as exc:
        warnings.append(f"report and JUnit not written: {exc}")
        return None, None
    return published.report, published.junit


def read_recording(path: Path) -> Sequence[details.Trajectory]:
    """Trajectories of every object of an omega-prime recording, for the report's developer
    view (``recording`` and ``results`` do not know each other; the runner wires them)."""
    names = recording.read_metadata(path).get("simtest.run", {})
    return details.from_samples(recording.read_trajectories(path), names=names)


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime
