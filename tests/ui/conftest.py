"""Fixtures for the results UI: an output folder with real recordings plus a run history.

``ui_target`` is the sample output folder of the report tests (``tests/results/sampleoutdir``:
eight scenarios, every verdict, a retried one, recordings and metric timelines) with the known
eight-run history of ``tests/results/historydata`` added to the same SQLite database.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any
from wsgiref.util import setup_testing_defaults

import pytest

from simtest_operator import results
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.runner.campaigns import read_recording
from simtest_operator.ui import server, views
from tests.results.historydata import fill
from tests.results.sampleoutdir import make_outdir

SAMPLE_RUN = "smoke-20250301T120000Z-0badcafe"


@pytest.fixture(scope="module")
def ui_target(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output folder (its ``results.sqlite`` holds the sample run and the history)."""
    root = make_outdir(tmp_path_factory.mktemp("ui") / "out")
    with results.open_store(root) as store:
        fill(store)
    return root


@pytest.fixture
def app(ui_target: Path) -> Iterator[server.App]:
    """The WSGI app over the fixture database, reading recordings as ``simtest ui`` does."""
    with ReadOnlyDatabase(ui_target) as db:
        yield server.App(db, views.Context(base_dir=ui_target, read_trajectories=read_recording))


Get = Callable[[str], tuple[str, str, bytes]]


@pytest.fixture
def get(app: server.App) -> Get:
    """GET a path (with query) from the app: (status, content type, body)."""

    def call(url: str) -> tuple[str, str, bytes]:
        path, _, query = url.partition("?")
        environ: dict[str, Any] = {"PATH_INFO": path, "QUERY_STRING": query}
        setup_testing_defaults(environ)
        seen: dict[str, Any] = {}

        def start_response(status: str, headers: list[tuple[str, str]]) -> None:
            seen["status"], seen["headers"] = status, dict(headers)

        body = b"".join(app(environ, start_response))
        return seen["status"], seen["headers"]["Content-Type"], body

    return call
