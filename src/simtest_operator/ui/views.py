"""What each page of the results UI shows: database answers turned into template context.

One function per page, ``(db, params) -> dict``; the server renders the dict with the page's
template, or returns it as JSON under ``/api/<page>``. Plots reuse the report's SVG pieces
(:mod:`simtest_operator.results.plots`) and detail loading
(:mod:`~simtest_operator.results.details`), so the UI and ``report.html`` draw a scenario
the same way.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.errors import SimtestError
from simtest_operator.results import (
    comparing,
    details,
    evidence,
    history,
    plots,
    records,
    reportmodel,
)
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.ui import queries
from simtest_operator.verdicts import Verdict

PAGE_SIZE = 50
MAX_RUNS = 1_000_000
"""Upper bound of every run-count parameter (``last``, ``runs``, ``limit``; ``page`` times
``PAGE_SIZE``): far above any database the UI was measured on (100,000 runs)."""


class NotFoundError(SimtestError):
    """A page names a run or scenario the database does not hold (HTTP 404)."""


class BadRequestError(SimtestError):
    """A page's parameters are invalid (HTTP 400)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Context:
    """What every view may use besides the database."""

    base_dir: Path | None = None
    """Where relative artifact paths start (the output folder of a local run)."""
    read_trajectories: details.TrajectoryReader | None = None
    """The recording reader (wired by the CLI; ``ui`` does not import ``recording``)."""
    search: SearchSectionOf | None = None
    """A searching run's *Search* section (wired by the CLI: the search engine sits above
    ``ui``)."""


View = Callable[[ReadOnlyDatabase, Mapping[str, str], Context], dict[str, Any]]
SearchSectionOf = Callable[
    [records.CampaignRecord, Sequence[records.StoredOutcome]], reportmodel.SearchSection | None
]


def _int(params: Mapping[str, str], name: str, default: int, *, maximum: int) -> int:
    """A whole-number parameter in ``[0, maximum]``: an unbounded one reached the database as an
    offset past 64 bits (``?page=99999999999999999999``: OverflowError, a 500)."""
    try:
        value = int(params.get(name, default))
    except ValueError:
        value = -1
    if not 0 <= value <= maximum:
        raise BadRequestError(f"parameter {name!r} must be a whole number from 0 to {maximum}")
    return value


def _run_or_newest(db: ReadOnlyDatabase, params: Mapping[str, str]) -> queries.RunRow:
    key = params.get("run") or params.get("key")
    if not key:
        newest = queries.runs(db, limit=1)
        if not newest:
            raise NotFoundError("the database holds no campaign runs yet")
        return newest[0]
    found = queries.run(db, key)
    if found is None:
        raise NotFoundError(f"no campaign run {key!r}")
    return found


def overview(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """Totals, the newest run's verdicts and the pass rate of recent runs."""
    recent = queries.trend(db, limit=_int(params, "last", 30, maximum=MAX_RUNS))
    newest = recent[-1] if recent else None
    return {
        "runs": queries.run_count(db),
        "scenarios": queries.scenario_count(db),
        "newest": newest,
        "trend": recent,
        "trend_chart": plots.stacked_bars(
            [
                (f"{r.name} {r.started_at:%Y-%m-%d %H:%M}" if r.started_at else r.run_key, r.counts)
                for r in reversed(recent[-10:])
            ]
        ),
    }


def runs(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """One page of campaign runs, newest first."""
    page = _int(params, "page", 0, maximum=MAX_RUNS // PAGE_SIZE)
    total = queries.run_count(db)
    return {
        "runs": queries.runs(db, limit=PAGE_SIZE, offset=page * PAGE_SIZE),
        "page": page,
        "pages": max(1, math.ceil(total / PAGE_SIZE)),
        "total": total,
    }


def run(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """One run: counts, its scenarios (failing and flaky first), previous run to compare."""
    row = _run_or_newest(db, params)
    outcomes = db.outcomes(row.run_key, final_only=False)
    final = comparing.final_outcomes(outcomes)
    flags = {s.scenario_id: s for s in history.summaries(db, scenario_ids=sorted(final))}
    scenarios: list[dict[str, Any]] = []
    for scenario_id, stored in final.items():
        summary = flags.get(scenario_id)
        scenarios.append(
            {
                "id": scenario_id,
                "verdict": stored.verdict.value,
                "reason": stored.outcome.reason,
                "attempt": stored.outcome.attempts,
                "category": stored.scenario.category,
                "road": stored.scenario.road,
                "requirements": evidence.requirements(stored.scenario.tags),
                "flakiness": summary.flakiness if summary else history.Flakiness.STABLE,
                "pass_rate": summary.pass_rate if summary else 0.0,
            }
        )
    scenarios.sort(
        key=lambda s: (s["verdict"] in ("Passed", "Skipped"), not s["flakiness"].flaky, s["id"])
    )
    search = None
    campaign = db.campaign(row.run_key) if context.search is not None else None
    if context.search is not None and campaign is not None:
        search = context.search(campaign, outcomes)
    return {
        "run": row,
        "scenarios": scenarios,
        "previous": queries.previous_run(db, row.run_key),
        "search": search,
    }


def coverage(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """One run's verdicts by tag, road, scenario type or requirement."""
    row = _run_or_newest(db, params)
    dimension = params.get("by", "category")
    if dimension not in queries.COVERAGE:
        raise BadRequestError(f"by must be one of {', '.join(queries.COVERAGE)}")
    evaluation, note = None, ""
    if dimension == "base":
        evaluation, groups = queries.base_scenarios(db, row.run_key)
        if evaluation is None:
            note = "this run has no evaluation yet: `simtest evaluate` decomposes its recordings"
    else:
        groups = queries.coverage(db, row.run_key, dimension)
    return {
        "run": row,
        "by": dimension,
        "dimensions": queries.COVERAGE,
        "evaluation": evaluation,
        "note": note,
        "groups": groups,
        "chart": plots.stacked_bars([(g.label, g.counts) for g in groups]),
    }


def scenario(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """The developer view: reason, attempts, metrics, trajectory replay and metric timelines."""
    row = _run_or_newest(db, params)
    scenario_id = params.get("id", "")
    attempts = db.outcomes(row.run_key, scenario_id=scenario_id, final_only=False)
    if not attempts:
        raise NotFoundError(f"scenario {scenario_id!r} has no result in run {row.run_key}")
    final = attempts[-1]
    extra = details.load(
        final, context.base_dir or Path.cwd(), read_trajectories=context.read_trajectories
    )
    summary = history.summaries(db, scenario_ids=[scenario_id])
    replay = {
        "entities": [
            {
                "name": t.entity,
                "ego": t.is_ego,
                "t": [p[0] for p in t.points],
                "x": [p[1] for p in t.points],
                "y": [p[2] for p in t.points],
            }
            for t in extra.trajectories
            if t.points
        ],
        "timelines": [
            {
                "name": s.name,
                "unit": s.unit,
                "t": [p[0] for p in s.points if math.isfinite(p[1])],
                "v": [p[1] for p in s.points if math.isfinite(p[1])],
            }
            for s in extra.timelines
        ],
    }
    return {
        "run": row,
        "id": scenario_id,
        "final": final,
        "earlier": attempts[:-1],
        "requirements": evidence.requirements(final.scenario.tags),
        "metrics": sorted(final.outcome.metrics.items()),
        "summary": summary[0] if summary else None,
        "trajectory_svg": plots.trajectories(extra.trajectories),
        "timelines": [(s.name, plots.timeline(s)) for s in extra.timelines],
        "notes": extra.notes,
        "replay": replay,
        "previous": queries.previous_run(db, row.run_key),
    }


def compare(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """Two runs side by side: new, fixed, regressed, still failing and removed scenarios."""
    other = _run_or_newest(db, {"run": params.get("other", "")})
    base_key = params.get("base") or queries.previous_run(db, other.run_key)
    if not base_key:
        raise NotFoundError(
            f"run {other.run_key} has no earlier run of its campaign to compare with"
        )
    base = _run_or_newest(db, {"run": base_key})
    comparison = comparing.compare(
        db.outcomes(base.run_key),
        db.outcomes(other.run_key),
        base_label=base.run_key,
        other_label=other.run_key,
    )
    return {
        "base": base,
        "other": other,
        "changes": [
            {
                "id": c.scenario_id,
                "change": c.change.value,
                "before": c.before.value if c.before else "",
                "after": c.after.value if c.after else "",
                "reason": c.reason_after or c.reason_before,
                "content_changed": c.content_changed,
            }
            for c in comparison.changes
        ],
        "counts": {k.value: v for k, v in comparison.counts().items()},
        "runs": queries.runs(db, limit=PAGE_SIZE),
    }


ORIGINAL = "original"
"""The side of an evaluation comparison that is the run's own verdicts (judged while it ran)."""


def evaluations(
    db: ReadOnlyDatabase, params: Mapping[str, str], context: Context
) -> dict[str, Any]:
    """One run's evaluations, and two of its judgements side by side: by default its original
    verdicts against its newest finished evaluation (``base``/``other``: ``original`` or an
    evaluation id)."""
    row = _run_or_newest(db, params)
    listed = queries.evaluations(db, row.run_key)
    known = {e.evaluation_id for e in listed}
    finished = [e for e in listed if e.finished_at is not None]
    base = params.get("base") or ORIGINAL
    other = params.get("other") or (finished[0].evaluation_id if finished else ORIGINAL)
    for side in (base, other):
        if side != ORIGINAL and side not in known:
            raise NotFoundError(f"no evaluation {side!r} of run {row.run_key}")
    before, after = _judgement(db, row.run_key, base), _judgement(db, row.run_key, other)
    changes = []
    for scenario_id in sorted(before.keys() | after.keys()):
        a, b = before.get(scenario_id), after.get(scenario_id)
        change = comparing.classify(Verdict(a[0]) if a else None, Verdict(b[0]) if b else None)
        changes.append(
            {
                "id": scenario_id,
                "change": change.value,
                "before": a[0] if a else "",
                "after": b[0] if b else "",
                "evidence": b[2] if b else "",
                "reason": (b or a or ("", "", ""))[1],
            }
        )
    counts = {c.value: 0 for c in comparing.Change}
    for entry in changes:
        counts[entry["change"]] += 1
    return {
        "run": row,
        "evaluations": listed,
        "base": base,
        "other": other,
        "changes": changes,
        "counts": counts,
        "note": ""
        if listed
        else "this run has no evaluation yet: `simtest evaluate` re-scores its recordings",
    }


def _judgement(db: ReadOnlyDatabase, run_key: str, side: str) -> dict[str, tuple[str, str, str]]:
    """Scenario id -> (verdict, reason, evidence) of the original verdicts or an evaluation."""
    if side != ORIGINAL:
        return queries.evaluated(db, side)
    final = comparing.final_outcomes(db.outcomes(run_key))
    return {k: (o.verdict.value, o.outcome.reason, "") for k, o in final.items()}


def sets(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """Pass rates per coverage label for each SUT version, simulator version or namespace."""
    axis = params.get("axis", "sut")
    dimension = params.get("by", "category")
    if axis not in queries.AXES or dimension not in queries.DIMENSIONS:
        raise BadRequestError(
            f"axis must be one of {', '.join(queries.AXES)}; "
            f"by one of {', '.join(queries.DIMENSIONS)}"
        )
    columns, rows = queries.metadata_sets(
        db, axis=axis, dimension=dimension, limit_runs=_int(params, "runs", 1000, maximum=MAX_RUNS)
    )
    return {
        "axis": axis,
        "by": dimension,
        "axes": queries.AXES,
        "dimensions": queries.DIMENSIONS,
        "columns": columns,
        "rows": rows,
    }


def flakiness(db: ReadOnlyDatabase, params: Mapping[str, str], context: Context) -> dict[str, Any]:
    """Every scenario's history summary, flaky first."""
    found = history.summaries(db)
    if params.get("flaky") == "1":
        found = tuple(s for s in found if s.flakiness.flaky)
    return {
        "summaries": found,
        "flaky": sum(1 for s in found if s.flakiness.flaky),
        "explanations": {f.value: f.explanation for f in history.Flakiness},
    }


def scenario_history(
    db: ReadOnlyDatabase, params: Mapping[str, str], context: Context
) -> dict[str, Any]:
    """One scenario across runs: each run's verdict, seed and versions; its flakiness."""
    scenario_id = params.get("id", "")
    found = history.scenario_history(
        db, scenario_id, limit=_int(params, "limit", 200, maximum=MAX_RUNS)
    )
    if not found.entries:
        raise NotFoundError(f"scenario {scenario_id!r} has no runs")
    return {
        "id": scenario_id,
        "history": found,
        "explanation": found.summary.flakiness.explanation,
        "strip": [
            (e.verdict, plots.VERDICT_COLOURS.get(e.verdict, "#999"), e.run_key)
            for e in reversed(found.entries)
        ],
    }


PAGES: dict[str, tuple[View, str]] = {
    "": (overview, "overview.html.j2"),
    "runs": (runs, "runs.html.j2"),
    "run": (run, "run.html.j2"),
    "coverage": (coverage, "coverage.html.j2"),
    "scenario": (scenario, "scenario.html.j2"),
    "compare": (compare, "compare.html.j2"),
    "evaluations": (evaluations, "evaluations.html.j2"),
    "sets": (sets, "sets.html.j2"),
    "history": (flakiness, "history.html.j2"),
    "history/scenario": (scenario_history, "scenario_history.html.j2"),
}
"""Path (without the leading ``/`` or ``/api/``) -> (view, template)."""
