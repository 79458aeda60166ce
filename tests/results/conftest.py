"""Fixtures for the results tests: one store per backend.

``store_target`` is parametrised over SQLite and PostgreSQL (the latter marked ``postgres`` and
backed by the throw-away server of ``tests/fixtures/postgres.py``), so every store test runs
against both databases.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from simtest_operator import results
from tests.results.resultdata import T0


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def store_target(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> str:
    """A target for :func:`results.open_store`: a fresh SQLite file or a fresh PG database."""
    if request.param == "postgres":
        return str(request.getfixturevalue("postgres_dsn"))
    return str(tmp_path_factory.mktemp("store") / "results.sqlite")


@pytest.fixture
def store(store_target: str) -> Iterator[results.Store]:
    """An open, migrated store on a fresh database."""
    with results.open_store(store_target, clock=lambda: T0) as opened:
        yield opened
