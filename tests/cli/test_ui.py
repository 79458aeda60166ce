"""``simtest ui``: serves a results database over HTTP; bad input is one line and exit 2.

Covers: a real ``simtest ui`` process on a free port answers the health probe and the JSON API
from the output folder's database and opens it read-only (the file is unchanged afterwards);
a missing database, a database with an old schema and a port already in use are refused with a
one-line message.
"""

from __future__ import annotations

import hashlib
import json
import re
import socket
import subprocess
import sys
import urllib.request
from pathlib import Path

from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from tests.results.sampleoutdir import make_outdir

START = "from simtest_operator.cli.main import main; main()"


def test_serves_the_database_read_only(tmp_path: Path) -> None:
    outdir = make_outdir(tmp_path / "out")
    database = outdir / "results.sqlite"
    before = hashlib.sha256(database.read_bytes()).hexdigest()
    process = subprocess.Popen(
        [sys.executable, "-c", START, "ui", "--database", str(outdir), "--port", "0"],
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert process.stderr is not None
    try:
        line = process.stderr.readline()
        found = re.search(r"serving (\S+) on (http://127\.0\.0\.1:\d+/)", line)
        assert found is not None, line
        assert found.group(1) == str(database)
        base = found.group(2)
        with urllib.request.urlopen(base + "healthz", timeout=10) as answer:
            assert answer.read() == b"ok\n"
        with urllib.request.urlopen(base + "api/runs", timeout=10) as answer:
            listed = json.load(answer)
        assert [r["run_key"] for r in listed["runs"]] == ["smoke-20250301T120000Z-0badcafe"]
    finally:
        process.terminate()
        process.wait(timeout=10)
        process.stderr.close()
    assert hashlib.sha256(database.read_bytes()).hexdigest() == before


def test_refusals_are_one_line(tmp_path: Path) -> None:
    runner = CliRunner()
    missing = runner.invoke(cli, ["ui", "--database", str(tmp_path / "none.sqlite")])
    assert missing.exit_code == 2
    assert missing.output == f"simtest ui: no results database at {tmp_path / 'none.sqlite'}\n"
    old = tmp_path / "old.sqlite"
    results.SqliteStore(old, auto_migrate=False).migrate(target=2)
    refused = runner.invoke(cli, ["ui", "--database", str(old)])
    assert refused.exit_code == 2
    assert refused.output.startswith(f"simtest ui: results database {old} has schema 2; ")
    make_outdir(tmp_path / "out")
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        taken = runner.invoke(cli, ["ui", "--database", str(tmp_path / "out"), "--port", str(port)])
    assert taken.exit_code == 2
    assert (
        taken.output == f"simtest ui: cannot listen on 127.0.0.1:{port}: Address already in use\n"
    )
