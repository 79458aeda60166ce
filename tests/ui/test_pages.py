"""The results UI's pages and JSON endpoints through WSGI, on SQLite and PostgreSQL.

Covers: every page renders (200) on both databases; the JSON twins carry the figures the pages
show (run counts, coverage by type/road/tag/requirement, comparison classes, pass rate by SUT
version, flakiness, one scenario's history, the developer view's replay data read from the real
recording); bad parameters are 400, unknown runs/scenarios/pages 404, a POST 405 -- each a
one-line message, never a traceback; the static script and the health probe are served.
"""

from __future__ import annotations

import html
import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any
from wsgiref.util import setup_testing_defaults

import pytest

from simtest_operator import results
from simtest_operator.results import evaluations as ev
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.runner.campaigns import read_recording
from simtest_operator.ui import server, views
from simtest_operator.verdicts import ScenarioOutcome, Verdict
from tests.results.historydata import fill
from tests.results.resultdata import T0
from tests.results.sampleoutdir import make_outdir
from tests.ui.conftest import SAMPLE_RUN

Call = Callable[..., tuple[str, str, bytes]]


def _evaluate(store: results.Store) -> None:
    """An evaluation of the sample run (``simtest evaluate`` stores the same) with base scenarios:
    cut-in/close: following passed, cut-in failed; cut-in/far: following passed."""
    info = ev.EvaluationInfo(run_key=results.RunKey(SAMPLE_RUN), criteria_name="strict",
                             criteria={"minTtc": 1.5}, created_at=T0)  # fmt: skip
    key = store.begin_evaluation(info)

    def base(kind: str, verdict: Verdict, start: float) -> ev.StoredBaseScenario:
        return ev.StoredBaseScenario(kind=kind, actor=1, start=start, end=start + 5.0,
                                     verdict=verdict)  # fmt: skip

    for scenario_id, bases in (
        ("cut-in/close.xosc", (base("following", Verdict.PASSED, 0),
                               base("cut-in", Verdict.FAILED, 1))),
        ("cut-in/far.xosc", (base("following", Verdict.PASSED, 0),)),
    ):  # fmt: skip
        store.add_evaluated_run(key, ev.EvaluatedRun(
            scenario_id=scenario_id, attempt=1, verdict=Verdict.PASSED, reason="",
            evidence="complete", base_scenarios=bases))  # fmt: skip
    store.finish_evaluation(key, finished_at=T0)


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def call(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Call]:
    """A WSGI caller over the sample run plus the history, in either database."""
    dsn = str(request.getfixturevalue("postgres_dsn")) if request.param == "postgres" else None
    root = make_outdir(tmp_path / "out", database=dsn)
    target = dsn or str(root)
    with results.open_store(target) as store:
        fill(store)
        _evaluate(store)
    with ReadOnlyDatabase(target) as db:
        app = server.App(db, views.Context(base_dir=root, read_trajectories=read_recording))

        def go(url: str, method: str = "GET") -> tuple[str, str, bytes]:
            path, _, query = url.partition("?")
            environ: dict[str, Any] = {"PATH_INFO": path, "QUERY_STRING": query,
                                       "REQUEST_METHOD": method}  # fmt: skip
            setup_testing_defaults(environ)
            seen: dict[str, Any] = {}

            def start_response(status: str, headers: list[tuple[str, str]]) -> None:
                seen["status"], seen["type"] = status, dict(headers)["Content-Type"]

            body = b"".join(app(environ, start_response))
            return seen["status"], seen["type"], body

        yield go


def _json(call: Call, url: str) -> Any:
    status, kind, body = call(url)
    assert (status, kind) == ("200 OK", "application/json"), body[:300]
    return json.loads(body)


PAGES = ["/", "/runs", "/runs?page=1", "/run", f"/run?run={SAMPLE_RUN}", "/coverage",
         "/coverage?by=requirement", "/coverage?by=base",
         f"/scenario?run={SAMPLE_RUN}&id=cut-in%2Fclose.xosc",
         "/compare", f"/evaluations?run={SAMPLE_RUN}", "/evaluations",
         "/sets", "/sets?axis=simulator&by=tag", "/history", "/history?flaky=1",
         "/history/scenario?id=seedy.xosc"]  # fmt: skip


def test_every_page_renders(call: Call) -> None:
    for url in PAGES:
        status, kind, body = call(url)
        assert (status, kind) == ("200 OK", "text/html; charset=utf-8"), url
        assert b"Traceback" not in body and b"</html>" in body, url


def test_runs_and_coverage(call: Call) -> None:
    listed = _json(call, "/api/runs")
    assert listed["total"] == 9 and len(listed["runs"]) == 9
    sample = next(r for r in listed["runs"] if r["run_key"] == SAMPLE_RUN)
    assert sample["counts"] == {"Passed": 3, "Failed": 1, "Timeout": 1, "Invalid": 1,
                                "Skipped": 1}  # fmt: skip
    assert sample["total"] == 7 and sample["failing"] == 3
    assert sample["pass_rate"] == 0.5, "3 passed of the 6 that ran (one Skipped)"
    by_type = {g["label"]: g["counts"] for g in
               _json(call, f"/api/coverage?run={SAMPLE_RUN}&by=category")["groups"]}  # fmt: skip
    assert by_type["pedestrian"] == {"Passed": 1, "Timeout": 1}
    by_tag = {g["label"]: g["total"] for g in
              _json(call, f"/api/coverage?run={SAMPLE_RUN}&by=tag")["groups"]}  # fmt: skip
    assert by_tag == {"(none)": 3, "cut-in": 1, "highway": 2, "night": 1, "urban": 2}
    newest = _json(call, "/api/run")["run"]["run_key"]
    first = _json(call, "/api/history/scenario?id=steady.xosc")["history"]["entries"][-1]
    by_req = _json(call, f"/api/coverage?run={first['run_key']}&by=requirement")["groups"]
    assert {g["label"]: g["counts"] for g in by_req} == {
        "(none)": {"Passed": 4},
        "EuroNCAP-CCRs": {"Passed": 1},
        "UN-R157-5.2.5.2": {"Passed": 1},
    }
    assert newest != first["run_key"]


def test_coverage_by_base_scenario(call: Call) -> None:
    found = _json(call, f"/api/coverage?run={SAMPLE_RUN}&by=base")
    assert {g["label"]: g["counts"] for g in found["groups"]} == {
        "cut-in": {"Failed": 1}, "following": {"Passed": 2}}  # fmt: skip
    assert found["evaluation"] and found["note"] == ""
    never = _json(call, "/api/coverage?by=base")
    assert never["groups"] == [] and "no evaluation yet" in never["note"]
    status, _, body = call(f"/coverage?run={SAMPLE_RUN}&by=base")
    assert status == "200 OK" and b'data-label="following"' in body


def test_comparisons(call: Call) -> None:
    entries = _json(call, "/api/history/scenario?id=regress.xosc")["history"]["entries"]
    # Runs 6 (SUT 2.0) against 3 (SUT 1.0): regress.xosc regressed, steady.xosc unchanged.
    found = _json(call, f"/api/compare?base={entries[2]['run_key']}&other={entries[0]['run_key']}")
    assert found["counts"]["regressed"] == 1
    assert [c["id"] for c in found["changes"] if c["change"] == "regressed"] == ["regress.xosc"]
    default = _json(call, "/api/compare")
    assert default["other"]["run_key"] != default["base"]["run_key"]
    sets = _json(call, "/api/sets?axis=sut&by=category")
    assert sets["columns"] == ["idm-driver 1.0", "idm-driver 1.4.0", "idm-driver 2.0"]
    cut_in = dict(sets["rows"])["cut-in"]
    assert cut_in["idm-driver 2.0"]["counts"] == {"Passed": 2, "Failed": 2}
    assert cut_in["idm-driver 2.0"]["pass_rate"] == 0.5


def test_evaluations_of_one_run_side_by_side(call: Call) -> None:
    found = _json(call, f"/api/evaluations?run={SAMPLE_RUN}")
    (listed,) = found["evaluations"]
    assert (listed["criteria_name"], listed["counts"]) == ("strict", {"Passed": 2})
    assert listed["finished_at"] is not None
    # Default: the original verdicts against the newest finished evaluation.
    assert (found["base"], found["other"]) == ("original", listed["evaluation_id"])
    changes = {c["id"]: c for c in found["changes"]}
    close = changes["cut-in/close.xosc"]
    assert (close["change"], close["before"], close["after"], close["evidence"]) == (
        "fixed", "Failed", "Passed", "complete")  # fmt: skip
    assert changes["cut-in/far.xosc"]["change"] == "unchanged"
    assert found["counts"]["fixed"] == 1 and found["counts"]["removed"] == 5, "not re-scored"
    back = _json(call, f"/api/evaluations?run={SAMPLE_RUN}&base={listed['evaluation_id']}"
                       "&other=original")  # fmt: skip
    close = next(c for c in back["changes"] if c["id"] == "cut-in/close.xosc")
    assert (close["change"], close["reason"]) == ("regressed", "collision with 'cutter' at t=7.2 s")
    never = _json(call, "/api/evaluations")
    assert never["evaluations"] == [] and "no evaluation yet" in never["note"]
    assert set(never["counts"]) >= {"fixed", "regressed"} and never["counts"]["regressed"] == 0
    status, _, body = call(f"/evaluations?run={SAMPLE_RUN}")
    assert status == "200 OK" and b'<tr data-change="fixed">' in body
    status, _, body = call(f"/run?run={SAMPLE_RUN}")
    assert b'id="run-evaluations"' in body


def test_history_and_flakiness(call: Call) -> None:
    found = {s["scenario_id"]: s for s in _json(call, "/api/history")["summaries"]}
    assert found["nondet.xosc"]["flakiness"] == "nondeterministic"
    assert found["follow/stop.xosc"]["flakiness"] == "retried"
    assert found["regress.xosc"]["pass_rate"] == 0.6
    only = _json(call, "/api/history?flaky=1")
    assert only["flaky"] == len(only["summaries"]) == 5
    one = _json(call, "/api/history/scenario?id=seedy.xosc")
    assert one["history"]["summary"]["flakiness"] == "seed-sensitive"
    assert [e["verdict"] for e in one["history"]["entries"]] == ["Failed", "Passed", "Failed",
                                                                 "Passed"]  # fmt: skip


def test_developer_view_data(call: Call) -> None:
    view = _json(call, f"/api/scenario?run={SAMPLE_RUN}&id=cut-in%2Fclose.xosc")
    assert view["final"]["outcome"]["reason"] == "collision with 'cutter' at t=7.2 s"
    entities = {e["name"]: e for e in view["replay"]["entities"]}
    assert set(entities) == {"ego", "object 1"} and entities["ego"]["ego"]
    ego = entities["ego"]
    assert ego["t"][0] == 0.0 and ego["t"][-1] == 10.0 and ego["x"][-1] == 200.0
    ttc = next(s for s in view["replay"]["timelines"] if s["name"] == "ttc")
    assert ttc["unit"] == "s" and 2.0 not in ttc["t"], "the infinite sample is left out"
    retried = _json(call, f"/api/scenario?run={SAMPLE_RUN}&id=follow%2Fstop.xosc")
    assert [e["outcome"]["verdict"] for e in retried["earlier"]] == ["Error"]
    assert retried["summary"]["flakiness"] == "retried"


@pytest.mark.parametrize(
    ("url", "status", "message"),
    [
        ("/scenario?run=nope&id=x", "404 Not Found", "no campaign run 'nope'"),
        (f"/api/scenario?run={SAMPLE_RUN}&id=x", "404 Not Found", "scenario 'x' has no result"),
        ("/api/history/scenario?id=x", "404 Not Found", "scenario 'x' has no runs"),
        ("/api/coverage?by=colour", "400 Bad Request", "by must be one of category, road"),
        ("/api/runs?page=two", "400 Bad Request", "parameter 'page' must be a whole number"),
        # Unbounded, these reached the database as offsets past 64 bits: OverflowError, a 500.
        (
            "/api/runs?page=99999999999999999999",
            "400 Bad Request",
            "'page' must be a whole number from 0 to 20000",
        ),
        ("/api/runs?page=-1", "400 Bad Request", "from 0 to 20000"),
        ("/api/?last=99999999999999999999", "400 Bad Request", "'last' must be a whole number"),
        ("/api/sets?runs=99999999999999999999", "400 Bad Request", "'runs' must be a whole"),
        ("/api/history/scenario?id=x&limit=" + "9" * 5000, "400 Bad Request", "'limit' must be"),
        ("/api/sets?axis=moon", "400 Bad Request", "axis must be one of sut"),
        ("/nothing/here", "404 Not Found", "no page /nothing/here"),
        (f"/evaluations?run={SAMPLE_RUN}&other=x", "404 Not Found", "no evaluation 'x' of run"),
    ],
)
def test_bad_requests_are_one_line(call: Call, url: str, status: str, message: str) -> None:
    got, _, body = call(url)
    assert got == status
    text = html.unescape(body.decode())
    assert message in text and "Traceback" not in text


def test_static_probe_and_methods(call: Call) -> None:
    status, kind, body = call("/static/replay.js")
    assert status == "200 OK" and kind.startswith("text/javascript") and b"replay" in body
    assert call("/static/../server.py")[0] == "404 Not Found"
    assert call("/static/nope.js")[0] == "404 Not Found"
    assert call("/healthz")[:2] == ("200 OK", "text/plain")
    assert call("/", method="POST")[0] == "405 Method Not Allowed"


def test_the_developer_view_names_the_sut_image(tmp_path: Path) -> None:
    digest = "ghcr.io/acme/planner@sha256:" + "5e" * 32
    versions = {"sut.reported": "acme-planner 2.1.0", "sut.configHash": "sha256:0123456789abcdef",
                "sut.image": "ghcr.io/acme/planner:2.1.0", "sut.imageID": digest}  # fmt: skip
    scenario = results.ScenarioInfo(scenario_id="a.xosc", sha256="0" * 64)
    with results.open_store(tmp_path) as store:
        key = store.begin_campaign(results.CampaignInfo(name="byo", started_at=T0),
                                   scenarios=[scenario])  # fmt: skip
        outcome = ScenarioOutcome(scenario_id="a.xosc", verdict=Verdict.PASSED, versions=versions)
        store.add_outcome(key, scenario, outcome, recorded_at=T0)
    with ReadOnlyDatabase(tmp_path) as db:
        app = server.App(db, views.Context(base_dir=tmp_path))
        environ: dict[str, Any] = {"PATH_INFO": "/scenario",
                                   "QUERY_STRING": f"run={key}&id=a.xosc"}  # fmt: skip
        setup_testing_defaults(environ)
        body = b"".join(app(environ, lambda status, headers: None)).decode()
    row = body[body.index('id="sut-identity"') :].split("</tr>")[0]
    assert "acme-planner 2.1.0" in row and "sha256:0123456789abcdef" in row
    assert f'<code id="sut-image-id">{digest}</code>' in row
