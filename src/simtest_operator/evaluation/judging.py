"""Judging: turn what a run produced into one verdict with a one-line reason and its metrics.

Precedence, most specific first: a scenario the engine could not run is ``Invalid``; broken
infrastructure is ``Error``; a violated criterion (the campaign's, one of the scenario's own
ScenarioRunner criteria that is not optional, or a 1.3 monitor false at the end) is ``Failed``
(even if the run also ran out of time, the violation is the more useful news); a storyboard that
did not complete within the time limit is ``Timeout``; everything else ``Passed``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

from simtest_operator.evaluation import monitors
from simtest_operator.evaluation.carla_criteria import Outcome, Status
from simtest_operator.evaluation.online import OnlineEvaluator
from simtest_operator.verdicts import Verdict


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunFacts:
    """What the engine and runner know about how the run ended."""

    simulated_seconds: float
    wall_seconds: float
    storyboard_complete: bool
    invalid_reason: str | None = None
    """Set when an unsupported or broken element stopped the run (names element and line)."""
    error_reason: str | None = None
    """Set when the infrastructure failed (simulator crash, map conversion)."""
    wall_limit_hit: bool = False
    """The run was stopped because it exceeded its wall-clock budget."""
    ignored_elements: tuple[str, ...] = ()
    monitors: Mapping[str, bool] = dataclasses.field(default_factory=dict)
    """Final values of the scenario's 1.3 monitors (:mod:`.monitors`); a false one fails."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Judgement:
    """A verdict, its one-line reason and the run's metrics."""

    verdict: Verdict
    reason: str
    metrics: Mapping[str, float]


def judge(evaluator: OnlineEvaluator, facts: RunFacts) -> Judgement:
    """The verdict for a finished (or aborted) run."""
    metrics = dict(evaluator.metrics())
    metrics["simulatedSeconds"] = round(facts.simulated_seconds, 4)
    metrics["wallSeconds"] = round(facts.wall_seconds, 4)
    if facts.wall_seconds > 0.0 and facts.simulated_seconds > 0.0:
        metrics["realTimeFactor"] = round(facts.simulated_seconds / facts.wall_seconds, 2)
    metrics["ignoredElements"] = float(len(facts.ignored_elements))
    outcomes = evaluator.criterion_outcomes()
    metrics.update(_outcome_metrics(evaluator, outcomes))
    metrics.update(monitors.metrics(facts.monitors))
    metrics = {key: value for key, value in metrics.items() if math.isfinite(value)}
    if facts.invalid_reason is not None:
        return Judgement(verdict=Verdict.INVALID, reason=facts.invalid_reason, metrics=metrics)
    if facts.error_reason is not None:
        return Judgement(verdict=Verdict.ERROR, reason=facts.error_reason, metrics=metrics)
    summary = _summary(outcomes)
    failures = sorted(
        [(v.time, v.criterion, v.message) for v in evaluator.violations]
        + [
            (
                o.time if o.time is not None else facts.simulated_seconds,
                f"criteria_{o.name}",
                f"criteria_{o.name} failed: {o.detail}",
            )
            for o in outcomes
            if o.decisive
        ]
        + monitors.failures(facts.monitors, facts.simulated_seconds),
        key=lambda failure: failure[0],
    )
    if failures:
        reason = failures[0][2]
        if len(failures) > 1:
            others = ", ".join(name for _, name, _ in failures[1:])
            reason += f" (+{len(failures) - 1} more: {others})"
        return Judgement(verdict=Verdict.FAILED, reason=reason + summary, metrics=metrics)
    if facts.wall_limit_hit:
        return Judgement(
            verdict=Verdict.TIMEOUT,
            reason=f"wall-clock limit reached after {facts.wall_seconds:.1f} s "
            f"({facts.simulated_seconds:.2f} s simulated)" + summary,
            metrics=metrics,
        )
    if not facts.storyboard_complete:
        return Judgement(
            verdict=Verdict.TIMEOUT,
            reason=f"storyboard not complete within {evaluator.criteria.time_limit:g} s "
            "simulated time" + summary,
            metrics=metrics,
        )
    return Judgement(
        verdict=Verdict.PASSED,
        reason=f"storyboard complete at t={facts.simulated_seconds:.2f} s, all criteria held"
        + summary,
        metrics=metrics,
    )


def _outcome_metrics(evaluator: OnlineEvaluator, outcomes: tuple[Outcome, ...]) -> dict[str, float]:
    """``criteria.<Test>`` = 1 (passed) / 0 (failed) per evaluated criterion, and the driven
    distance when a criterion needs it."""
    metrics = {
        f"criteria.{o.name}": 1.0 if o.status is Status.PASSED else 0.0
        for o in outcomes
        if o.status is not Status.NOT_EVALUATED
    }
    checks = evaluator.scenario_criteria
    if checks is not None and "DrivenDistanceTest" in checks.names:
        metrics["drivenDistance"] = round(checks.driven_distance, 2)
    return metrics


def _summary(outcomes: tuple[Outcome, ...]) -> str:
    """``; ScenarioRunner criteria: CollisionTest passed, ...`` (empty without criteria)."""
    if not outcomes:
        return ""
    return "; ScenarioRunner criteria: " + ", ".join(o.describe() for o in outcomes)
