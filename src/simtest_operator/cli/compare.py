"""``simtest compare``: KPI regressions between two runs, per scenario and base scenario.

Loads each side's newest evaluation (``simtest evaluate``) -- or the run's original metrics when
it has none, or with ``--original`` -- compares metric distributions with
:func:`results.kpis.compare_kpis` and checks ``--fail-on`` rules for CI release gates. Exit codes
follow ``simtest run``: 0 no rule violated, 1 a rule violated, 2 bad input.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import click

from simtest_operator.cli.terminal import printable
from simtest_operator.errors import SimtestError

if TYPE_CHECKING:
    from simtest_operator.results import kpis, records
    from simtest_operator.results.evaluations import EvaluationId
    from simtest_operator.results.stores import Store


def _worst(values: list[float], higher_is_better: bool) -> float:
    finite = [v for v in values if not math.isnan(v)]
    if not finite:
        return math.nan
    return min(finite) if higher_is_better else max(finite)


def load_side(
    store: Store,
    *,
    run_key: records.RunKey | None,
    evaluation_id: EvaluationId | None,
    original: bool,
    directions: Mapping[str, bool],
) -> tuple[str, list[kpis.KpiScenario], dict[str, set[str]]]:
    """(label, scenarios, scenario id -> groups) of one side of the comparison."""
    from simtest_operator.results import kpis

    if run_key is None:
        newest = store.campaigns(limit=1)
        if not newest:
            raise SimtestError("no runs in the store")
        run_key = newest[0].run_key
    elif store.campaign(run_key) is None:
        raise SimtestError(f"no run {run_key} in the store")
    outcomes = store.outcomes(run_key)
    groups_of = {o.scenario.scenario_id: {o.scenario.category} for o in outcomes}
    if evaluation_id is None and not original:
        finished = [e for e in store.evaluations(run_key) if e.finished_at is not None]
        evaluation_id = finished[0].evaluation_id if finished else None
    if original or evaluation_id is None:
        scenarios = [
            kpis.KpiScenario(
                scenario_id=o.scenario.scenario_id,
                verdict=o.verdict,
                groups={kpis.RUN_GROUP: dict(o.outcome.metrics)},
            )
            for o in outcomes
        ]
        return f"{run_key} (original verdicts)", scenarios, groups_of
    record = store.evaluation(evaluation_id)
    if record is None or record.info.run_key != run_key:
        raise SimtestError(f"no evaluation {evaluation_id} of run {run_key}")
    scenarios = []
    for run in store.evaluated_runs(evaluation_id):
        by_kind: dict[str, dict[str, list[float]]] = {}
        for base in run.base_scenarios:
            for name, check in base.metrics.items():
                by_kind.setdefault(base.kind, {}).setdefault(name, []).append(check.value)
        groups: dict[str, Mapping[str, float]] = {
            kind: {
                name: _worst(values, directions.get(name, True)) for name, values in metrics.items()
            }
            for kind, metrics in by_kind.items()
        }
        groups[kpis.RUN_GROUP] = dict(run.metrics)
        groups_of.setdefault(run.scenario_id, set()).update(by_kind)
        scenarios.append(
            kpis.KpiScenario(scenario_id=run.scenario_id, verdict=run.verdict, groups=groups)
        )
    return f"{run_key} (evaluation {evaluation_id})", scenarios, groups_of


@click.command()
@click.argument("base", metavar="BASE")
@click.argument("other", metavar="OTHER", required=False)
@click.option("--base-run", metavar="KEY", help="Run key in BASE  [default: newest]")
@click.option("--run", "run_key", metavar="KEY", help="Run key in OTHER  [default: newest]")
@click.option("--base-evaluation", metavar="ID", help="Evaluation of the base run.")
@click.option("--evaluation", metavar="ID", help="Evaluation of the other run.")
@click.option("--original", is_flag=True, help="Compare the runs' original verdicts and metrics.")
@click.option(
    "--fail-on",
    "fail_on",
    metavar="RULES",
    help="Exit 1 when a rule holds, e.g. 'minTTC.p50@cut-in:worse>0.2,verdict:regressed>0'.",
)
@click.option(
    "--json",
    "json_out",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Also write the comparison as JSON.",
)
def compare(
    base: str,
    other: str | None,
    base_run: str | None,
    run_key: str | None,
    base_evaluation: str | None,
    evaluation: str | None,
    original: bool,
    fail_on: str | None,
    json_out: Path | None,
) -> None:
    """Compare two runs' KPIs per scenario and base scenario; gate CI with --fail-on RULES.

    BASE and OTHER are output folders or database DSNs (OTHER defaults to BASE, with --base-run
    and --run naming two runs in it). Each side uses its newest evaluation (simtest evaluate),
    else its original metrics. Metric changes are reported per base-scenario type with their
    distributions (p10/p50/p90) and how many scenarios got worse. Exit code: 0 no --fail-on rule
    holds, 1 one does, 2 bad input.
    """
    from simtest_operator.evaluation.reevaluating import METRICS, Direction
    from simtest_operator.results import evaluations, kpis, opening, records

    directions = {name: d is Direction.HIGHER_IS_BETTER for name, d in METRICS.items()}
    try:
        rules = kpis.parse_rules(fail_on) if fail_on else ()
        sides = []
        for target, key, ev_id in (
            (base, base_run, base_evaluation),
            (other or base, run_key, evaluation),
        ):
            if "://" not in target and "=" not in target and not Path(target).exists():
                raise SimtestError(f"{target}: no such output folder, database file or DSN")
            with opening.open_store(target) as store:
                sides.append(
                    load_side(
                        store,
                        run_key=records.RunKey(key) if key else None,
                        evaluation_id=evaluations.EvaluationId(ev_id) if ev_id else None,
                        original=original,
                        directions=directions,
                    )
                )
    except SimtestError as exc:
        click.echo(f"simtest compare: {exc}", err=True)
        raise SystemExit(2) from None
    (base_label, base_items, _), (other_label, other_items, groups_of) = sides
    comparison = kpis.compare_kpis(
        base_items,
        other_items,
        higher_is_better=directions,
        base_label=base_label,
        other_label=other_label,
    )
    click.echo(f"base  {base_label}\nother {other_label}\n{comparison.matched} scenarios matched")
    for change in comparison.changes:
        if change.worse_items or any(w < 0 for w in change.worse_by):
            click.echo(f"  {printable(change.summary())}")
    click.echo(
        f"verdicts: {len(comparison.regressed)} regressed, {len(comparison.fixed)} fixed, "
        f"{len(comparison.failing)} failing"
    )
    results = kpis.check_rules(comparison, rules, groups_of=groups_of)
    for result in results:
        state = "VIOLATED" if result.violated else "ok"
        click.echo(f"rule {result.rule.text}: {state} ({result.value:g}; {result.detail})")
    if json_out is not None:
        json_out.write_text(
            json.dumps(_as_json(comparison, results), indent=2, allow_nan=False), "utf-8"
        )
    violated = [r for r in results if r.violated]
    if violated:
        click.echo(f"{len(violated)} of {len(results)} --fail-on rules violated")
        raise SystemExit(1)


def _number(value: float) -> float | str:
    return value if math.isfinite(value) else str(value)


def _as_json(
    comparison: kpis.KpiComparison, results: tuple[kpis.RuleResult, ...]
) -> dict[str, object]:
    return {
        "base": comparison.base,
        "other": comparison.other,
        "matched": comparison.matched,
        "regressed": list(comparison.regressed),
        "fixed": list(comparison.fixed),
        "failing": list(comparison.failing),
        "changes": [
            {
                "group": c.group,
                "metric": c.metric,
                "items": len(c.worse_by),
                "worse": list(c.worse_items),
                "base": {s: _number(c.stat(s, "base")) for s in ("p10", "p50", "p90")},
                "other": {s: _number(c.stat(s)) for s in ("p10", "p50", "p90")},
                "p50WorseBy": _number(c.stat_worse_by("p50")),
            }
            for c in comparison.changes
        ],
        "rules": [
            {"rule": r.rule.text, "value": _number(r.value), "violated": r.violated}
            for r in results
        ],
    }
