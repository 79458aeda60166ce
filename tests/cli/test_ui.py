"""``simtest ui``: serves a results database over HTTP; bad input is one line and exit 2.

Covers: a real ``simtest ui`` process on a free port answers the health probe and the JSON API
from the output folder's database and opens it read-only (the file is unchanged afterwards);
a missing database, a database with an old schema and a port already in use are refused with a
one-line message. Issue 29: clients that keep a request half-sent (or send nothing) do not stop
the others, ``/healthz`` included (wsgiref answered one request at a time); oversized headers are
refused with 431; an idle connection is closed after the channel timeout.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import re
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from tests.results.sampleoutdir import make_outdir

START = "from simtest_operator.cli.main import main; main()"


@contextlib.contextmanager
def serving(*args: str, program: str = START) -> Iterator[tuple[str, str]]:
    """A ``simtest ui`` process (or another ``program`` printing its first line): (database,
    base URL)."""
    process = subprocess.Popen(
        [sys.executable, "-c", program, *args], stderr=subprocess.PIPE, text=True
    )
    assert process.stderr is not None
    try:
        line = process.stderr.readline()
        found = re.search(r"serving (\S+) on (http://127\.0\.0\.1:\d+/)", line)
        assert found is not None, line
        yield found.group(1), found.group(2)
    finally:
        process.terminate()
        process.wait(timeout=10)
        process.stderr.close()


def get(url: str) -> tuple[int, bytes]:
    with urllib.request.urlopen(url, timeout=5) as answer:
        return answer.status, answer.read()


def test_serves_the_database_read_only(tmp_path: Path) -> None:
    outdir = make_outdir(tmp_path / "out")
    database = outdir / "results.sqlite"
    before = hashlib.sha256(database.read_bytes()).hexdigest()
    with serving("ui", "--database", str(outdir), "--port", "0") as (where, base):
        assert where == str(database)
        assert get(base + "healthz") == (200, b"ok\n")
        listed = json.loads(get(base + "api/runs")[1])
        assert [r["run_key"] for r in listed["runs"]] == ["smoke-20250301T120000Z-0badcafe"]
    assert hashlib.sha256(database.read_bytes()).hexdigest() == before


def _port(base: str) -> int:
    return int(base.rstrip("/").rpartition(":")[2])


@pytest.mark.timeout(60)
def test_a_slow_client_does_not_block_the_others(tmp_path: Path) -> None:
    outdir = make_outdir(tmp_path / "out")
    with (
        serving("ui", "--database", str(outdir), "--port", "0") as (_, base),
        contextlib.ExitStack() as stack,
    ):
        port = _port(base)
        slow = [stack.enter_context(socket.create_connection(("127.0.0.1", port), timeout=5))
                for _ in range(3)]  # fmt: skip
        slow[0].sendall(b"GET /api/ru")
        slow[1].sendall(b"GET /api/runs HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # no blank line
        # slow[2] sends nothing at all
        started = time.monotonic()
        for path in ("healthz", "api/runs", "runs", "healthz"):
            status, _ = get(base + path)
            assert status == 200, path
        assert time.monotonic() - started < 5
        with socket.create_connection(("127.0.0.1", port), timeout=5) as big:
            big.sendall(b"GET /healthz HTTP/1.1\r\nX-Big: " + b"a" * 70_000 + b"\r\n\r\n")
            status_line = big.recv(100).split(b"\r\n")[0]
            assert status_line.endswith(b" 431 Request Header Fields Too Large"), status_line
        assert get(base + "healthz") == (200, b"ok\n")


LIMITED = """
import sys
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.ui import server
limits = server.ServerLimits(channel_timeout=1, cleanup_interval=1)
database = ReadOnlyDatabase(sys.argv[1])
httpd = server.Server(server.App(database), host="127.0.0.1", port=0, limits=limits)
print(f"serving {database.where} on http://127.0.0.1:{httpd.port}/", file=sys.stderr, flush=True)
httpd.run()
"""


@pytest.mark.timeout(60)
def test_an_idle_connection_is_closed_after_the_channel_timeout(tmp_path: Path) -> None:
    outdir = make_outdir(tmp_path / "out")
    with serving(str(outdir), program=LIMITED) as (_, base):
        with socket.create_connection(("127.0.0.1", _port(base)), timeout=10) as idle:
            idle.sendall(b"GET /healthz HTTP/1.1\r\n")
            started = time.monotonic()
            assert idle.recv(100) == b"", "closed by the server"
            assert 0.5 < time.monotonic() - started < 8
        assert get(base + "healthz") == (200, b"ok\n")


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
