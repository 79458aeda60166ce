"""The store logic both databases share: every query, written once, over a tiny driver seam.

A concrete store supplies a transaction (:meth:`SqlStore._transaction`) yielding a :class:`Tx`
that runs ``?``-parameterised SQL, and a :class:`Codec` for the values whose representation
differs (JSON, timestamps). Everything else -- upserts, idempotency, ordering, the shape of the
returned records -- lives here, so SQLite and PostgreSQL cannot drift apart.
"""

from __future__ import annotations

import abc
import contextlib
import datetime
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from types import TracebackType
from typing import Protocol, Self

from simtest_operator.errors import ResultsError
from simtest_operator.results import comparing, migrating, records, sqlrows
from simtest_operator.results.evaluationstore import EvaluationQueries
from simtest_operator.verdicts import ScenarioOutcome

Clock = Callable[[], datetime.datetime]


def utc_now() -> datetime.datetime:
    """The default clock of a store (used only for ``recorded_at`` and migration times)."""
    return datetime.datetime.now(datetime.UTC)


class Tx(Protocol):
    """One open transaction."""

    def query(self, sql: str, params: Sequence[object] = ()) -> list[sqlrows.Row]:
        """Run a statement and return its rows (empty for statements without a result)."""
        ...

    def execute_many(self, sql: str, rows: Iterable[Sequence[object]]) -> None:
        """Run a statement once per parameter row."""
        ...


def require_aware(value: datetime.datetime, what: str) -> datetime.datetime:
    """Timestamps are stored in UTC; a naive one would be silently misread, so reject it."""
    if value.tzinfo is None:
        raise ResultsError(f"{what} must be timezone-aware, got naive {value.isoformat()}")
    return value.astimezone(datetime.UTC)


class SqlStore(abc.ABC, EvaluationQueries):
    """Implements :class:`~simtest_operator.results.stores.Store` over :class:`Tx`."""

    dialect: migrating.Dialect

    def __init__(self, *, codec: sqlrows.Codec, clock: Clock = utc_now) -> None:
        self._codec = codec
        self._clock = clock

    # --- driver seam -----------------------------------------------------------------------

    @abc.abstractmethod
    def _transaction(self, *, write: bool) -> contextlib.AbstractContextManager[Tx]:
        """A transaction that commits on success and rolls back on any exception."""

    def _lock_for_migration(self, tx: Tx) -> None:
        """Serialise concurrent migrators beyond what the write transaction already does."""

    @abc.abstractmethod
    def close(self) -> None:
        """Release the connection."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # --- schema ----------------------------------------------------------------------------

    def migrate(self, *, target: int | None = None) -> int:
        """Apply pending migrations (up to ``target``) in one transaction; returns the version."""
        with self._transaction(write=True) as tx:
            self._lock_for_migration(tx)
            tx.query(migrating.translate(migrating.BOOTSTRAP_SQL, self.dialect))
            applied = {int(row[0]) for row in tx.query("SELECT version FROM schema_migrations")}
            for migration in migrating.pending(migrating.load(), applied, target=target):
                for statement in migration.statements(self.dialect):
                    tx.query(statement)
                tx.query(
                    "INSERT INTO schema_migrations (version, name, applied_at) VALUES (?, ?, ?)",
                    (migration.version, migration.name, self._codec.time_in(self._clock())),
                )
                applied.add(migration.version)
            return max(applied, default=0)

    @property
    def schema_version(self) -> int:
        """The highest applied migration (0 for an empty database)."""
        with self._transaction(write=False) as tx:
            rows = tx.query("SELECT MAX(version) FROM schema_migrations")
        return int(rows[0][0] or 0)

    # --- writing ---------------------------------------------------------------------------

    def begin_campaign(
        self,
        campaign: records.CampaignInfo,
        *,
        scenarios: Sequence[records.ScenarioInfo] = (),
        run_key: records.RunKey | None = None,
    ) -> records.RunKey:
        key = run_key or records.derive_run_key(campaign)
        started = require_aware(campaign.started_at, "started_at")
        codec = self._codec
        with self._transaction(write=True) as tx:
            tx.query(
                f"INSERT INTO campaigns ({sqlrows.CAMPAIGN_COLUMNS}) "
                "VALUES (?, ?, ?, ?, ?, NULL, '', ?, ?, ?, ?, ?) ON CONFLICT (run_key) DO NOTHING",
                (
                    key,
                    campaign.name,
                    campaign.namespace,
                    campaign.manifest_sha256,
                    codec.time_in(started),
                    campaign.sut_name,
                    campaign.sut_version,
                    campaign.simulator_version,
                    codec.json_in(dict(campaign.settings)),
                    codec.json_in({}),
                ),
            )
            owner = tx.query("SELECT name FROM campaigns WHERE run_key = ?", (key,))
            if owner[0][0] != campaign.name:
                raise ResultsError(
                    f"run {key} belongs to campaign {owner[0][0]!r}, not {campaign.name!r}"
                )
            self._upsert_scenarios(tx, scenarios)
            count = tx.query("SELECT COUNT(*) FROM campaign_scenarios WHERE run_key = ?", (key,))
            tx.execute_many(
                "INSERT INTO campaign_scenarios (run_key, position, scenario_id, sha256) "
                "VALUES (?, ?, ?, ?) ON CONFLICT (run_key, scenario_id) DO NOTHING",
                [
                    (key, int(count[0][0]) + index, s.scenario_id, s.sha256)
                    for index, s in enumerate(scenarios)
                ],
            )
        return key

    def add_outcome(
        self,
        run_key: records.RunKey,
        scenario: records.ScenarioInfo,
        outcome: ScenarioOutcome,
        *,
        content_hashes: Mapping[str, str] | None = None,
        recorded_at: datetime.datetime | None = None,
    ) -> None:
        if outcome.scenario_id != scenario.scenario_id:
            raise ResultsError(
                f"outcome of {outcome.scenario_id!r} given for scenario {scenario.scenario_id!r}"
            )
        hashes = {"scenario": scenario.sha256} if content_hashes is None else dict(content_hashes)
        when = require_aware(recorded_at or self._clock(), "recorded_at")
        attempt_key = (run_key, scenario.scenario_id, outcome.attempts)
        codec = self._codec
        with self._transaction(write=True) as tx:
            if not tx.query("SELECT 1 FROM campaigns WHERE run_key = ?", (run_key,)):
                raise ResultsError(f"unknown campaign run {run_key!r}; call begin_campaign first")
            self._upsert_scenarios(tx, (scenario,))
            listed = tx.query(
                "SELECT 1 FROM campaign_scenarios WHERE run_key = ? AND scenario_id = ?",
                (run_key, scenario.scenario_id),
            )
            if not listed:  # outside the frozen list: append it (the MAX scan is rare)
                tx.query(
                    "INSERT INTO campaign_scenarios (run_key, position, scenario_id, sha256) "
                    "SELECT ?, COALESCE(MAX(position), -1) + 1, ?, ? FROM campaign_scenarios "
                    "WHERE run_key = ? ON CONFLICT (run_key, scenario_id) DO NOTHING",
                    (run_key, scenario.scenario_id, scenario.sha256, run_key),
                )
            tx.query(
                "INSERT INTO runs (run_key, scenario_id, attempt, sha256, verdict, reason, "
                "simulated_seconds, wall_seconds, artifacts, content_hashes, versions, "
                "recorded_at, ignored_elements) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
                "ON CONFLICT (run_key, scenario_id, attempt) DO UPDATE SET "
                "sha256 = excluded.sha256, verdict = excluded.verdict, reason = excluded.reason, "
                "simulated_seconds = excluded.simulated_seconds, "
                "wall_seconds = excluded.wall_seconds, artifacts = excluded.artifacts, "
                "content_hashes = excluded.content_hashes, versions = excluded.versions, "
                "recorded_at = excluded.recorded_at, ignored_elements = excluded.ignored_elements",
                (
                    *attempt_key,
                    scenario.sha256,
                    outcome.verdict.value,
                    outcome.reason,
                    outcome.simulated_seconds,
                    outcome.wall_seconds,
                    codec.json_in(dict(outcome.artifacts)),
                    codec.json_in(hashes),
                    codec.json_in(dict(outcome.versions)),
                    codec.time_in(when),
                    codec.json_in(list(outcome.ignored_elements)),
                ),
            )
            tx.query(
                "DELETE FROM metrics WHERE run_key = ? AND scenario_id = ? AND attempt = ?",
                attempt_key,
            )
            tx.execute_many(
                "INSERT INTO metrics (run_key, scenario_id, attempt, name, value) "
                "VALUES (?, ?, ?, ?, ?)",
                [
                    (*attempt_key, name, None if math.isnan(value) else value)
                    for name, value in sorted(outcome.metrics.items())
                ],
            )

    def add_versions(
        self,
        run_key: records.RunKey,
        additions: Mapping[tuple[str, int], Mapping[str, str]],
    ) -> None:
        codec = self._codec
        where = "WHERE run_key = ? AND scenario_id = ? AND attempt = ?"
        with self._transaction(write=True) as tx:
            for (scenario_id, attempt), entries in sorted(additions.items()):
                key = (run_key, scenario_id, attempt)
                found = tx.query(f"SELECT versions FROM runs {where}", key)
                if not found or not entries:
                    continue
                merged = {**(codec.json_out(found[0][0]) or {}), **entries}
                tx.query(f"UPDATE runs SET versions = ? {where}", (codec.json_in(merged), *key))

    def finish_campaign(
        self,
        run_key: records.RunKey,
        *,
        finished_at: datetime.datetime,
        phase: str,
        counts: Mapping[str, int] | None = None,
        info: records.CampaignInfo | None = None,
    ) -> None:
        codec = self._codec
        when = codec.time_in(require_aware(finished_at, "finished_at"))
        with self._transaction(write=True) as tx:
            owner = tx.query("SELECT name FROM campaigns WHERE run_key = ?", (run_key,))
            if not owner:
                raise ResultsError(f"unknown campaign run {run_key!r}")
            if info is not None and owner[0][0] != info.name:
                raise ResultsError(
                    f"run {run_key} belongs to campaign {owner[0][0]!r}, not {info.name!r}"
                )
            tx.query(
                "UPDATE campaigns SET finished_at = ?, phase = ? WHERE run_key = ?",
                (when, phase, run_key),
            )
            if counts is not None:
                tx.query(
                    "UPDATE campaigns SET counts = ? WHERE run_key = ?",
                    (codec.json_in({str(k): int(v) for k, v in counts.items()}), run_key),
                )
            if info is not None:
                tx.query(
                    "UPDATE campaigns SET namespace = ?, manifest_sha256 = ?, started_at = ?, "
                    "sut_name = ?, sut_version = ?, simulator_version = ?, settings = ? "
                    "WHERE run_key = ?",
                    (
                        info.namespace,
                        info.manifest_sha256,
                        codec.time_in(require_aware(info.started_at, "started_at")),
                        info.sut_name,
                        info.sut_version,
                        info.simulator_version,
                        codec.json_in(dict(info.settings)),
                        run_key,
                    ),
                )

    def _upsert_scenarios(self, tx: Tx, scenarios: Iterable[records.ScenarioInfo]) -> None:
        # A row is one file content (id + sha256), so its labels never change; a writer that did
        # not read the file (the operator lists the frozen list without headers) sends blanks,
        # and a blank must not erase what a pod or the local runner read from the header.
        tx.execute_many(
            "INSERT INTO scenarios (scenario_id, sha256, source, tags, category, road) "
            "VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (scenario_id, sha256) DO UPDATE SET "
            "source = CASE WHEN excluded.source = '' THEN scenarios.source "
            "ELSE excluded.source END, "
            "tags = CASE WHEN ? THEN excluded.tags ELSE scenarios.tags END, "
            "category = CASE WHEN excluded.category = ? THEN scenarios.category "
            "ELSE excluded.category END, "
            "road = CASE WHEN excluded.road = '' THEN scenarios.road ELSE excluded.road END",
            [
                (
                    s.scenario_id,
                    s.sha256,
                    s.source,
                    self._codec.json_in(list(s.tags)),
                    s.category,
                    s.road,
                    bool(s.tags),
                    records.UNCATEGORIZED,
                )
                for s in scenarios
            ],
        )

    # --- reading ---------------------------------------------------------------------------

    def campaigns(
        self, *, name: str | None = None, namespace: str | None = None, limit: int = 50
    ) -> tuple[records.CampaignRecord, ...]:
        where, params = [], []
        if name is not None:
            where.append("name = ?")
            params.append(name)
        if namespace is not None:
            where.append("namespace = ?")
            params.append(namespace)
        clause = f" WHERE {' AND '.join(where)}" if where else ""
        with self._transaction(write=False) as tx:
            rows = tx.query(
                f"SELECT {sqlrows.CAMPAIGN_COLUMNS} FROM campaigns{clause} "
                "ORDER BY started_at DESC, run_key DESC LIMIT ?",
                (*params, limit),
            )
        return tuple(sqlrows.campaign(self._codec, row) for row in rows)

    def campaign(self, run_key: records.RunKey) -> records.CampaignRecord | None:
        with self._transaction(write=False) as tx:
            rows = tx.query(
                f"SELECT {sqlrows.CAMPAIGN_COLUMNS} FROM campaigns WHERE run_key = ?", (run_key,)
            )
        return sqlrows.campaign(self._codec, rows[0]) if rows else None

    def scenarios(self, run_key: records.RunKey) -> tuple[records.ScenarioInfo, ...]:
        with self._transaction(write=False) as tx:
            rows = tx.query(
                "SELECT s.scenario_id, s.sha256, s.source, s.tags, s.category, s.road "
                "FROM campaign_scenarios c JOIN scenarios s "
                "ON s.scenario_id = c.scenario_id AND s.sha256 = c.sha256 "
                "WHERE c.run_key = ? ORDER BY c.position",
                (run_key,),
            )
        return tuple(sqlrows.scenario(self._codec, *row) for row in rows)

    def outcomes(
        self, run_key: records.RunKey, *, final_only: bool = True
    ) -> tuple[records.StoredOutcome, ...]:
        with self._transaction(write=False) as tx:
            rows = tx.query(
                f"SELECT {sqlrows.OUTCOME_COLUMNS} FROM runs r JOIN scenarios s "
                "ON s.scenario_id = r.scenario_id AND s.sha256 = r.sha256 WHERE r.run_key = ?",
                (run_key,),
            )
            metric_rows = tx.query(
                "SELECT scenario_id, attempt, name, value FROM metrics WHERE run_key = ?",
                (run_key,),
            )
        metrics: dict[tuple[str, int], dict[str, float]] = {}
        for scenario_id, attempt, name, value in metric_rows:
            metrics.setdefault((scenario_id, int(attempt)), {})[name] = (
                math.nan if value is None else float(value)
            )
        stored = [sqlrows.outcome(self._codec, row, metrics) for row in rows]
        # Sorted here, not in SQL: PostgreSQL collations differ from SQLite's byte order.
        stored.sort(key=lambda s: (s.scenario.scenario_id, s.outcome.attempts))
        if final_only:
            return tuple(comparing.final_outcomes(stored).values())
        return tuple(stored)

    def compare(self, base: records.RunKey, other: records.RunKey) -> comparing.Comparison:
        return comparing.compare(
            self.outcomes(base), self.outcomes(other), base_label=base, other_label=other
        )
