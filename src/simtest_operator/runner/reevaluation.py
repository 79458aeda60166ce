"""Re-evaluating a stored run: the action behind ``simtest evaluate``.

Reads the final attempt of every scenario of a run from a results store (an output folder's
SQLite file or PostgreSQL), fetches each recording (local path, ``file://``, ``s3://``), decodes
it (``recording.objects``), checks its evidence quality, decomposes it into base scenarios and
scores it with a criteria set (``evaluation``), and stores the result as a new evaluation of the
same run (``results``); the original verdicts stay. It lives in the runner layer because it is
the one place that may combine those three packages, which sit side by side on one layer.
"""

from __future__ import annotations

import collections
import dataclasses
import datetime
import math
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from simtest_operator import __version__
from simtest_operator.errors import SimtestError
from simtest_operator.evaluation import quality as quality_mod
from simtest_operator.evaluation import reevaluating, scenes
from simtest_operator.recording import objects
from simtest_operator.results import evaluations as ev
from simtest_operator.results import fetching, opening, records

Progress = Callable[[str, ev.EvaluatedRun], None]


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluateRequest:
    """What ``simtest evaluate`` decided from its options."""

    target: str | Path
    """The store: an output folder, a SQLite file or a PostgreSQL DSN."""
    base_dir: Path | None
    """Where relative artifact paths start (the run's output folder)."""
    criteria: reevaluating.CriteriaSet
    run_key: records.RunKey | None = None
    """Default: the newest run in the store."""
    pvc_root: Path | None = None
    now: Callable[[], datetime.datetime] = lambda: datetime.datetime.now(datetime.UTC)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluateSummary:
    """What was evaluated and how it came out."""

    run_key: records.RunKey
    evaluation_id: ev.EvaluationId
    runs: tuple[ev.EvaluatedRun, ...]
    wall_seconds: float

    @property
    def totals(self) -> collections.Counter[str]:
        return collections.Counter(r.verdict.value for r in self.runs)


def to_stored(
    scenario_id: str, attempt: int, result: reevaluating.RunEvaluation, recording: str
) -> ev.EvaluatedRun:
    """The store's record of one evaluation result."""
    bases = []
    for scored in result.base_scenarios:
        limits = {c.metric: c for c in scored.checks}
        bases.append(
            ev.StoredBaseScenario(
                kind=scored.base.kind.value,
                actor=scored.base.actor,
                start=scored.base.start,
                end=scored.base.end,
                verdict=scored.verdict,
                reason=scored.reason,
                detail=scored.base.detail,
                metrics={
                    name: ev.MetricCheck(
                        value=value,
                        threshold=limits[name].limit if name in limits else None,
                        passed=limits[name].passed if name in limits else None,
                    )
                    for name, value in scored.metrics.items()
                },
            )
        )
    return ev.EvaluatedRun(
        scenario_id=scenario_id,
        attempt=attempt,
        verdict=result.verdict,
        reason=result.reason,
        evidence=result.evidence,
        quality=result.quality,
        issues=result.issues,
        metrics=result.metrics,
        base_scenarios=tuple(bases),
        recording=recording,
    )


def evaluate_recording(
    path: Path | None,
    criteria: reevaluating.CriteriaSet,
    *,
    simulated_seconds: float,
    original: records.StoredOutcome,
    missing_reason: str = "",
) -> reevaluating.RunEvaluation:
    """Score one recording (``path`` None: it could not be had, ``missing_reason`` says why)."""
    verdict, reason = original.outcome.verdict, original.outcome.reason
    if path is None:
        missing = quality_mod.Quality(metrics={}, issues=(missing_reason or "no recording",))
        return reevaluating.evaluate(
            None, missing, criteria, original=verdict, original_reason=reason
        )
    try:
        decoded = objects.read_objects(path)
    except SimtestError as exc:
        unreadable = quality_mod.Quality(metrics={}, issues=(str(exc),))
        return reevaluating.evaluate(
            None, unreadable, criteria, original=verdict, original_reason=reason
        )
    quality = quality_mod.assess(
        decoded, simulated_seconds=simulated_seconds, rules=criteria.quality.rules()
    )
    scene = scenes.scene_from_columns(decoded)
    if scene is None:
        return reevaluating.evaluate(
            None, quality, criteria, original=verdict, original_reason=reason
        )
    return reevaluating.evaluate(scene, quality, criteria, original=verdict, original_reason=reason)


def reevaluate(request: EvaluateRequest, *, progress: Progress | None = None) -> EvaluateSummary:
    """Evaluate every final attempt of a stored run again and store the new evaluation."""
    started = time.perf_counter()
    with (
        opening.open_store(request.target) as store,
        tempfile.TemporaryDirectory(prefix="simtest-evaluate-") as scratch,
    ):
        run_key = request.run_key
        if run_key is None:
            newest = store.campaigns(limit=1)
            if not newest:
                raise SimtestError(f"no runs in {request.target}")
            run_key = newest[0].run_key
        elif store.campaign(run_key) is None:
            raise SimtestError(f"no run {run_key} in {request.target}")
        evaluation_id = store.begin_evaluation(
            ev.EvaluationInfo(
                run_key=run_key,
                criteria_name=request.criteria.name,
                criteria=request.criteria.document(),
                created_at=request.now(),
                versions={"simtest": __version__},
            )
        )
        fetcher = fetching.Fetcher(
            base_dir=request.base_dir, scratch=Path(scratch), pvc_root=request.pvc_root
        )
        stored = []
        for original in store.outcomes(run_key):
            outcome = original.outcome
            uri = outcome.artifacts.get("recording", "")
            path: Path | None = None
            why = "the run kept no recording" if not uri else ""
            if uri:
                try:
                    path = fetcher.local(uri)
                except SimtestError as exc:
                    why = str(exc)
            simulated = outcome.simulated_seconds
            result = evaluate_recording(
                path,
                request.criteria,
                simulated_seconds=simulated if math.isfinite(simulated) else 0.0,
                original=original,
                missing_reason=why,
            )
            evaluated = to_stored(outcome.scenario_id, outcome.attempts, result, uri)
            store.add_evaluated_run(evaluation_id, evaluated)
            stored.append(evaluated)
            if progress is not None:
                progress(original.scenario.category, evaluated)
        store.finish_evaluation(evaluation_id, finished_at=request.now())
    return EvaluateSummary(
        run_key=run_key,
        evaluation_id=evaluation_id,
        runs=tuple(stored),
        wall_seconds=time.perf_counter() - started,
    )
