"""The results UI's questions to the database, each one bounded SQL statement (or a few).

Kept apart from the server so they can be measured on their own (``bench/ui_queries.py``, 100,000
runs on PostgreSQL) and tested without HTTP. Every function takes a
:class:`~simtest_operator.results.querying.ReadOnlyDatabase` and returns plain values; a "run"
here is the final attempt of a scenario in one campaign run.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.results import evidence, history
from simtest_operator.results.querying import ReadOnlyDatabase

VERDICTS = ("Passed", "Failed", "Timeout", "Error", "Invalid", "Skipped")
DIMENSIONS = {
    "category": "Scenario type",
    "road": "Road network",
    "tag": "Tag",
    "requirement": "Requirement",
}
"""Labels of a scenario (file header): query value -> heading."""
COVERAGE = {**DIMENSIONS, "base": "Base scenario"}
"""Coverage dimensions: the scenario labels plus the base scenarios of the run's newest
evaluation (``simtest evaluate``), counted per base-scenario instance."""
AXES = {"sut": "SUT version", "simulator": "Simulator version", "namespace": "Namespace"}
"""Metadata a comparison of sets groups runs by: query value -> heading."""
_AXIS_SQL = {
    "sut": "c.sut_name || ' ' || c.sut_version",
    "simulator": "c.simulator_version",
    "namespace": "c.namespace",
}


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunRow:
    """One campaign run in a list, with its final-attempt verdict counts."""

    run_key: str
    name: str
    namespace: str
    started_at: datetime.datetime | None
    finished: bool
    phase: str
    sut: str
    simulator: str
    counts: Mapping[str, int]

    @property
    def total(self) -> int:
        """Scenarios with a stored verdict."""
        return sum(self.counts.values())

    @property
    def failing(self) -> int:
        """Scenarios whose verdict counts against the run."""
        return self.total - self.counts.get("Passed", 0) - self.counts.get("Skipped", 0)

    @property
    def pass_rate(self) -> float:
        """Passed over scenarios that ran (not Skipped); 0 when none did."""
        ran = self.total - self.counts.get("Skipped", 0)
        return self.counts.get("Passed", 0) / ran if ran else 0.0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Group:
    """Verdict counts of the scenarios sharing one coverage label (or metadata value)."""

    label: str
    counts: Mapping[str, int]

    @property
    def total(self) -> int:
        """Scenarios in the group."""
        return sum(self.counts.values())

    @property
    def passed(self) -> int:
        """Passed scenarios."""
        return self.counts.get("Passed", 0)

    @property
    def pass_rate(self) -> float:
        """Passed over scenarios that ran (not Skipped); 0 when none did."""
        ran = self.total - self.counts.get("Skipped", 0)
        return self.passed / ran if ran else 0.0


def run_count(db: ReadOnlyDatabase) -> int:
    """How many campaign runs the database holds."""
    return int(db.query("SELECT COUNT(*) FROM campaigns")[0][0])


def runs(db: ReadOnlyDatabase, *, limit: int = 50, offset: int = 0) -> tuple[RunRow, ...]:
    """Campaign runs, newest first, with their verdict counts (one page)."""
    rows = db.query(
        "SELECT run_key, name, namespace, started_at, finished_at, phase, "
        "sut_name || ' ' || sut_version, simulator_version FROM campaigns "
        "ORDER BY started_at DESC, run_key DESC LIMIT ? OFFSET ?",
        (limit, offset),
    )
    counts = _counts(db, [str(row[0]) for row in rows])
    return tuple(
        RunRow(
            run_key=str(row[0]),
            name=str(row[1]),
            namespace=str(row[2]),
            started_at=db.time(row[3]),
            finished=row[4] is not None,
            phase=str(row[5]),
            sut=str(row[6]).strip(),
            simulator=str(row[7]),
            counts=counts.get(str(row[0]), {}),
        )
        for row in rows
    )


def run(db: ReadOnlyDatabase, run_key: str) -> RunRow | None:
    """One run's row, or ``None`` for an unknown key."""
    rows = db.query(
        "SELECT run_key, name, namespace, started_at, finished_at, phase, "
        "sut_name || ' ' || sut_version, simulator_version FROM campaigns WHERE run_key = ?",
        (run_key,),
    )
    if not rows:
        return None
    row = rows[0]
    return RunRow(
        run_key=str(row[0]), name=str(row[1]), namespace=str(row[2]), started_at=db.time(row[3]),
        finished=row[4] is not None, phase=str(row[5]), sut=str(row[6]).strip(),
        simulator=str(row[7]), counts=_counts(db, [run_key]).get(run_key, {}),
    )  # fmt: skip


def _counts(db: ReadOnlyDatabase, keys: Sequence[str]) -> dict[str, dict[str, int]]:
    if not keys:
        return {}
    found: dict[str, dict[str, int]] = {}
    for key, verdict, count in db.query(
        f"SELECT r.run_key, r.verdict, COUNT(*) FROM runs r WHERE r.run_key IN "
        f"({', '.join('?' * len(keys))}) AND {history.FINAL_ATTEMPT} GROUP BY r.run_key, r.verdict",
        tuple(keys),
    ):
        found.setdefault(str(key), {})[str(verdict)] = int(count)
    return found


def _has_evaluations(db: ReadOnlyDatabase) -> bool:
    """Whether the schema has the evaluation tables (version 4 and later)."""
    return int(db.query("SELECT MAX(version) FROM schema_migrations")[0][0] or 0) >= 4


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluationRow:
    """One evaluation of a run (``simtest evaluate`` or the cluster's evaluation step)."""

    evaluation_id: str
    criteria_name: str
    created_at: datetime.datetime | None
    finished_at: datetime.datetime | None
    """None: interrupted (``simtest compare`` skips it)."""
    counts: Mapping[str, int]
    """Verdicts of the evaluated scenarios."""


def evaluations(db: ReadOnlyDatabase, run_key: str) -> tuple[EvaluationRow, ...]:
    """The run's evaluations, newest first, with their verdict counts."""
    if not _has_evaluations(db):
        return ()
    counts: dict[str, dict[str, int]] = {}
    for evaluation_id, verdict, count in db.query(
        # Through the run's evaluations (indexed by run) to their rows (keyed by evaluation).
        "SELECT r.evaluation_id, r.verdict, COUNT(*) FROM evaluations e "
        "JOIN evaluated_runs r ON r.evaluation_id = e.evaluation_id WHERE e.run_key = ? "
        "GROUP BY r.evaluation_id, r.verdict",
        (run_key,),
    ):
        counts.setdefault(str(evaluation_id), {})[str(verdict)] = int(count)
    return tuple(
        EvaluationRow(
            evaluation_id=str(evaluation_id),
            criteria_name=str(name),
            created_at=db.time(created),
            finished_at=db.time(finished),
            counts=counts.get(str(evaluation_id), {}),
        )
        for evaluation_id, name, created, finished in db.query(
            "SELECT evaluation_id, criteria_name, created_at, finished_at FROM evaluations "
            "WHERE run_key = ? ORDER BY created_at DESC, evaluation_id DESC",
            (run_key,),
        )
    )


def evaluated(db: ReadOnlyDatabase, evaluation_id: str) -> dict[str, tuple[str, str, str]]:
    """Scenario id -> (verdict, reason, evidence) of one evaluation (its last attempt each)."""
    found: dict[str, tuple[str, str, str]] = {}
    for scenario_id, verdict, reason, evidence_ in db.query(
        "SELECT scenario_id, verdict, reason, evidence FROM evaluated_runs "
        "WHERE evaluation_id = ? ORDER BY scenario_id, attempt",
        (evaluation_id,),
    ):
        found[str(scenario_id)] = (str(verdict), str(reason), str(evidence_))
    return found


def base_scenarios(db: ReadOnlyDatabase, run_key: str) -> tuple[str | None, tuple[Group, ...]]:
    """(evaluation id, verdict counts per base-scenario kind) of the run's newest evaluation;
    ``(None, ())`` when the run was never evaluated or the schema predates evaluations."""
    if not _has_evaluations(db):
        return None, ()
    newest = db.query(
        "SELECT evaluation_id FROM evaluations WHERE run_key = ? "
        "ORDER BY created_at DESC, evaluation_id DESC LIMIT 1",
        (run_key,),
    )
    if not newest:
        return None, ()
    groups: dict[str, dict[str, int]] = {}
    for kind, verdict, count in db.query(
        "SELECT kind, verdict, COUNT(*) FROM base_scenarios WHERE evaluation_id = ? "
        "GROUP BY kind, verdict",
        (newest[0][0],),
    ):
        groups.setdefault(str(kind), {})[str(verdict)] = int(count)
    return str(newest[0][0]), tuple(Group(label=k, counts=v) for k, v in sorted(groups.items()))


def _label_sql(db: ReadOnlyDatabase, dimension: str) -> tuple[str, str]:
    """(FROM addition, label expression) of a coverage dimension over ``scenarios s``; for tags
    and requirements only scenarios with such a label appear."""
    if dimension in ("category", "road"):
        return "", f"s.{dimension}"
    if dimension in ("tag", "requirement"):
        return f", {db.json_items('s.tags')}", "item.value"
    raise ValueError(f"unknown coverage dimension {dimension!r}; one of {', '.join(DIMENSIONS)}")


def labels_of(dimension: str, category: str, road: str, tags: Sequence[str]) -> tuple[str, ...]:
    """A scenario's labels in one coverage dimension (``(none)`` when it has none)."""
    if dimension == "category":
        found: tuple[str, ...] = (category,)
    elif dimension == "road":
        found = (road,)
    elif dimension == "tag":
        found = tuple(t for t in tags if not t.startswith(evidence.REQUIREMENT_PREFIX))
    elif dimension == "requirement":
        found = evidence.requirements(tags)
    else:
        raise ValueError(
            f"unknown coverage dimension {dimension!r}; one of {', '.join(DIMENSIONS)}"
        )
    return tuple(label for label in found if label) or ("(none)",)


def coverage(db: ReadOnlyDatabase, run_key: str, dimension: str) -> tuple[Group, ...]:
    """Verdict counts of one run's scenarios grouped by ``dimension`` (see :data:`DIMENSIONS`);
    ``requirement`` groups by the ``req:`` tags (:func:`evidence.requirements`)."""
    rows = db.query(
        "SELECT r.verdict, s.category, s.road, s.tags FROM runs r JOIN scenarios s "
        "ON s.scenario_id = r.scenario_id AND s.sha256 = r.sha256 "
        f"WHERE r.run_key = ? AND {history.FINAL_ATTEMPT}",
        (run_key,),
    )
    groups: dict[str, dict[str, int]] = {}
    for verdict, category, road, tags in rows:
        for label in labels_of(dimension, str(category), str(road), tuple(db.json(tags))):
            counts = groups.setdefault(label, {})
            counts[str(verdict)] = counts.get(str(verdict), 0) + 1
    return tuple(Group(label=k, counts=v) for k, v in sorted(groups.items()))


def metadata_sets(
    db: ReadOnlyDatabase, *, axis: str, dimension: str, limit_runs: int = 1000
) -> tuple[tuple[str, ...], tuple[tuple[str, Mapping[str, Group]], ...]]:
    """Pass rates of each ``dimension`` label per value of ``axis`` (SUT version, simulator
    version, namespace) over the newest ``limit_runs`` runs: (axis values, rows of groups)."""
    if axis not in _AXIS_SQL:
        raise ValueError(f"unknown comparison axis {axis!r}; one of {', '.join(AXES)}")
    extra, label = _label_sql(db, dimension)
    # Count per (axis value, scenario content, verdict) first -- 100,000 runs fold into a few
    # thousand rows -- and only then join the scenarios and unfold their tags.
    rows = db.query(
        f"SELECT g.axis, {label}, g.verdict, SUM(g.n) FROM (SELECT c.axis, "
        "r.scenario_id, r.sha256, r.verdict, COUNT(*) AS n FROM runs r "
        f"JOIN (SELECT run_key, {_AXIS_SQL[axis]} AS axis FROM campaigns c "
        "ORDER BY started_at DESC LIMIT ?) c ON c.run_key = r.run_key "
        f"WHERE {history.FINAL_ATTEMPT} GROUP BY c.axis, r.scenario_id, r.sha256, r.verdict) g "
        "JOIN scenarios s ON s.scenario_id = g.scenario_id AND s.sha256 = g.sha256"
        f"{extra} GROUP BY g.axis, {label}, g.verdict",
        (limit_runs,),
    )
    table: dict[str, dict[str, dict[str, int]]] = {}
    for value, raw, verdict, count in rows:
        text = str(raw or "(none)")
        if dimension == "requirement":
            if not evidence.requirements([text]):
                continue
            text = evidence.requirements([text])[0]
        elif dimension == "tag" and text.startswith(evidence.REQUIREMENT_PREFIX):
            continue
        cell = table.setdefault(text, {}).setdefault(str(value).strip(), {})
        cell[str(verdict)] = cell.get(str(verdict), 0) + int(count)
    columns = tuple(sorted({value for cells in table.values() for value in cells}))
    return columns, tuple(
        (label_, {value: Group(label=value, counts=counts) for value, counts in cells.items()})
        for label_, cells in sorted(table.items())
    )


def trend(db: ReadOnlyDatabase, *, limit: int = 30) -> tuple[RunRow, ...]:
    """The newest ``limit`` runs, oldest first (the overview's pass-rate chart)."""
    return tuple(reversed(runs(db, limit=limit)))


def scenario_count(db: ReadOnlyDatabase) -> int:
    """Distinct scenario ids ever listed."""
    return int(db.query("SELECT COUNT(DISTINCT scenario_id) FROM scenarios")[0][0])


def run_keys_of(db: ReadOnlyDatabase, scenario_id: str, *, limit: int = 2) -> tuple[str, ...]:
    """The newest runs of a scenario (for "compare with the previous run" links)."""
    rows = db.query(
        "SELECT r.run_key FROM runs r JOIN campaigns c ON c.run_key = r.run_key "
        "WHERE r.scenario_id = ? GROUP BY r.run_key, c.started_at "
        "ORDER BY c.started_at DESC LIMIT ?",
        (scenario_id, limit),
    )
    return tuple(str(row[0]) for row in rows)


def previous_run(db: ReadOnlyDatabase, run_key: str) -> str | None:
    """The run of the same campaign (name and namespace) that started just before ``run_key``."""
    rows = db.query(
        "SELECT p.run_key FROM campaigns c JOIN campaigns p ON p.name = c.name "
        "AND p.namespace = c.namespace AND p.started_at < c.started_at WHERE c.run_key = ? "
        "ORDER BY p.started_at DESC LIMIT 1",
        (run_key,),
    )
    return str(rows[0][0]) if rows else None


def as_json(value: Any) -> Any:
    """Plain JSON values of the dataclasses above (for the ``/api`` endpoints)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out = {f.name: as_json(getattr(value, f.name)) for f in dataclasses.fields(value)}
        for extra in ("total", "failing", "passed", "pass_rate"):
            if hasattr(type(value), extra) and extra not in out:
                out[extra] = as_json(getattr(value, extra))
        return out
    if isinstance(value, datetime.datetime):
        return value.isoformat()
    if isinstance(value, Mapping):
        return {str(k): as_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [as_json(v) for v in value]
    if isinstance(value, history.Flakiness):
        return value.value
    return value
