"""Benchmark of the results UI's database work on PostgreSQL with 100,000 runs.

Generates a results database (``--campaigns`` campaign runs x ``--scenarios`` scenarios = runs,
default 1,000 x 100 = 100,000 final attempts, plus ~1 % retried ``Error`` attempts and three
metrics per attempt) through the real schema (``results.open_store`` migrates it), loaded with
``COPY``; then times every page of ``simtest ui`` through its WSGI app -- the view's queries, the
Python around them and the template -- ``--repeat`` times each, and prints p50/p95/max per page.

Data: 100 scenario ids over four types, four roads, tags and ``req:`` requirement tags; five SUT
versions over time; seeds 1-3; 10 % of the scenarios flip verdicts at random (flaky), 5 % fail
from the third SUT version on (a regression). Without ``--dsn`` a throw-away server is started
from the Debian packages (as the tests do, ``tests/fixtures/postgres.py``) and removed after::

    python bench/ui_queries.py [--dsn postgresql://...] [--repeat 30] \
        [--json bench/results/ui_queries.json]
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import os
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from wsgiref.util import setup_testing_defaults

import psycopg

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.fixtures import postgres as pgfixture  # noqa: E402

from simtest_operator import results  # noqa: E402
from simtest_operator.results.querying import ReadOnlyDatabase  # noqa: E402
from simtest_operator.ui import server, views  # noqa: E402

T0 = datetime.datetime(2026, 1, 1, tzinfo=datetime.UTC)
CATEGORIES = ("cut-in", "pedestrian", "car-following", "lane-change")
ROADS = ("A9.xodr", "town.xodr", "Town01.xodr", "ring.xodr")
TAGS = ("highway", "urban", "night", "rain", "truck", "junction")
REQUIREMENTS = ("req:UN-R157-5.2.5.2", "req:UN-R157-5.2.3", "req:EuroNCAP-AEB-C2C-2.3",
                "req:EuroNCAP-VRU-CPNA", "req:ISO-34502-6.1")  # fmt: skip


@contextlib.contextmanager
def throwaway_server() -> Iterator[str]:
    """A PostgreSQL server in a temp folder (fsync off, like the tests'); yields a DSN."""
    bin_dir = pgfixture._bin_dir()
    root = Path(tempfile.mkdtemp(prefix="simtest-bench-pg-"))
    data_dir, socket_dir, log = root / "data", root / "socket", root / "server.log"
    socket_dir.mkdir()
    if os.geteuid() == 0:
        shutil.chown(root, user="postgres", group="postgres")
        shutil.chown(socket_dir, user="postgres", group="postgres")
    port = pgfixture._free_port()
    pgfixture._run([str(bin_dir / "initdb"), "--pgdata", str(data_dir), "--username",
                    pgfixture.SUPERUSER, "--auth", "trust", "--no-sync"], log=log)  # fmt: skip
    options = (f"-c listen_addresses=127.0.0.1 -c port={port} "
               f"-c unix_socket_directories={socket_dir} -c fsync=off")  # fmt: skip
    pgfixture._run([str(bin_dir / "pg_ctl"), "start", "-D", str(data_dir), "-l", str(log), "-w",
                    "-o", options], log=log)  # fmt: skip
    try:
        with psycopg.connect(f"postgresql://{pgfixture.SUPERUSER}@127.0.0.1:{port}/postgres",
                             autocommit=True) as connection:  # fmt: skip
            connection.execute("CREATE DATABASE bench")
        yield f"postgresql://{pgfixture.SUPERUSER}@127.0.0.1:{port}/bench"
    finally:
        subprocess.run(pgfixture._as_server_user(
            [str(bin_dir / "pg_ctl"), "stop", "-D", str(data_dir), "-m", "fast"]),
            capture_output=True, timeout=120, check=False)  # fmt: skip
        shutil.rmtree(root, ignore_errors=True)


def _copy(
    connection: psycopg.Connection[Any], table: str, columns: str, rows: list[tuple[Any, ...]]
) -> None:
    with connection.cursor() as cursor, cursor.copy(f"COPY {table} ({columns}) FROM STDIN") as copy:
        for row in rows:
            copy.write_row(row)


def generate(dsn: str, *, campaigns: int, scenarios: int, seed: int = 7) -> int:
    """Fill the database; returns the number of ``runs`` rows."""
    with results.open_store(dsn):
        pass  # creates and migrates the schema
    rng = random.Random(seed)
    ids = [f"{CATEGORIES[i % 4]}/scenario-{i:03d}.xosc" for i in range(scenarios)]
    flaky = set(rng.sample(ids, scenarios // 10))
    regressing = set(rng.sample(sorted(set(ids) - flaky), scenarios // 20))
    scenario_rows = []
    for index, scenario_id in enumerate(ids):
        tags = sorted({TAGS[index % 6], TAGS[(index * 7) % 6], REQUIREMENTS[index % 5]})
        road = ROADS[(index // 4) % 4]
        source = f"git://scenarios/{scenario_id}"
        row = (scenario_id, f"{index:064x}", source, json.dumps(tags), CATEGORIES[index % 4], road)
        scenario_rows.append(row)
    campaign_rows, listed, run_rows, metric_rows = [], [], [], []
    for number in range(campaigns):
        started = T0 + datetime.timedelta(hours=6 * number)
        key = f"nightly-{started:%Y%m%dT%H%M%SZ}-{number:08x}"
        version = f"1.{number * 5 // campaigns}.0"
        campaign_rows.append((key, "nightly", "team-a", "ab" * 32, started,
                              started + datetime.timedelta(minutes=30), "Failed", "idm-driver",
                              version, "sumo-1.20", json.dumps({"seed": 1 + number % 3}),
                              json.dumps({})))  # fmt: skip
        for position, (scenario_id, sha, *_rest) in enumerate(scenario_rows):
            listed.append((key, position, scenario_id, sha))
            attempt = 1
            if rng.random() < 0.01:
                run_rows.append(_run(key, scenario_id, sha, 1, "Error", started))
                attempt = 2
            if scenario_id in flaky:
                verdict = "Passed" if rng.random() < 0.7 else "Failed"
            elif scenario_id in regressing and number * 5 // campaigns >= 2:
                verdict = "Failed"
            else:
                verdict = "Passed" if rng.random() < 0.97 else "Timeout"
            run_rows.append(_run(key, scenario_id, sha, attempt, verdict, started))
            for name in ("minTtc", "minThw", "maxDecel"):
                metric_rows.append((key, scenario_id, attempt, name, round(rng.uniform(0, 8), 3)))
    with psycopg.connect(dsn, autocommit=True) as connection:
        _copy(connection, "scenarios", "scenario_id, sha256, source, tags, category, road",
              scenario_rows)  # fmt: skip
        _copy(connection, "campaigns", "run_key, name, namespace, manifest_sha256, started_at, "
              "finished_at, phase, sut_name, sut_version, simulator_version, settings, counts",
              campaign_rows)  # fmt: skip
        _copy(connection, "campaign_scenarios", "run_key, position, scenario_id, sha256", listed)
        _copy(connection, "runs", "run_key, scenario_id, sha256, attempt, verdict, reason, "
              "simulated_seconds, wall_seconds, artifacts, content_hashes, versions, recorded_at, "
              "ignored_elements", run_rows)  # fmt: skip
        _copy(connection, "metrics", "run_key, scenario_id, attempt, name, value", metric_rows)
        connection.execute("ANALYZE")
    return len(run_rows)


def _run(key: str, scenario_id: str, sha: str, attempt: int, verdict: str,
         started: datetime.datetime) -> tuple[Any, ...]:  # fmt: skip
    reason = "" if verdict == "Passed" else f"{verdict.lower()} at t=7.2 s"
    recording = f"{hash((key, scenario_id, attempt)) & (2**63 - 1):064x}"
    return (key, scenario_id, sha, attempt, verdict, reason, 20.0, 0.4,
            json.dumps({"recording": f"s3://bench/{key}/{scenario_id}/recording.mcap"}),
            json.dumps({"scenario": sha, "recording": recording}),
            json.dumps({"sumo": "1.20.0"}), started + datetime.timedelta(seconds=attempt),
            "[]")  # fmt: skip


def pages(db: ReadOnlyDatabase) -> dict[str, str]:
    """The URLs timed: every page, with real keys from the database."""
    newest, older = (r[0] for r in db.query(
        "SELECT run_key FROM campaigns ORDER BY started_at DESC LIMIT 2"))  # fmt: skip
    scenario = db.query("SELECT scenario_id FROM scenarios ORDER BY scenario_id LIMIT 1")[0][0]
    return {
        "overview": "/",
        "runs (page 1)": "/runs",
        "runs (page 10)": "/runs?page=9",
        "run (newest, 100 scenarios)": f"/run?run={newest}",
        "coverage by type": f"/coverage?run={newest}&by=category",
        "coverage by tag": f"/coverage?run={newest}&by=tag",
        "coverage by requirement": f"/coverage?run={newest}&by=requirement",
        "developer view": f"/scenario?run={newest}&id={scenario}",
        "compare two runs": f"/compare?base={older}&other={newest}",
        "evaluations of a run": f"/evaluations?run={newest}",
        "SUT versions x type": "/sets?axis=sut&by=category",
        "SUT versions x requirement": "/sets?axis=sut&by=requirement",
        "history and flakiness (all)": "/history",
        "history of one scenario": f"/history/scenario?id={scenario}",
        "API: history (JSON)": "/api/history",
    }


def measure(app: server.App, url: str, repeat: int) -> list[float]:
    """Wall times in ms of ``repeat`` GETs of ``url`` through the WSGI app (one warm-up)."""
    path, _, query = url.partition("?")
    times = []
    for index in range(repeat + 1):
        environ: dict[str, Any] = {"PATH_INFO": path, "QUERY_STRING": query}
        setup_testing_defaults(environ)
        status: list[str] = []

        def start_response(
            line: str, headers: list[tuple[str, str]], seen: list[str] = status
        ) -> None:
            seen.append(line)

        started = time.perf_counter()
        body = b"".join(app(environ, start_response))
        elapsed = (time.perf_counter() - started) * 1000
        if not status[0].startswith("200"):
            raise SystemExit(f"{url}: {status[0]} {body[:300]!r}")
        if index:
            times.append(elapsed)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dsn", help="an empty PostgreSQL database (default: a throw-away server)")
    parser.add_argument("--campaigns", type=int, default=1000)
    parser.add_argument("--scenarios", type=int, default=100)
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--json", type=Path, help="write the figures here")
    args = parser.parse_args()
    with contextlib.ExitStack() as stack:
        dsn = args.dsn or stack.enter_context(throwaway_server())
        started = time.perf_counter()
        rows = generate(dsn, campaigns=args.campaigns, scenarios=args.scenarios)
        print(f"generated {rows} runs rows in {time.perf_counter() - started:.1f} s")
        db = stack.enter_context(ReadOnlyDatabase(dsn))
        app = server.App(db, views.Context())
        figures: dict[str, dict[str, Any]] = {}
        for name, url in pages(db).items():
            times = sorted(measure(app, url, args.repeat))
            p95 = times[min(len(times) - 1, round(0.95 * (len(times) - 1)))]
            figures[name] = {"url": url, "p50_ms": round(statistics.median(times), 1),
                             "p95_ms": round(p95, 1), "max_ms": round(times[-1], 1)}  # fmt: skip
            print(
                f"{name:32s} p50 {figures[name]['p50_ms']:7.1f} ms   p95 "
                f"{figures[name]['p95_ms']:7.1f} ms   max {figures[name]['max_ms']:7.1f} ms"
            )
    worst = max(float(f["p95_ms"]) for f in figures.values())
    print(f"worst p95: {worst:.1f} ms ({'within' if worst <= 200 else 'OVER'} the 200 ms budget)")
    load = os.getloadavg()[0]
    if args.json:
        args.json.write_text(json.dumps({
            "runs": rows, "campaigns": args.campaigns, "scenarios": args.scenarios,
            "repeat": args.repeat, "load_average_1m": round(load, 1), "pages": figures,
        }, indent=2) + "\n")  # fmt: skip


if __name__ == "__main__":
    main()
