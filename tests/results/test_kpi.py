"""KPI comparison and ``--fail-on`` rules: direction-aware changes, distributions, verdict moves,
and rule parsing with one-line errors."""

from __future__ import annotations

import math

import pytest

from simtest_operator.errors import ResultsError
from simtest_operator.results import kpis
from simtest_operator.verdicts import Verdict

HIGHER = {"minTTC": True, "maxDecel": False}


def _run(
    values: dict[str, tuple[float, float]], verdicts: dict[str, Verdict] | None = None
) -> list[kpis.KpiScenario]:
    """scenario id -> (cut-in minTTC, cut-in maxDecel)."""
    return [
        kpis.KpiScenario(
            scenario_id=sid,
            verdict=(verdicts or {}).get(sid, Verdict.PASSED),
            groups={"cut-in": {"minTTC": ttc, "maxDecel": decel}, "run": {"minTTC": ttc}},
        )
        for sid, (ttc, decel) in values.items()
    ]


BASE = _run({f"s{i}": (2.0 + 0.1 * i, 4.0) for i in range(10)})
# Every minTTC 0.4 s lower, decelerations 1 m/s^2 softer, s9 gone, s10 new, s3 now failing.
OTHER = _run(
    {**{f"s{i}": (1.6 + 0.1 * i, 3.0) for i in range(9)}, "s10": (9.0, 1.0)},
    {"s3": Verdict.FAILED},
)


def test_changes_are_signed_positive_when_worse_whatever_the_direction() -> None:
    comparison = kpis.compare_kpis(BASE, OTHER, higher_is_better=HIGHER)
    assert comparison.matched == 9
    (ttc,) = comparison.change("cut-in", "minTTC")
    assert ttc.worse_by == pytest.approx([0.4] * 9)
    assert len(ttc.worse_items) == 9
    assert ttc.stat_worse_by("p50") == pytest.approx(0.4)
    assert ttc.stat("p50", "base") == pytest.approx(2.4) and ttc.stat("p50") == pytest.approx(2.0)
    (decel,) = comparison.change("cut-in", "maxDecel")
    assert decel.worse_by == pytest.approx([-1.0] * 9) and decel.worse_items == ()
    assert "minTTC on cut-in" in ttc.summary() and "worse in 9 of 9" in ttc.summary()
    assert comparison.regressed == ("s3",) and comparison.failing == ("s3",)
    assert comparison.fixed == ()


def test_metrics_without_a_direction_and_infinite_pairs_are_handled() -> None:
    base = [
        kpis.KpiScenario(
            scenario_id="a",
            verdict=Verdict.PASSED,
            groups={"run": {"minTTC": math.inf, "wallSeconds": 1.0}},
        )
    ]
    groups = {"run": {"minTTC": math.inf, "wallSeconds": 9.0}}
    other = [kpis.KpiScenario(scenario_id="a", verdict=Verdict.PASSED, groups=groups)]
    comparison = kpis.compare_kpis(base, other, higher_is_better=HIGHER)
    (change,) = comparison.changes
    assert change.metric == "minTTC" and change.worse_by == (0.0,)
    assert math.isnan(change.stat("p50"))


@pytest.mark.parametrize(
    ("rules", "violated"),
    [
        ("minTTC.p50@cut-in:worse>0.2", [True]),
        ("minTTC.p50@cut-in:worse>0.5", [False]),
        ("minTTC@cut-in:worsened>=9", [True]),
        ("maxDecel.p90:worse>0", [False]),
        ("verdict:regressed>0, verdict:fixed>0", [True, False]),
        ("verdict@cut-in:regressed>0", [True]),
        ("verdict@pedestrian:regressed>0", [False]),
        ("minDistance:worse>0", [False]),
    ],
)
def test_rules(rules: str, violated: list[bool]) -> None:
    comparison = kpis.compare_kpis(BASE, OTHER, higher_is_better=HIGHER)
    groups = {s.scenario_id: {"cut-in"} for s in OTHER}
    results = kpis.check_rules(comparison, kpis.parse_rules(rules), groups_of=groups)
    assert [r.violated for r in results] == violated


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("minTTC>0.2", "bad --fail-on rule 'minTTC>0.2': expected"),
        ("minTTC:regressed>0", "minTTC takes worse or worsened, not 'regressed'"),
        ("verdict:worse>0", "verdict takes regressed or fixed or failing, not 'worse'"),
        ("verdict.p50:regressed>0", "verdict has no statistic"),
        ("minTTC.p75:worse>1", "bad --fail-on rule 'minTTC.p75:worse>1'"),
        (" , ", "--fail-on is empty"),
    ],
)
def test_bad_rules_are_one_line_errors(text: str, message: str) -> None:
    with pytest.raises(ResultsError) as raised:
        kpis.parse_rules(text)
    assert message in str(raised.value) and "\n" not in str(raised.value)
