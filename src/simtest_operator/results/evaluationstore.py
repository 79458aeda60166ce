"""Evaluation queries, shared by SQLite and PostgreSQL (mixed into :class:`.sqlstore.SqlStore`).

Same rules as the rest of the store: one transaction per call, idempotent per (evaluation,
scenario, attempt) -- storing an evaluated attempt again replaces it with its base scenarios.
"""

from __future__ import annotations

import contextlib
import datetime
import math
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from typing import Protocol

from simtest_operator.errors import ResultsError
from simtest_operator.results import evaluations as ev
from simtest_operator.results import records, sqlrows
from simtest_operator.verdicts import Verdict

_EVALUATION_COLUMNS = (
    "evaluation_id, run_key, criteria_name, criteria, created_at, finished_at, versions"
)


class _Tx(Protocol):
    """What :class:`.sqlstore.Tx` offers (redeclared: sqlstore imports this module)."""

    def query(self, sql: str, params: Sequence[object] = ()) -> list[sqlrows.Row]: ...

    def execute_many(self, sql: str, rows: Iterable[Sequence[object]]) -> None: ...


def _number(value: float) -> float | None:
    return None if math.isnan(value) else value


def _aware(value: datetime.datetime, what: str) -> datetime.datetime:
    if value.tzinfo is None:
        raise ResultsError(f"{what} must be timezone-aware, got naive {value.isoformat()}")
    return value.astimezone(datetime.UTC)


class EvaluationStore(Protocol):
    """What a store offers for evaluations (implemented by :class:`EvaluationQueries`)."""

    def begin_evaluation(self, info: ev.EvaluationInfo) -> ev.EvaluationId: ...

    def add_evaluated_run(self, evaluation_id: ev.EvaluationId, run: ev.EvaluatedRun) -> None: ...

    def finish_evaluation(
        self, evaluation_id: ev.EvaluationId, *, finished_at: datetime.datetime
    ) -> None: ...

    def evaluations(self, run_key: records.RunKey) -> tuple[ev.EvaluationRecord, ...]: ...

    def evaluation(self, evaluation_id: ev.EvaluationId) -> ev.EvaluationRecord | None: ...

    def evaluated_runs(self, evaluation_id: ev.EvaluationId) -> tuple[ev.EvaluatedRun, ...]: ...


class EvaluationQueries:
    """The evaluation methods over the store's transaction and codec."""

    _codec: sqlrows.Codec
    _clock: Callable[[], datetime.datetime]

    def _transaction(self, *, write: bool) -> contextlib.AbstractContextManager[_Tx]:
        raise NotImplementedError  # provided by SqlStore

    def begin_evaluation(self, info: ev.EvaluationInfo) -> ev.EvaluationId:
        """Record a new evaluation of a stored run; returns its id."""
        evaluation_id = ev.derive_evaluation_id(info)
        codec = self._codec
        with self._transaction(write=True) as tx:
            if not tx.query("SELECT 1 FROM campaigns WHERE run_key = ?", (info.run_key,)):
                raise ResultsError(f"unknown campaign run {info.run_key!r}")
            tx.query(
                f"INSERT INTO evaluations ({_EVALUATION_COLUMNS}, criteria_sha256) "
                "VALUES (?, ?, ?, ?, ?, NULL, ?, ?) ON CONFLICT (evaluation_id) DO NOTHING",
                (
                    evaluation_id,
                    info.run_key,
                    info.criteria_name,
                    codec.json_in(dict(info.criteria)),
                    codec.time_in(_aware(info.created_at, "created_at")),
                    codec.json_in(dict(info.versions)),
                    info.criteria_sha256,
                ),
            )
        return evaluation_id

    def add_evaluated_run(self, evaluation_id: ev.EvaluationId, run: ev.EvaluatedRun) -> None:
        """Store one evaluated attempt with its metrics and base scenarios, atomically."""
        if run.evidence not in ev.EVIDENCE:
            raise ResultsError(f"evidence must be one of {ev.EVIDENCE}, got {run.evidence!r}")
        codec = self._codec
        key = (evaluation_id, run.scenario_id, run.attempt)
        with self._transaction(write=True) as tx:
            owner = tx.query(
                "SELECT run_key FROM evaluations WHERE evaluation_id = ?", (evaluation_id,)
            )
            if not owner:
                raise ResultsError(f"unknown evaluation {evaluation_id!r}")
            run_key = owner[0][0]
            if not tx.query(
                "SELECT 1 FROM runs WHERE run_key = ? AND scenario_id = ? AND attempt = ?",
                (run_key, run.scenario_id, run.attempt),
            ):
                raise ResultsError(
                    f"run {run_key} has no attempt {run.attempt} of {run.scenario_id!r}"
                )
            tx.query(
                "DELETE FROM evaluated_runs WHERE evaluation_id = ? AND scenario_id = ? "
                "AND attempt = ?",
                key,
            )
            now = self._clock()
            tx.query(
                "INSERT INTO evaluated_runs (evaluation_id, run_key, scenario_id, attempt, "
                "verdict, reason, evidence, quality, issues, recording, recorded_at) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    evaluation_id,
                    run_key,
                    run.scenario_id,
                    run.attempt,
                    run.verdict.value,
                    run.reason,
                    run.evidence,
                    codec.json_in({k: _number(v) for k, v in run.quality.items()}),
                    codec.json_in(list(run.issues)),
                    run.recording,
                    codec.time_in(_aware(now, "recorded_at")),
                ),
            )
            tx.execute_many(
                "INSERT INTO evaluated_metrics (evaluation_id, scenario_id, attempt, name, value) "
                "VALUES (?, ?, ?, ?, ?)",
                [(*key, name, _number(value)) for name, value in sorted(run.metrics.items())],
            )
            tx.execute_many(
                "INSERT INTO base_scenarios (evaluation_id, scenario_id, attempt, position, "
                "kind, actor, start_seconds, end_seconds, verdict, reason, detail) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                [
                    (
                        *key,
                        position,
                        b.kind,
                        b.actor,
                        b.start,
                        b.end,
                        b.verdict.value,
                        b.reason,
                        b.detail,
                    )
                    for position, b in enumerate(run.base_scenarios)
                ],
            )
            tx.execute_many(
                "INSERT INTO base_scenario_metrics (evaluation_id, scenario_id, attempt, "
                "position, name, value, threshold, passed) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [
                    (
                        *key,
                        position,
                        name,
                        _number(m.value),
                        m.threshold,
                        None if m.passed is None else int(m.passed),
                    )
                    for position, b in enumerate(run.base_scenarios)
                    for name, m in sorted(b.metrics.items())
                ],
            )

    def finish_evaluation(
        self, evaluation_id: ev.EvaluationId, *, finished_at: datetime.datetime
    ) -> None:
        """Mark an evaluation complete (an unfinished one was interrupted)."""
        with self._transaction(write=True) as tx:
            if not tx.query("SELECT 1 FROM evaluations WHERE evaluation_id = ?", (evaluation_id,)):
                raise ResultsError(f"unknown evaluation {evaluation_id!r}")
            tx.query(
                "UPDATE evaluations SET finished_at = ? WHERE evaluation_id = ?",
                (self._codec.time_in(_aware(finished_at, "finished_at")), evaluation_id),
            )

    def _evaluation(self, row: sqlrows.Row) -> ev.EvaluationRecord:
        codec = self._codec
        return ev.EvaluationRecord(
            evaluation_id=ev.EvaluationId(row[0]),
            info=ev.EvaluationInfo(
                run_key=records.RunKey(row[1]),
                criteria_name=row[2],
                criteria=codec.json_out(row[3]),
                created_at=codec.time_out(row[4]),
                versions=codec.json_out(row[6]),
            ),
            finished_at=None if row[5] is None else codec.time_out(row[5]),
        )

    def evaluations(self, run_key: records.RunKey) -> tuple[ev.EvaluationRecord, ...]:
        """The evaluations of one run, newest first."""
        with self._transaction(write=False) as tx:
            rows = tx.query(
                f"SELECT {_EVALUATION_COLUMNS} FROM evaluations WHERE run_key = ? "
                "ORDER BY created_at DESC, evaluation_id DESC",
                (run_key,),
            )
        return tuple(self._evaluation(row) for row in rows)

    def evaluation(self, evaluation_id: ev.EvaluationId) -> ev.EvaluationRecord | None:
        with self._transaction(write=False) as tx:
            rows = tx.query(
                f"SELECT {_EVALUATION_COLUMNS} FROM evaluations WHERE evaluation_id = ?",
                (evaluation_id,),
            )
        return self._evaluation(rows[0]) if rows else None

    def evaluated_runs(self, evaluation_id: ev.EvaluationId) -> tuple[ev.EvaluatedRun, ...]:
        """Every evaluated attempt of an evaluation, by scenario id and attempt."""
        codec = self._codec
        with self._transaction(write=False) as tx:
            runs = tx.query(
                "SELECT scenario_id, attempt, verdict, reason, evidence, quality, issues, "
                "recording FROM evaluated_runs WHERE evaluation_id = ?",
                (evaluation_id,),
            )
            metric_rows = tx.query(
                "SELECT scenario_id, attempt, name, value FROM evaluated_metrics "
                "WHERE evaluation_id = ?",
                (evaluation_id,),
            )
            base_rows = tx.query(
                "SELECT scenario_id, attempt, position, kind, actor, start_seconds, end_seconds, "
                "verdict, reason, detail FROM base_scenarios WHERE evaluation_id = ?",
                (evaluation_id,),
            )
            check_rows = tx.query(
                "SELECT scenario_id, attempt, position, name, value, threshold, passed "
                "FROM base_scenario_metrics WHERE evaluation_id = ?",
                (evaluation_id,),
            )
        metrics: dict[tuple[str, int], dict[str, float]] = defaultdict(dict)
        for scenario_id, attempt, name, value in metric_rows:
            metrics[(scenario_id, int(attempt))][name] = math.nan if value is None else value
        checks: dict[tuple[str, int, int], dict[str, ev.MetricCheck]] = defaultdict(dict)
        for scenario_id, attempt, position, name, value, threshold, passed in check_rows:
            checks[(scenario_id, int(attempt), int(position))][name] = ev.MetricCheck(
                value=math.nan if value is None else float(value),
                threshold=None if threshold is None else float(threshold),
                passed=None if passed is None else bool(passed),
            )
        bases: dict[tuple[str, int], list[tuple[int, ev.StoredBaseScenario]]] = defaultdict(list)
        for (
            scenario_id,
            attempt,
            position,
            kind,
            actor,
            start,
            end,
            verdict,
            reason,
            detail,
        ) in base_rows:
            bases[(scenario_id, int(attempt))].append(
                (
                    int(position),
                    ev.StoredBaseScenario(
                        kind=kind,
                        actor=None if actor is None else int(actor),
                        start=float(start),
                        end=float(end),
                        verdict=Verdict(verdict),
                        reason=reason,
                        detail=detail,
                        metrics=checks[(scenario_id, int(attempt), int(position))],
                    ),
                )
            )
        result = [
            ev.EvaluatedRun(
                scenario_id=scenario_id,
                attempt=int(attempt),
                verdict=Verdict(verdict),
                reason=reason,
                evidence=evidence,
                quality={
                    k: math.nan if v is None else float(v)
                    for k, v in codec.json_out(quality).items()
                },
                issues=tuple(codec.json_out(issues)),
                metrics=metrics[(scenario_id, int(attempt))],
                base_scenarios=tuple(
                    b
                    for _, b in sorted(bases[(scenario_id, int(attempt))], key=lambda item: item[0])
                ),
                recording=recording,
            )
            for scenario_id, attempt, verdict, reason, evidence, quality, issues, recording in runs
        ]
        result.sort(key=lambda r: (r.scenario_id, r.attempt))
        return tuple(result)
