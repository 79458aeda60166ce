"""Schema migrations on SQLite and PostgreSQL.

Covers: a fresh database ends at the latest version with one ``schema_migrations`` row per step;
re-opening is a no-op (no new rows, same ``applied_at``, data untouched); upgrading a v1 database
that holds rows keeps them and fills the new columns; a database newer than the code is refused;
concurrent openers (threads on PostgreSQL's advisory lock, processes on SQLite's write lock) apply
each step exactly once; and the migration files themselves (numbering, tokens, splitting).
"""

from __future__ import annotations

import concurrent.futures
import datetime
import multiprocessing
from pathlib import Path

import pytest

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.results import dsn, migrating, postgres, sqlite
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, campaign, outcome, scenario

LATER = T0 + datetime.timedelta(days=1)


def _raw(store: results.Store, sql: str) -> list[tuple[object, ...]]:
    assert isinstance(store, sqlite.SqliteStore | postgres.PostgresStore)
    with store._transaction(write=True) as tx:
        return tx.query(sql)


def _open(
    target: str, *, auto_migrate: bool = True, now: datetime.datetime = T0
) -> sqlite.SqliteStore | postgres.PostgresStore:
    if isinstance(dsn.classify(target), dsn.Dsn):
        return postgres.PostgresStore(target, clock=lambda: now, auto_migrate=auto_migrate)
    return sqlite.SqliteStore(target, clock=lambda: now, auto_migrate=auto_migrate)


def test_fresh_database_reaches_the_latest_version(store_target: str) -> None:
    with _open(store_target) as store:
        assert store.schema_version == migrating.LATEST_VERSION >= 2
        rows = _raw(store, "SELECT version, name FROM schema_migrations ORDER BY version")
    assert rows == [(m.version, m.name) for m in migrating.load()]


def test_reopening_is_a_no_op(store_target: str) -> None:
    with _open(store_target) as store:
        s = scenario("a.xosc")
        key = store.begin_campaign(campaign(), scenarios=[s])
        store.add_outcome(key, s, outcome("a.xosc", metrics={"minTTC": 3.0}))
        before = _raw(store, "SELECT version, name, applied_at FROM schema_migrations")
    with _open(store_target, now=LATER) as store:
        assert store.migrate() == migrating.LATEST_VERSION
        assert _raw(store, "SELECT version, name, applied_at FROM schema_migrations") == before
        (stored,) = store.outcomes(key)
        assert stored.outcome.metrics == {"minTTC": 3.0}


def test_upgrade_from_v1_keeps_rows(store_target: str) -> None:
    with _open(store_target, auto_migrate=False) as store:
        assert isinstance(store, sqlite.SqliteStore | postgres.PostgresStore)
        assert store.migrate(target=1) == 1
        stamp = "'2025-03-01T12:00:00.000000+00:00'"
        sha = "0" * 64
        for statement in (
            "INSERT INTO campaigns (run_key, name, started_at, settings) "
            f"VALUES ('old-run', 'smoke', {stamp}, '{{}}')",
            "INSERT INTO scenarios (scenario_id, sha256, tags, category) "
            f"VALUES ('a.xosc', '{sha}', '[\"x\"]', 'cut-in')",
            "INSERT INTO runs (run_key, scenario_id, sha256, attempt, verdict, reason, "
            "artifacts, content_hashes, versions, recorded_at) VALUES ('old-run', 'a.xosc', "
            f"'{sha}', 1, 'Failed', 'collision', '{{}}', '{{}}', '{{}}', {stamp})",
            "INSERT INTO metrics (run_key, scenario_id, attempt, name, value) "
            "VALUES ('old-run', 'a.xosc', 1, 'minTTC', 0.25)",
        ):
            _raw(store, statement)
        with pytest.raises(ResultsError):  # v2 tables do not exist yet
            store.scenarios(results.RunKey("old-run"))
    with _open(store_target) as store:
        assert store.schema_version == migrating.LATEST_VERSION
        key = results.RunKey("old-run")
        (stored,) = store.outcomes(key)
        assert stored.verdict is Verdict.FAILED
        assert stored.outcome.reason == "collision"
        assert stored.outcome.metrics == {"minTTC": 0.25}
        assert stored.outcome.ignored_elements == ()
        assert stored.scenario.tags == ("x",)
        # The new frozen-list table starts empty for old runs and fills on the next outcome.
        assert store.scenarios(key) == ()
        store.add_outcome(key, stored.scenario, outcome("a.xosc", attempts=2))
        assert [s.scenario_id for s in store.scenarios(key)] == ["a.xosc"]


def test_a_newer_database_is_refused(store_target: str) -> None:
    with _open(store_target) as store:
        _raw(
            store,
            "INSERT INTO schema_migrations (version, name, applied_at) "
            "VALUES (999, 'future', '2030-01-01T00:00:00.000000+00:00')",
        )
    with pytest.raises(ResultsError, match="schema version 999, newer than this simtest"):
        _open(store_target)


@pytest.mark.postgres
def test_concurrent_migrators_apply_each_step_once(postgres_dsn: str) -> None:
    def open_and_close(_: int) -> int:
        with postgres.PostgresStore(postgres_dsn) as store:
            return store.schema_version

    with concurrent.futures.ThreadPoolExecutor(max_workers=6) as pool:
        versions = list(pool.map(open_and_close, range(6)))
    assert versions == [migrating.LATEST_VERSION] * 6
    with postgres.PostgresStore(postgres_dsn) as store:
        rows = _raw(store, "SELECT version FROM schema_migrations ORDER BY version")
    assert rows == [(v,) for v in range(1, migrating.LATEST_VERSION + 1)]


def _open_sqlite(path: str) -> int:
    with sqlite.SqliteStore(path) as store:
        return store.schema_version


def test_concurrent_sqlite_openers_apply_each_step_once(tmp_path: Path) -> None:
    path = str(tmp_path / "results.sqlite")
    context = multiprocessing.get_context("spawn")
    with context.Pool(3) as pool:
        versions = pool.map(_open_sqlite, [path] * 3)
    assert versions == [migrating.LATEST_VERSION] * 3
    with sqlite.SqliteStore(path) as store:
        assert len(_raw(store, "SELECT version FROM schema_migrations")) == len(migrating.load())


def test_migration_files_translate_and_split() -> None:
    migrations = migrating.load()
    assert [m.version for m in migrations] == list(range(1, len(migrations) + 1))
    first = migrations[0]
    for dialect in migrating.Dialect:
        statements = first.statements(dialect)
        assert statements[0].startswith("CREATE TABLE campaigns")
        assert all("@" not in s and not s.endswith(";") for s in statements)
    assert "JSONB" in " ".join(first.statements(migrating.Dialect.POSTGRES))
    assert "JSONB" not in " ".join(first.statements(migrating.Dialect.SQLITE))
    with pytest.raises(ResultsError, match="@BLOB@"):
        migrating.translate("CREATE TABLE t (x @BLOB@)", migrating.Dialect.SQLITE)
    assert migrating.split_statements("-- c\nA;\nB ;  \n\nC") == ("A", "B", "C")
