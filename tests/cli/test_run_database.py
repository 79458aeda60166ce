"""``simtest run`` with a PostgreSQL results database: every DSN form, and the password stays out.

Covers (issue 12, item 1): each DSN spelling libpq accepts, given with ``--db`` or through the
campaign's ``databaseSecretRef`` (a ``SIMTEST_SECRET_*`` variable), writes the run into
PostgreSQL; no SQLite file appears (in the output or the working folder); the password is in
none of stdout/stderr, campaign.json, report.html or any other file written; an ambiguous
``--db`` is refused with one line and exit 2 before the output folder is created.
"""

from __future__ import annotations

import json
import socket
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from tests.results import dsnforms
from tests.runner.support import write_campaign

pytestmark = pytest.mark.timeout(120)
SECRET_REF = """  results:
    databaseSecretRef: {name: results-db, key: dsn}
"""


def _run(
    tmp_path: Path, manifest: Path, *args: str, env: dict[str, str] | None = None
) -> tuple[int, str]:
    result = CliRunner().invoke(
        cli,
        ["run", str(manifest), "-o", str(tmp_path / "out"), "--engine", "fake", "--plain", *args],
        env={"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), **(env or {})},
    )
    return result.exit_code, result.output


def _files_holding(folder: Path, text: str) -> list[Path]:
    return [p for p in folder.rglob("*") if p.is_file() and text.encode() in p.read_bytes()]


@pytest.mark.postgres
@pytest.mark.parametrize(
    "form", ["key-value", "upper-case-uri", "postgres-uri", "password-in-query"]
)
@pytest.mark.parametrize("via", ["--db", "databaseSecretRef"])
def test_every_dsn_form_goes_to_postgresql_and_the_password_nowhere(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, postgres_dsn: str, form: str, via: str
) -> None:
    monkeypatch.chdir(tmp_path)
    target = dsnforms.forms(postgres_dsn)[form]
    manifest = write_campaign(tmp_path, {"a": "pass", "b": "fail"}, retries=0,
                              extra=SECRET_REF if via == "databaseSecretRef" else "")  # fmt: skip
    if via == "--db":
        code, output = _run(tmp_path, manifest, "--db", target)
    else:
        code, output = _run(tmp_path, manifest, env={"SIMTEST_SECRET_RESULTS_DB_DSN": target})
    assert code == 1, output
    assert dsnforms.PASSWORD not in output
    assert _files_holding(tmp_path, dsnforms.PASSWORD) == []
    assert not [p for p in tmp_path.rglob("*") if p.suffix == ".sqlite" or "=" in p.name]
    state = json.loads((tmp_path / "out/campaign.json").read_text())
    database = postgres_dsn.rsplit("/", 1)[1]
    assert state["store"].startswith("postgresql://") and state["store"].endswith("/" + database)
    assert f"results {state['store']}" in output
    with results.open_store(postgres_dsn) as store:
        [record] = store.campaigns()
        assert record.run_key == state["runKey"] and record.finished
        assert {o.outcome.verdict.value for o in store.outcomes(record.run_key)} == {
            "Passed",
            "Failed",
        }


@pytest.mark.parametrize(
    "target",
    [f"mysql://u:{dsnforms.PASSWORD}@db/x", f"host=db password={dsnforms.PASSWORD} dbname",
     f"u:{dsnforms.PASSWORD}@db/x"],
)  # fmt: skip
def test_an_ambiguous_database_is_refused_before_anything_is_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, target: str
) -> None:
    monkeypatch.chdir(tmp_path)
    manifest = write_campaign(tmp_path, {"a": "pass"})
    code, output = _run(tmp_path, manifest, "--db", target)
    assert code == 2, output
    assert output.startswith("error: ResultsError: ") and output.count("\n") == 1
    assert dsnforms.PASSWORD not in output
    assert not (tmp_path / "out").exists()
    assert _files_holding(tmp_path, dsnforms.PASSWORD) == []


def test_an_unreachable_database_fails_the_run_in_one_line_and_the_state_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Issue 12 item 7: campaign.json stayed "running" and libpq's error spanned two lines.
    monkeypatch.chdir(tmp_path)
    with socket.socket() as probe:  # a port nothing listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    manifest = write_campaign(tmp_path, {"a": "pass"})
    target = f"postgresql://u:{dsnforms.PASSWORD}@127.0.0.1:{port}/x?connect_timeout=5"
    code, output = _run(tmp_path, manifest, "--db", target)
    assert code == 2, output
    assert output.startswith("error: ResultsError: cannot connect to the results database")
    assert output.count("\n") == 1 and "Traceback" not in output
    assert dsnforms.PASSWORD not in output
    state = json.loads((tmp_path / "out/campaign.json").read_text())
    assert (state["state"], state["exitCode"]) == ("failed", 2)
    assert state["reason"].startswith("cannot connect to the results database")
    assert _files_holding(tmp_path, dsnforms.PASSWORD) == []
    code, output = _run(tmp_path, manifest)  # fixed (default store): the same output resumes
    assert code == 0, output
    assert json.loads((tmp_path / "out/campaign.json").read_text())["state"] == "finished"
