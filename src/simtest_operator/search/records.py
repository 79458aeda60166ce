"""What a search proposes and what it is told: proposals, outcomes, failure and criticality."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence

from simtest_operator.api.v1alpha1.search import SearchObjective
from simtest_operator.openscenario import parameters
from simtest_operator.verdicts import Verdict

FAILURES = frozenset({Verdict.FAILED, Verdict.TIMEOUT})
"""Verdicts on the system under test that count as found failures."""
VERDICT = "verdict"

METRIC_SCALES: Mapping[str, float] = {
    "minTTC": 4.0,
    "minTHW": 2.0,
    "minDistance": 10.0,
    "maxDecel": 6.0,
}
"""Typical magnitudes (s, s, m, m/s^2) that squash a metric into ``[0, 1)`` for the verdict's
continuous surrogate; a metric not listed uses 1."""


@dataclasses.dataclass(frozen=True, slots=True)
class Proposal:
    """One concrete scenario a searcher proposed."""

    index: int
    """0, 1, 2, ... in the order asked."""
    values: Mapping[str, float | str]
    """Parameter name -> value (floats for ranges, str for choices)."""
    basis: int
    """How many outcomes the searcher had been told when it proposed this."""

    def overrides(self) -> dict[str, str]:
        """The OpenSCENARIO parameter overrides that make the logical scenario concrete."""
        return {
            name: value if isinstance(value, str) else parameters.to_text(value)
            for name, value in self.values.items()
        }


@dataclasses.dataclass(frozen=True, slots=True)
class Outcome:
    """What one run of a proposal gave."""

    verdict: Verdict
    metrics: Mapping[str, float] = dataclasses.field(default_factory=dict)

    @property
    def failed(self) -> bool:
        """Failed or Timeout: a failure of the system under test."""
        return self.verdict in FAILURES

    @property
    def judged(self) -> bool:
        """Whether the run says anything about the system (Error and Invalid do not)."""
        return self.verdict.counts_as_ran


def criticality(outcome: Outcome, objective: SearchObjective) -> float | None:
    """How critical an outcome is under ``objective``: lower is more critical; None when the run
    says nothing about the system or lacks the metric.

    For ``verdict`` a failure scores below every pass (``-1``) and a pass scores in ``[0, 1)`` by
    how close its metrics came to critical (the smallest squashed ``minTTC``, ``minDistance``,
    ...): a continuous surrogate that gives a model-based optimiser a slope towards the failures
    rather than a plateau of passes. For a metric, ``maximize`` flips the sign.
    """
    if not outcome.judged:
        return None
    if objective.metric == VERDICT:
        if outcome.failed:
            return -1.0
        margins = [
            _squash(value, METRIC_SCALES[name])
            for name, value in outcome.metrics.items()
            if name in METRIC_SCALES and name != "maxDecel" and math.isfinite(value)
        ]
        decel = outcome.metrics.get("maxDecel")
        if decel is not None and math.isfinite(decel):
            margins.append(1.0 - _squash(abs(decel), METRIC_SCALES["maxDecel"]))
        return min(margins, default=0.5)
    value = outcome.metrics.get(objective.metric)
    if value is None or not math.isfinite(value):
        return None
    return value if objective.goal == "minimize" else -value


def _squash(value: float, scale: float) -> float:
    return max(value, 0.0) / (max(value, 0.0) + scale)


def scores(outcomes: Sequence[Outcome], objective: SearchObjective) -> list[float | None]:
    """:func:`criticality` of each outcome."""
    return [criticality(o, objective) for o in outcomes]
