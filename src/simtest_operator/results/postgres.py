"""The shared results store: PostgreSQL through psycopg 3, for the operator and for teams.

Same schema and queries as SQLite (see :mod:`.sqlstore`), with native JSONB and TIMESTAMPTZ
columns so the tables are pleasant to query from other tools. Migrations take a transaction-level
advisory lock, so several operator replicas or CI jobs opening the database at once apply each
step exactly once. The DSN comes from a Secret and may hold a password: it never appears in an
error message (only host, port and database name do; see :mod:`.dsn`).
"""

from __future__ import annotations

import contextlib
import datetime
from collections.abc import Iterable, Iterator, Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import psycopg

from simtest_operator.errors import ResultsError
from simtest_operator.results import dsn, migrating, sqlrows, sqlstore

MIGRATION_LOCK = 0x73696D7465737400
"""Advisory lock key for migrations (``b"simtest\\0"`` as a big-endian integer)."""


class _PostgresCodec:
    """JSONB through psycopg's adapter; TIMESTAMPTZ as aware datetimes."""

    def __init__(self) -> None:
        # psycopg is imported when a PostgreSQL store is opened, not with the results package
        # (70 ms that every SQLite user, e.g. simtest evaluate on an output folder, would pay).
        from psycopg.types.json import Jsonb

        self._jsonb = Jsonb

    def json_in(self, value: object) -> object:
        return self._jsonb(value)

    def json_out(self, raw: Any) -> Any:
        return raw

    def time_in(self, value: datetime.datetime) -> object:
        return value

    def time_out(self, raw: Any) -> datetime.datetime:
        if not isinstance(raw, datetime.datetime):
            raise ResultsError(f"expected a timestamp from PostgreSQL, got {raw!r}")
        return raw.astimezone(datetime.UTC)


class _PostgresTx:
    def __init__(self, connection: psycopg.Connection[Any]) -> None:
        self._connection = connection

    def query(self, sql: str, params: Sequence[object] = ()) -> list[sqlrows.Row]:
        cursor = self._connection.execute(_placeholders(sql), tuple(params) if params else None)
        return list(cursor.fetchall()) if cursor.description is not None else []

    def execute_many(self, sql: str, rows: Iterable[Sequence[object]]) -> None:
        batch = [tuple(row) for row in rows]
        if batch:
            with self._connection.cursor() as cursor:
                cursor.executemany(_placeholders(sql), batch)


def _placeholders(sql: str) -> str:
    # The shared queries use sqlite3's "?"; none contains a literal "?" or "%".
    return sql.replace("?", "%s")


class PostgresStore(sqlstore.SqlStore):
    """A results store in a PostgreSQL database; migrated on open."""

    dialect = migrating.Dialect.POSTGRES

    def __init__(
        self,
        target: str | dsn.Dsn,
        *,
        clock: sqlstore.Clock = sqlstore.utc_now,
        auto_migrate: bool = True,
        connect_timeout: int = 10,
    ) -> None:
        """Connect to ``target`` (a DSN); ``auto_migrate=False`` is for staged upgrades."""
        super().__init__(codec=_PostgresCodec(), clock=clock)
        located = dsn.classify(target) if isinstance(target, str) else target
        if not isinstance(located, dsn.Dsn):
            raise ResultsError(f"not a PostgreSQL DSN: {located}")
        self._dsn = located
        self.where = located.where
        import psycopg

        self._error: type[Exception] = psycopg.Error
        try:
            self._connection: psycopg.Connection[Any] = psycopg.connect(
                located.conninfo, autocommit=True, connect_timeout=connect_timeout
            )
        except psycopg.Error as exc:
            reason = " ".join(dsn.redact(str(exc), located).split())
            raise ResultsError(
                f"cannot connect to the results database {self.where}: {reason}; "
                "check the DSN secret and that the server is reachable"
            ) from None
        if auto_migrate:
            try:
                self.migrate()
            except BaseException:
                self.close()
                raise

    @contextlib.contextmanager
    def _transaction(self, *, write: bool) -> Iterator[sqlstore.Tx]:
        try:
            with self._connection.transaction():
                if not write:
                    self._connection.execute("SET TRANSACTION READ ONLY")
                yield _PostgresTx(self._connection)
        except self._error as exc:
            reason = " ".join(dsn.redact(str(exc), self._dsn).split())
            raise ResultsError(f"results database {self.where}: {reason}") from exc

    def _lock_for_migration(self, tx: sqlstore.Tx) -> None:
        tx.query("SELECT pg_advisory_xact_lock(?)", (MIGRATION_LOCK,))

    def close(self) -> None:
        self._connection.close()
