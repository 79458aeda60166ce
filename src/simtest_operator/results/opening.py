"""Opening a results store from what a user or a Secret gives: a file, a folder or a DSN.

The one place that decides between SQLite and PostgreSQL, so the CLI, the local runner and the
operator accept the same spellings.
"""

from __future__ import annotations

from pathlib import Path

from simtest_operator.errors import ResultsError
from simtest_operator.results import postgres, sqlite, sqlstore, stores


def open_store(
    target: str | Path,
    *,
    clock: sqlstore.Clock = sqlstore.utc_now,
    create: bool = True,
    connect_timeout: int = 10,
) -> stores.Store:
    """Open (migrating as needed) the store at ``target``.

    ``postgresql://...`` or ``postgres://...`` -> PostgreSQL; an existing folder -> its
    ``results.sqlite``; anything else -> that SQLite file. With ``create=False`` a missing SQLite
    file is an error instead of a new empty database (readers should not leave files behind).
    ``connect_timeout`` (seconds) bounds the wait for a PostgreSQL server that does not answer.
    """
    if isinstance(target, str) and postgres.is_dsn(target):
        return postgres.PostgresStore(target, clock=clock, connect_timeout=connect_timeout)
    path = Path(target)
    if path.is_dir():
        path = path / sqlite.DEFAULT_FILENAME
    if not create and not path.is_file():
        raise ResultsError(f"no results database at {path}")
    return sqlite.SqliteStore(path, clock=clock)


def describe(target: str | Path) -> str:
    """A display form of a store target that never shows a password."""
    if isinstance(target, str) and postgres.is_dsn(target):
        return f"postgresql://{postgres.describe(target)}"
    return str(target)
