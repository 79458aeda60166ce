"""Migrating: the versioned schema of the results database, shared by SQLite and PostgreSQL.

Migrations are numbered SQL files in :mod:`simtest_operator.results.migrations`, applied in order
and recorded in ``schema_migrations``; applying is idempotent (applied versions are skipped). One
file serves both databases: a few tokens name the types that differ (``@JSON@`` is TEXT in SQLite
and JSONB in PostgreSQL, ``@TIMESTAMP@`` TEXT or TIMESTAMPTZ, ``@FLOAT@`` REAL or DOUBLE
PRECISION). Each store applies the pending steps in one transaction under its own lock
(``BEGIN IMMEDIATE`` in SQLite, an advisory lock in PostgreSQL), so concurrent openers are safe.
"""

from __future__ import annotations

import dataclasses
import enum
import importlib.resources
import re
from collections.abc import Collection, Sequence

from simtest_operator.errors import ResultsError

MIGRATIONS_PACKAGE = "simtest_operator.results.migrations"
_FILE_NAME = re.compile(r"^(\d{4})_([a-z0-9_]+)\.sql$")

BOOTSTRAP_SQL = (
    "CREATE TABLE IF NOT EXISTS schema_migrations ("
    " version INTEGER PRIMARY KEY, name TEXT NOT NULL, applied_at @TIMESTAMP@ NOT NULL)"
)
"""The bookkeeping table itself; created before the first migration runs."""


class Dialect(enum.StrEnum):
    """The two databases the store speaks."""

    SQLITE = "sqlite"
    POSTGRES = "postgres"


_TYPES: dict[Dialect, dict[str, str]] = {
    Dialect.SQLITE: {"@JSON@": "TEXT", "@TIMESTAMP@": "TEXT", "@FLOAT@": "REAL"},
    Dialect.POSTGRES: {
        "@JSON@": "JSONB",
        "@TIMESTAMP@": "TIMESTAMPTZ",
        "@FLOAT@": "DOUBLE PRECISION",
    },
}


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Migration:
    """One numbered schema step."""

    version: int
    name: str
    sql: str

    def statements(self, dialect: Dialect) -> tuple[str, ...]:
        """The step's statements for one database, in order."""
        return split_statements(translate(self.sql, dialect))


def translate(sql: str, dialect: Dialect) -> str:
    """Replace the type tokens with the dialect's types; unknown tokens are an error."""
    for token, sql_type in _TYPES[dialect].items():
        sql = sql.replace(token, sql_type)
    leftover = re.search(r"@[A-Z_]+@", sql)
    if leftover:
        raise ResultsError(f"unknown type token {leftover.group(0)} in a migration")
    return sql


def split_statements(sql: str) -> tuple[str, ...]:
    """Split a script into statements at ``;`` ending a line; ``--`` comment lines are dropped."""
    lines = [line for line in sql.splitlines() if not line.lstrip().startswith("--")]
    statements = re.split(r";[ \t]*(?:\n|$)", "\n".join(lines))
    return tuple(s.strip() for s in statements if s.strip())


def load() -> tuple[Migration, ...]:
    """Every migration shipped with the package, by version; versions must run 1, 2, 3, ..."""
    found = []
    for entry in importlib.resources.files(MIGRATIONS_PACKAGE).iterdir():
        match = _FILE_NAME.match(entry.name)
        if match:
            found.append(
                Migration(
                    version=int(match.group(1)),
                    name=match.group(2),
                    sql=entry.read_text(encoding="utf-8"),
                )
            )
    found.sort(key=lambda m: m.version)
    versions = [m.version for m in found]
    if versions != list(range(1, len(found) + 1)):
        raise ResultsError(f"migration versions must be 1..n without gaps, found {versions}")
    return tuple(found)


LATEST_VERSION = len(load())
"""The schema version this code writes and reads."""


def pending(
    migrations: Sequence[Migration], applied: Collection[int], *, target: int | None = None
) -> tuple[Migration, ...]:
    """The steps still to apply to reach ``target`` (default: the latest), in order.

    A database that already has a version this code does not know was written by a newer
    simtest; writing to it could corrupt it, so that is an error.
    """
    known = {m.version for m in migrations}
    unknown = sorted(set(applied) - known)
    if unknown:
        raise ResultsError(
            f"the results database has schema version {max(unknown)}, newer than this simtest "
            f"knows ({max(known, default=0)}); upgrade simtest to use it"
        )
    limit = max(known, default=0) if target is None else target
    return tuple(m for m in migrations if m.version not in applied and m.version <= limit)
