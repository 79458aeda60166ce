"""A read-only connection to a results database, for readers that need their own SQL.

History, flakiness, evidence export and the results UI ask aggregate questions the
:class:`~simtest_operator.results.stores.Store` protocol does not (pass rates over all runs,
coverage by tag over 100,000 rows). They run their SQL here: the same targets as
:func:`~simtest_operator.results.opening.open_store` (a DSN, an output folder, a SQLite file),
opened read-only so a reader can never change results, and never migrated (a reader must not
upgrade a database other processes write). Placeholders are sqlite3's ``?`` in both dialects.
"""

from __future__ import annotations

import datetime
import json
import sqlite3
import threading
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import psycopg

from simtest_operator.errors import ResultsError
from simtest_operator.results import comparing, dsn, migrating, records, sqlite, sqlrows

Row = tuple[Any, ...]
MINIMUM_VERSION = 3
"""The oldest schema the readers' SQL is written for (``campaigns.counts`` exists)."""


class ReadOnlyDatabase:
    """One read-only connection; each :meth:`query` is its own snapshot. Threads may share it
    (the results UI's server threads do): queries take turns."""

    def __init__(self, target: str | Path, *, connect_timeout: int = 10) -> None:
        located = dsn.classify(target)
        self._turn = threading.Lock()
        self._pg: psycopg.Connection[Any] | None = None
        self._dsn = located if isinstance(located, dsn.Dsn) else None
        self._lite: sqlite3.Connection | None = None
        if isinstance(located, dsn.Dsn):
            self.dialect = migrating.Dialect.POSTGRES
            self.where = located.where
            try:
                self._pg = psycopg.connect(
                    located.conninfo,
                    autocommit=True,
                    connect_timeout=connect_timeout,
                    # Read-only; room to aggregate 100,000 runs in memory instead of sorting on
                    # disk (the default 4 MB spills); and a plan per execution: psycopg prepares
                    # a query run five times, and PostgreSQL's generic plan for it (parameters
                    # unknown) was 3x slower for the UI's aggregates (bench/ui_queries.py).
                    options=(
                        "-c default_transaction_read_only=on -c work_mem=64MB "
                        "-c plan_cache_mode=force_custom_plan"
                    ),
                )
            except psycopg.Error as exc:
                reason = " ".join(dsn.redact(str(exc), located).split())
                raise ResultsError(
                    f"cannot connect to the results database {self.where}: {reason}"
                ) from None
        else:
            path = located / sqlite.DEFAULT_FILENAME if located.is_dir() else located
            if not path.is_file():
                raise ResultsError(f"no results database at {path}")
            self.dialect = migrating.Dialect.SQLITE
            self.where = str(path)
            try:
                self._lite = sqlite3.connect(
                    f"{path.resolve().as_uri()}?mode=ro", uri=True, check_same_thread=False
                )
            except sqlite3.Error as exc:
                raise ResultsError(f"cannot open results database {path}: {exc}") from None
        version = self.query("SELECT MAX(version) FROM schema_migrations")[0][0] or 0
        if int(version) < MINIMUM_VERSION:
            self.close()
            raise ResultsError(
                f"results database {self.where} has schema {version}; open it once with "
                f"`simtest report` or `simtest run` to migrate it to {MINIMUM_VERSION} or later"
            )

    @property
    def postgres(self) -> bool:
        """Whether the database is PostgreSQL (for the few dialect-specific expressions)."""
        return self._pg is not None

    def query(self, sql: str, params: tuple[object, ...] | list[object] = ()) -> list[Row]:
        """Rows of one statement (``?`` placeholders)."""
        try:
            with self._turn:
                if self._pg is not None:
                    cursor = self._pg.execute(sql.replace("?", "%s"), tuple(params) or None)
                    return list(cursor.fetchall())
                assert self._lite is not None
                return self._lite.execute(sql, tuple(params)).fetchall()
        except (psycopg.Error, sqlite3.Error) as exc:
            text = str(exc) if self._dsn is None else dsn.redact(str(exc), self._dsn)
            reason = " ".join(text.split())
            raise ResultsError(f"results database {self.where}: {reason}") from None

    def json(self, raw: Any) -> Any:
        """A JSON column's value (text in SQLite, decoded already by psycopg)."""
        return json.loads(raw) if isinstance(raw, str) else raw

    def time(self, raw: Any) -> datetime.datetime | None:
        """A timestamp column's value as an aware UTC datetime (``None`` stays ``None``)."""
        if raw is None:
            return None
        value = raw if isinstance(raw, datetime.datetime) else datetime.datetime.fromisoformat(raw)
        return value.astimezone(datetime.UTC)

    # Codec (sqlrows): lets the store's row conversion build records from these rows too.
    def json_out(self, raw: Any) -> Any:
        return self.json(raw)

    def time_out(self, raw: Any) -> datetime.datetime:
        value = self.time(raw)
        if value is None:
            raise ResultsError(f"results database {self.where}: a required timestamp is NULL")
        return value

    def json_in(self, value: object) -> object:
        raise ResultsError("the read-only connection writes nothing")

    def time_in(self, value: datetime.datetime) -> object:
        raise ResultsError("the read-only connection writes nothing")

    def campaign(self, run_key: str) -> records.CampaignRecord | None:
        """One campaign run, as the store returns it."""
        rows = self.query(
            f"SELECT {sqlrows.CAMPAIGN_COLUMNS} FROM campaigns WHERE run_key = ?", (run_key,)
        )
        return sqlrows.campaign(self, rows[0]) if rows else None

    def outcomes(
        self, run_key: str, *, scenario_id: str | None = None, final_only: bool = True
    ) -> tuple[records.StoredOutcome, ...]:
        """A run's stored attempts (of one scenario), converted as the store converts them."""
        one = scenario_id is not None
        params: tuple[object, ...] = (run_key, scenario_id) if one else (run_key,)
        rows = self.query(
            f"SELECT {sqlrows.OUTCOME_COLUMNS} FROM runs r JOIN scenarios s "
            "ON s.scenario_id = r.scenario_id AND s.sha256 = r.sha256 "
            f"WHERE r.run_key = ?{' AND r.scenario_id = ?' if one else ''}",
            params,
        )
        metrics: dict[tuple[str, int], dict[str, float]] = {}
        for sid, attempt, name, value in self.query(
            "SELECT scenario_id, attempt, name, value FROM metrics WHERE run_key = ?"
            f"{' AND scenario_id = ?' if one else ''}",
            params,
        ):
            metrics.setdefault((sid, int(attempt)), {})[name] = (
                float("nan") if value is None else float(value)
            )
        stored = sorted(
            (sqlrows.outcome(self, row, metrics) for row in rows),
            key=lambda s: (s.scenario.scenario_id, s.outcome.attempts),
        )
        if final_only:
            return tuple(comparing.final_outcomes(stored).values())
        return tuple(stored)

    def json_text(self, column: str, key: str) -> str:
        """SQL for the text value of ``column``'s top-level ``key`` (a JSON object column)."""
        if self.postgres:
            return f"({column} ->> '{key}')"
        return f"CAST(json_extract({column}, '$.{key}') AS TEXT)"

    def json_items(self, column: str) -> str:
        """A table expression yielding one ``value`` row per element of a JSON array column."""
        if self.postgres:
            return f"jsonb_array_elements_text({column}) AS item(value)"
        return f"json_each({column}) AS item"

    def close(self) -> None:
        """Release the connection."""
        if self._pg is not None:
            self._pg.close()
        if self._lite is not None:
            self._lite.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
