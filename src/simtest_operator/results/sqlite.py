"""The default results store: one SQLite file (``results.sqlite``) in the run's output folder.

Needs nothing but the standard library, so ``simtest run`` works on any laptop. The file is in
WAL mode, so a report can read it while a campaign still writes. Each call is one explicit
transaction (``BEGIN IMMEDIATE`` for writes takes the write lock up front, which also serialises
concurrent migrators); the sqlite3 module's implicit transactions are switched off.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import sqlite3
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.errors import ResultsError
from simtest_operator.results import migrating, sqlrows, sqlstore

DEFAULT_FILENAME = "results.sqlite"
"""File name of the store inside an output folder."""

_TIME_FORMAT = "%Y-%m-%dT%H:%M:%S.%f+00:00"
"""Fixed-width UTC text, so timestamps sort correctly as strings."""


class _SqliteCodec:
    """JSON as sorted text, timestamps as fixed-width UTC ISO text."""

    def json_in(self, value: object) -> object:
        return json.dumps(value, sort_keys=True)

    def json_out(self, raw: Any) -> Any:
        return json.loads(raw)

    def time_in(self, value: datetime.datetime) -> object:
        return value.astimezone(datetime.UTC).strftime(_TIME_FORMAT)

    def time_out(self, raw: Any) -> datetime.datetime:
        return datetime.datetime.fromisoformat(str(raw))


class _SqliteTx:
    def __init__(self, connection: sqlite3.Connection) -> None:
        self._connection = connection

    def query(self, sql: str, params: Sequence[object] = ()) -> list[sqlrows.Row]:
        return self._connection.execute(sql, tuple(params)).fetchall()

    def execute_many(self, sql: str, rows: Iterable[Sequence[object]]) -> None:
        self._connection.executemany(sql, (tuple(row) for row in rows))


class SqliteStore(sqlstore.SqlStore):
    """A results store in one SQLite file; created and migrated on open."""

    dialect = migrating.Dialect.SQLITE

    def __init__(
        self,
        path: str | Path,
        *,
        clock: sqlstore.Clock = sqlstore.utc_now,
        auto_migrate: bool = True,
        busy_timeout: float = 30.0,
    ) -> None:
        """Open (creating if needed) ``path``; ``auto_migrate=False`` is for staged upgrades."""
        super().__init__(codec=_SqliteCodec(), clock=clock)
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._connection = sqlite3.connect(
                self.path, isolation_level=None, timeout=busy_timeout
            )
            self._connection.execute("PRAGMA journal_mode = WAL")
            self._connection.execute("PRAGMA foreign_keys = ON")
            self._connection.execute("PRAGMA synchronous = NORMAL")
        except (OSError, sqlite3.Error) as exc:
            raise ResultsError(f"cannot open results database {self.path}: {exc}") from exc
        if auto_migrate:
            try:
                self.migrate()
            except BaseException:
                self.close()
                raise

    @contextlib.contextmanager
    def _transaction(self, *, write: bool) -> Iterator[sqlstore.Tx]:
        try:
            self._connection.execute("BEGIN IMMEDIATE" if write else "BEGIN")
        except sqlite3.Error as exc:
            raise ResultsError(f"results database {self.path}: {exc}") from exc
        try:
            yield _SqliteTx(self._connection)
        except sqlite3.Error as exc:
            self._connection.execute("ROLLBACK")
            raise ResultsError(f"results database {self.path}: {exc}") from exc
        except BaseException:
            # KeyboardInterrupt and friends included: a killed run must not leave half a row.
            self._connection.execute("ROLLBACK")
            raise
        else:
            self._connection.execute("COMMIT")

    def close(self) -> None:
        self._connection.close()

    def integrity_problems(self) -> tuple[str, ...]:
        """What ``PRAGMA integrity_check`` and ``foreign_key_check`` report (empty when sound)."""
        rows = self._connection.execute("PRAGMA integrity_check").fetchall()
        problems = [str(row[0]) for row in rows if row[0] != "ok"]
        problems += [repr(row) for row in self._connection.execute("PRAGMA foreign_key_check")]
        return tuple(problems)
