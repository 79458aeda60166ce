"""Re-evaluation: score a recorded run again with another criteria set, from its recording alone.

A :class:`CriteriaSet` (a YAML/JSON file, validated with pydantic) names metrics and thresholds
per base-scenario type; :func:`evaluate` decomposes the scene, computes each base scenario's
metrics over its window, checks them, and folds everything with the evidence quality into one
:class:`RunEvaluation`. No simulator is involved, so a new criteria set costs a read of the
recordings, not a campaign.

Verdict rules (most specific first): no recording or an unreadable one -> ``Error`` (evidence
missing); the original run was ``Invalid``/``Skipped`` -> unchanged (nothing to judge); a
collision or any failed base-scenario check -> ``Failed`` (a violation seen in partial evidence
is still a violation); incomplete evidence -> ``Error`` with ``evidence = incomplete`` (it can
never be ``Passed``); an original ``Timeout`` stays ``Timeout``; otherwise ``Passed``.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping
from typing import Annotated, Any

import numpy as np
import pydantic

from simtest_operator.errors import ScenarioError
from simtest_operator.evaluation import quality as quality_mod
from simtest_operator.evaluation.basescenarios import (
    BaseScenario,
    Decomposition,
    Kind,
    Parameters,
    decompose,
)
from simtest_operator.evaluation.scenes import Scene
from simtest_operator.verdicts import Verdict


class Direction(enum.StrEnum):
    """Whether a larger value of a metric is better."""

    HIGHER_IS_BETTER = "higher"
    LOWER_IS_BETTER = "lower"


METRICS: dict[str, Direction] = {
    "minTTC": Direction.HIGHER_IS_BETTER,
    "minTHW": Direction.HIGHER_IS_BETTER,
    "minDistance": Direction.HIGHER_IS_BETTER,
    "PET": Direction.HIGHER_IS_BETTER,
    "maxDecel": Direction.LOWER_IS_BETTER,
    "collision": Direction.LOWER_IS_BETTER,
}
"""Every base-scenario metric and its direction; thresholds are ``>=`` for higher-is-better
metrics and ``<=`` for the others (``collision`` is 0 or 1)."""

Threshold = Annotated[float, pydantic.Field(ge=0.0)]


class _Strict(pydantic.BaseModel):
    model_config = pydantic.ConfigDict(extra="forbid", frozen=True, populate_by_name=True)


class Limits(_Strict):
    """Thresholds of one base-scenario type; an unset metric is computed but not checked."""

    min_ttc: Threshold | None = pydantic.Field(default=None, alias="minTTC")
    min_thw: Threshold | None = pydantic.Field(default=None, alias="minTHW")
    min_distance: Threshold | None = pydantic.Field(default=None, alias="minDistance")
    pet: Threshold | None = pydantic.Field(default=None, alias="PET")
    max_decel: Threshold | None = pydantic.Field(default=None, alias="maxDecel")

    def by_metric(self) -> dict[str, float]:
        values = {
            "minTTC": self.min_ttc,
            "minTHW": self.min_thw,
            "minDistance": self.min_distance,
            "PET": self.pet,
            "maxDecel": self.max_decel,
        }
        return {name: value for name, value in values.items() if value is not None}


def _default_limits() -> dict[Kind, Limits]:
    return {
        kind: Limits.model_validate(limits)
        for kind, limits in {
            Kind.FREE_DRIVING: {"maxDecel": 4.0},
            Kind.FOLLOWING: {"minTHW": 0.8, "minTTC": 3.0},
            Kind.APPROACHING: {"minTTC": 1.5, "maxDecel": 9.0},
            Kind.CUT_IN: {"minTTC": 1.0, "minTHW": 0.3, "maxDecel": 9.0},
            Kind.CUT_OUT: {"minTTC": 1.5, "maxDecel": 9.0},
            Kind.LANE_CHANGE: {"minDistance": 0.5},
            Kind.CROSSING: {"PET": 1.0, "minDistance": 0.5},
            Kind.VRU: {"PET": 1.0, "minDistance": 1.0},
        }.items()
    }


class QualitySpec(_Strict):
    """Evidence requirements (see :class:`~simtest_operator.evaluation.quality.QualityRules`)."""

    min_rate_hz: float = pydantic.Field(default=10.0, alias="minRateHz", gt=0)
    timing_tolerance: float = pydantic.Field(default=0.05, alias="timingTolerance", ge=0)
    coverage_tolerance: float = pydantic.Field(default=0.25, alias="coverageTolerance", ge=0)
    max_position_error: float = pydantic.Field(default=0.5, alias="maxPositionError", gt=0)

    def rules(self) -> quality_mod.QualityRules:
        return quality_mod.QualityRules(
            min_rate_hz=self.min_rate_hz,
            timing_tolerance=self.timing_tolerance,
            coverage_tolerance=self.coverage_tolerance,
            max_position_error=self.max_position_error,
        )


class CriteriaSet(_Strict):
    """A named criteria set for re-evaluation (what ``simtest evaluate --criteria`` reads)."""

    name: str = pydantic.Field(min_length=1, max_length=100)
    collision: bool = True
    """A collision in any base scenario fails it."""
    lane_width: float = pydantic.Field(default=3.5, alias="laneWidth", gt=0)
    range: float = pydantic.Field(100.0, gt=0)
    base_scenarios: dict[Kind, Limits] = pydantic.Field(
        default_factory=_default_limits, alias="baseScenarios"
    )
    """Per type; a type left out of a file keeps the defaults."""
    quality: QualitySpec = pydantic.Field(default_factory=lambda: QualitySpec.model_validate({}))

    @pydantic.field_validator("base_scenarios", mode="after")
    @classmethod
    def _complete(cls, value: dict[Kind, Limits]) -> dict[Kind, Limits]:
        return {**_default_limits(), **value}

    def parameters(self) -> Parameters:
        return Parameters(lane_width=self.lane_width, range=self.range)

    def document(self) -> dict[str, Any]:
        """The whole set as stored with an evaluation (defaults made explicit)."""
        return self.model_dump(mode="json", by_alias=True, exclude_none=True)


DEFAULT_CRITERIA = CriteriaSet.model_validate({"name": "default"})


def load_criteria(data: Mapping[str, Any], *, where: str) -> CriteriaSet:
    """Validate a criteria document; the error names the field and ``where`` it came from."""
    try:
        return CriteriaSet.model_validate(data)
    except pydantic.ValidationError as exc:
        first = exc.errors()[0]
        parts = [str(part) for part in first["loc"] if part != "[key]"]
        field = ".".join(parts) or "(document)"
        raise ScenarioError(f"{where}: {field}: {first['msg']}") from None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Check:
    """One metric of one base scenario against its threshold."""

    metric: str
    value: float
    limit: float
    passed: bool


def _op(metric: str) -> str:
    """How a failed check reads: ``minTTC 0.8 < 1`` or ``maxDecel 9.5 > 9``."""
    return "<" if METRICS[metric] is Direction.HIGHER_IS_BETTER else ">"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScoredBaseScenario:
    """A base scenario with its metrics, checks and verdict (Passed or Failed)."""

    base: BaseScenario
    metrics: Mapping[str, float]
    checks: tuple[Check, ...]

    @property
    def verdict(self) -> Verdict:
        return Verdict.PASSED if all(c.passed for c in self.checks) else Verdict.FAILED

    @property
    def reason(self) -> str:
        failed = [c for c in self.checks if not c.passed]
        if not failed:
            return ""
        return "; ".join(f"{c.metric} {c.value:.2f} {_op(c.metric)} {c.limit:g}" for c in failed)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunEvaluation:
    """The new evaluation of one recorded run."""

    verdict: Verdict
    reason: str
    evidence: str
    """``complete``, ``incomplete`` (quality issues) or ``missing`` (no readable recording)."""
    quality: Mapping[str, float]
    issues: tuple[str, ...]
    base_scenarios: tuple[ScoredBaseScenario, ...]
    metrics: Mapping[str, float]
    """Run-level metrics: the worst value of each base-scenario metric over the run."""


def _min(values: np.ndarray[Any, Any]) -> float:
    finite = values[np.isfinite(values)]
    return float(finite.min()) if len(finite) else math.inf


def _score(
    base: BaseScenario, decomposition: Decomposition, criteria: CriteriaSet
) -> ScoredBaseScenario:
    scene = decomposition.scene
    window = slice(base.first, base.last + 1)
    ego = scene.ego
    speed = ego.speed[window]
    gap = decomposition.lead_gap[window]
    closing = decomposition.lead_closing[window]
    metrics: dict[str, float] = {}
    with np.errstate(invalid="ignore", divide="ignore"):
        metrics["minTTC"] = _min(np.where(closing > 0.0, gap / closing, np.inf))
        metrics["minTHW"] = _min(np.where(speed > 0.1, gap / speed, np.inf))
    relations = [
        r for r in decomposition.relations if base.actor is None or r.track.object_id == base.actor
    ]
    distances = [_min(r.distance[window]) for r in relations]
    metrics["minDistance"] = min(distances, default=math.inf)
    metrics["maxDecel"] = max(0.0, float(np.max(-ego.longitudinal_acceleration[window])))
    conflict = relations[0].conflict if relations else None
    if base.kind in (Kind.CROSSING, Kind.VRU) and conflict is not None:
        other_t = relations[0].track.t[conflict.other_frame]
        metrics["PET"] = abs(float(ego.t[conflict.ego_frame] - other_t))
    metrics["collision"] = 1.0 if metrics["minDistance"] <= 0.0 else 0.0
    checks = [
        Check(
            metric=name,
            value=metrics[name],
            limit=limit,
            passed=metrics[name] >= limit
            if METRICS[name] is Direction.HIGHER_IS_BETTER
            else metrics[name] <= limit,
        )
        for name, limit in criteria.base_scenarios[base.kind].by_metric().items()
        if name in metrics
    ]
    if criteria.collision:
        checks.append(
            Check(
                metric="collision",
                value=metrics["collision"],
                limit=0.0,
                passed=metrics["collision"] == 0.0,
            )
        )
    rounded = {k: round(v, 4) if math.isfinite(v) else v for k, v in metrics.items()}
    return ScoredBaseScenario(base=base, metrics=rounded, checks=tuple(checks))


def _worst(scored: tuple[ScoredBaseScenario, ...]) -> dict[str, float]:
    worst: dict[str, float] = {}
    for item in scored:
        for name, value in item.metrics.items():
            if not math.isfinite(value):
                continue
            higher = METRICS[name] is Direction.HIGHER_IS_BETTER
            current = worst.get(name)
            if current is None or (value < current if higher else value > current):
                worst[name] = value
    return worst


def evaluate(
    scene: Scene | None,
    quality: quality_mod.Quality | None,
    criteria: CriteriaSet,
    *,
    original: Verdict,
    original_reason: str = "",
) -> RunEvaluation:
    """The new evaluation of one run (``scene``/``quality`` ``None``: no readable recording)."""
    if original in (Verdict.INVALID, Verdict.SKIPPED):
        return RunEvaluation(
            verdict=original, reason=f"not re-evaluated: {original_reason or original.value}",
            evidence="missing", quality={}, issues=(), base_scenarios=(), metrics={},
        )  # fmt: skip
    if scene is None or quality is None:
        issues = quality.issues if quality is not None else ("no readable recording",)
        return RunEvaluation(
            verdict=Verdict.ERROR, reason=f"evidence missing: {issues[0]}", evidence="missing",
            quality=dict(quality.metrics) if quality else {}, issues=issues, base_scenarios=(),
            metrics={},
        )  # fmt: skip
    decomposition = decompose(scene, criteria.parameters())
    scored = tuple(_score(b, decomposition, criteria) for b in decomposition.base_scenarios)
    failed = [s for s in scored if s.verdict is Verdict.FAILED]
    evidence = "complete" if quality.complete else "incomplete"
    metrics = _worst(scored)
    metrics["baseScenarios"] = float(len(scored))
    metrics["baseScenariosFailed"] = float(len(failed))
    counts = f"{len(scored) - len(failed)}/{len(scored)} base scenarios passed"
    if failed:
        first = failed[0]
        actor = "" if first.base.actor is None else f" with object {first.base.actor}"
        reason = (
            f"{first.base.kind.value}{actor} at t={first.base.start:.1f}-{first.base.end:.1f} s: "
            f"{first.reason} ({counts})"
        )
        verdict = Verdict.FAILED
    elif not quality.complete:
        verdict = Verdict.ERROR
        reason = f"{quality.incomplete_reason()} ({counts})"
    elif original is Verdict.TIMEOUT:
        verdict, reason = Verdict.TIMEOUT, f"{original_reason} ({counts})"
    else:
        verdict, reason = Verdict.PASSED, counts
    return RunEvaluation(
        verdict=verdict, reason=reason, evidence=evidence, quality=dict(quality.metrics),
        issues=quality.issues, base_scenarios=scored, metrics=metrics,
    )  # fmt: skip
