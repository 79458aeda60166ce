"""KPI regressions between two runs: metric values per scenario and base scenario, not verdicts.

Two runs of the same scenarios (two SUT versions, or a run against a baseline) are matched item by
item: an item is a (scenario, base-scenario type) pair holding the worst value of each metric
over that type's base scenarios in the run -- or the scenario's run-level metrics when a run was
not evaluated with base scenarios. Per group (base-scenario type) and metric the comparison keeps
both distributions and the per-item change, signed so that positive is *worse* whatever the
metric's direction ("minTTC on cut-in worse by 0.4 s in 12 scenarios").

``--fail-on`` rules (:func:`parse_rules`), comma-separated, each ``SUBJECT:MEASURE OP NUMBER``:

* ``METRIC[.STAT][@GROUP]:worse OP X`` -- STAT (``p10``, ``p50`` (default), ``p90``, ``mean``,
  ``min``, ``max``) of the metric's values got worse by OP X (metric units);
* ``METRIC[@GROUP]:worsened OP N`` -- the number of matched items whose value got worse;
* ``verdict[@GROUP]:regressed|fixed|failing OP N`` -- scenarios passing before and failing now,
  the reverse, failing now.

OP is one of ``> >= < <=``; GROUP is a base-scenario type (``cut-in``) or ``run`` for run-level
metrics; without it every item counts. Example: ``minTTC.p50@cut-in:worse>0.2,verdict:regressed>0``.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import re
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np

from simtest_operator.errors import ResultsError
from simtest_operator.results.records import is_failing
from simtest_operator.verdicts import Verdict

RUN_GROUP = "run"
"""Group of the run-level metrics (a run without base scenarios)."""
STATS = ("p10", "p50", "p90", "mean", "min", "max")
_EPSILON = 1e-9


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class KpiScenario:
    """One scenario of a run, as the comparison sees it."""

    scenario_id: str
    verdict: Verdict
    groups: Mapping[str, Mapping[str, float]]
    """Group (base-scenario type, or ``run``) -> metric -> worst value in the scenario."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class MetricChange:
    """One metric of one group across the matched items."""

    group: str
    metric: str
    higher_is_better: bool
    base: tuple[float, ...]
    other: tuple[float, ...]
    worse_by: tuple[float, ...]
    """Per matched item, how much worse the other run is (negative: better)."""
    worse_items: tuple[str, ...]
    """Scenario ids whose value got worse."""

    def stat(self, name: str, which: str = "other") -> float:
        values = np.asarray(self.other if which == "other" else self.base, dtype=np.float64)
        values = values[np.isfinite(values)]
        if not len(values):
            return math.nan
        if name == "mean":
            return float(values.mean())
        if name == "min":
            return float(values.min())
        if name == "max":
            return float(values.max())
        return float(np.percentile(values, float(name[1:])))

    def stat_worse_by(self, name: str) -> float:
        """How much worse STAT got (positive: worse)."""
        before, after = self.stat(name, "base"), self.stat(name, "other")
        if math.isnan(before) or math.isnan(after):
            return math.nan
        return before - after if self.higher_is_better else after - before

    def summary(self) -> str:
        """E.g. ``minTTC on cut-in: p50 2.10 -> 1.70 s (worse by 0.40), worse in 12 of 32``."""
        return (
            f"{self.metric} on {self.group}: p10/p50/p90 "
            f"{self.stat('p10', 'base'):.2f}/{self.stat('p50', 'base'):.2f}/"
            f"{self.stat('p90', 'base'):.2f} -> {self.stat('p10'):.2f}/{self.stat('p50'):.2f}/"
            f"{self.stat('p90'):.2f} (p50 worse by {self.stat_worse_by('p50'):+.2f}), "
            f"worse in {len(self.worse_items)} of {len(self.worse_by)}"
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class KpiComparison:
    """Every metric change and the verdict moves between two runs."""

    base: str
    other: str
    changes: tuple[MetricChange, ...]
    regressed: tuple[str, ...]
    fixed: tuple[str, ...]
    failing: tuple[str, ...]
    matched: int

    def change(self, group: str | None, metric: str) -> tuple[MetricChange, ...]:
        return tuple(
            c for c in self.changes if c.metric == metric and (group is None or c.group == group)
        )


def _finite(value: float) -> bool:
    return not math.isnan(value)


def compare_kpis(
    base: Iterable[KpiScenario],
    other: Iterable[KpiScenario],
    *,
    higher_is_better: Mapping[str, bool],
    base_label: str = "base",
    other_label: str = "other",
) -> KpiComparison:
    """Match scenarios by id and compare each (group, metric) with a known direction."""
    before = {s.scenario_id: s for s in base}
    after = {s.scenario_id: s for s in other}
    matched = sorted(before.keys() & after.keys())
    series: dict[tuple[str, str], list[tuple[str, float, float]]] = {}
    for scenario_id in matched:
        old, new = before[scenario_id], after[scenario_id]
        for group in sorted(old.groups.keys() & new.groups.keys()):
            for metric in sorted(old.groups[group].keys() & new.groups[group].keys()):
                if metric not in higher_is_better:
                    continue
                a, b = old.groups[group][metric], new.groups[group][metric]
                if _finite(a) and _finite(b):
                    series.setdefault((group, metric), []).append((scenario_id, a, b))
    changes = []
    for (group, metric), items in sorted(series.items()):
        higher = higher_is_better[metric]
        worse_by = []
        for _, a, b in items:
            if math.isinf(a) and math.isinf(b) and a == b:
                worse_by.append(0.0)
            else:
                worse_by.append(a - b if higher else b - a)
        changes.append(
            MetricChange(
                group=group,
                metric=metric,
                higher_is_better=higher,
                base=tuple(a for _, a, _ in items),
                other=tuple(b for _, _, b in items),
                worse_by=tuple(worse_by),
                worse_items=tuple(
                    s for (s, _, _), w in zip(items, worse_by, strict=True) if w > _EPSILON
                ),
            )
        )
    return KpiComparison(
        base=base_label,
        other=other_label,
        changes=tuple(changes),
        regressed=tuple(
            s for s in matched if not is_failing(before[s].verdict) and is_failing(after[s].verdict)
        ),
        fixed=tuple(
            s for s in matched if is_failing(before[s].verdict) and not is_failing(after[s].verdict)
        ),
        failing=tuple(s for s in sorted(after) if is_failing(after[s].verdict)),
        matched=len(matched),
    )


# --- rules ------------------------------------------------------------------------------------

_OPS: dict[str, Callable[[float, float], bool]] = {
    ">": operator.gt,
    ">=": operator.ge,
    "<": operator.lt,
    "<=": operator.le,
}
_RULE = re.compile(
    r"^(?P<subject>[A-Za-z][\w]*)(?:\.(?P<stat>p10|p50|p90|mean|min|max))?"
    r"(?:@(?P<group>[\w-]+))?:(?P<measure>[a-z]+)(?P<op>>=|<=|>|<)"
    r"(?P<number>-?\d+(?:\.\d+)?)$"
)
_METRIC_MEASURES = ("worse", "worsened")
_VERDICT_MEASURES = ("regressed", "fixed", "failing")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Rule:
    """One ``--fail-on`` rule."""

    text: str
    subject: str
    stat: str
    group: str | None
    measure: str
    op: str
    number: float


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RuleResult:
    rule: Rule
    value: float
    violated: bool
    detail: str


def parse_rules(text: str) -> tuple[Rule, ...]:
    """Parse ``--fail-on``; a bad rule raises :class:`ResultsError` naming it."""
    rules = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        match = _RULE.match(part.replace(" ", ""))
        if match is None:
            raise ResultsError(
                f"bad --fail-on rule {part!r}: expected METRIC[.STAT][@GROUP]:worse|worsened "
                "OP NUMBER or verdict[@GROUP]:regressed|fixed|failing OP NUMBER"
            )
        subject, measure = match["subject"], match["measure"]
        allowed = _VERDICT_MEASURES if subject == "verdict" else _METRIC_MEASURES
        if measure not in allowed:
            raise ResultsError(
                f"bad --fail-on rule {part!r}: {subject} takes {' or '.join(allowed)}, "
                f"not {measure!r}"
            )
        if subject == "verdict" and match["stat"]:
            raise ResultsError(f"bad --fail-on rule {part!r}: verdict has no statistic")
        rules.append(
            Rule(
                text=part,
                subject=subject,
                stat=match["stat"] or "p50",
                group=match["group"],
                measure=measure,
                op=match["op"],
                number=float(match["number"]),
            )
        )
    if not rules:
        raise ResultsError("--fail-on is empty")
    return tuple(rules)


def check_rules(
    comparison: KpiComparison, rules: Sequence[Rule], *, groups_of: Mapping[str, set[str]]
) -> tuple[RuleResult, ...]:
    """Evaluate each rule; ``groups_of`` maps scenario id -> its groups (for verdict@GROUP)."""
    results = []
    for rule in rules:
        if rule.subject == "verdict":
            ids = {
                "regressed": comparison.regressed,
                "fixed": comparison.fixed,
                "failing": comparison.failing,
            }[rule.measure]
            if rule.group is not None:
                ids = tuple(s for s in ids if rule.group in groups_of.get(s, set()))
            value = float(len(ids))
            detail = f"{len(ids)} scenario(s) {rule.measure}" + (
                f": {', '.join(ids[:5])}{' ...' if len(ids) > 5 else ''}" if ids else ""
            )
        else:
            changes = comparison.change(rule.group, rule.subject)
            if not changes:
                results.append(
                    RuleResult(
                        rule=rule, value=math.nan, violated=False,
                        detail=f"no matched values of {rule.subject}"
                        + (f" on {rule.group}" if rule.group else ""),
                    )
                )  # fmt: skip
                continue
            if rule.measure == "worsened":
                value = float(sum(len(c.worse_items) for c in changes))
                detail = "; ".join(c.summary() for c in changes)
            else:
                worst = max(changes, key=lambda c: _nan_low(c.stat_worse_by(rule.stat)))
                value = worst.stat_worse_by(rule.stat)
                detail = worst.summary()
        violated = not math.isnan(value) and _OPS[rule.op](value, rule.number)
        results.append(RuleResult(rule=rule, value=value, violated=violated, detail=detail))
    return tuple(results)


def _nan_low(value: float) -> float:
    return -math.inf if math.isnan(value) else value
