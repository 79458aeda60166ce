"""Opening a results store from what a user or a Secret gives: a file, a folder or a DSN.

The CLI, the local runner and the operator all open stores here, so they accept the same
spellings; :mod:`.dsn` tells a DSN from a path.
"""

from __future__ import annotations

from pathlib import Path

from simtest_operator.errors import ResultsError
from simtest_operator.results import dsn, postgres, sqlite, sqlstore, stores


def open_store(
    target: str | Path,
    *,
    clock: sqlstore.Clock = sqlstore.utc_now,
    create: bool = True,
    connect_timeout: int = 10,
) -> stores.Store:
    """Open (migrating as needed) the store at ``target``.

    A DSN in any form libpq accepts -> PostgreSQL; an existing folder -> its ``results.sqlite``;
    any other path -> that SQLite file; a target that could be either -> ResultsError. With
    ``create=False`` a missing SQLite file is an error instead of a new empty database (readers
    should not leave files behind).
    ``connect_timeout`` (seconds) bounds the wait for a PostgreSQL server that does not answer.
    """
    located = dsn.classify(target)
    if isinstance(located, dsn.Dsn):
        return postgres.PostgresStore(located, clock=clock, connect_timeout=connect_timeout)
    path = located
    if path.is_dir():
        path = path / sqlite.DEFAULT_FILENAME
    if not create and not path.is_file():
        raise ResultsError(f"no results database at {path}")
    return sqlite.SqliteStore(path, clock=clock)
