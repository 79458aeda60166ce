"""A simulator pod's attempts in the results database (runner entrypoint + delivering).

Covers: run_job giving each attempt the pod's attempt number and every local artifact; a pinned
source the pod cannot read ending Error (the environment's fault), not Invalid; the rows a
pod writes into a real PostgreSQL (verdict, reason, metrics, versions, scenario and recording
hashes, artifact URIs under the run spec's prefix, header labels, a provisional campaign record);
a re-delivered attempt (retried pod, restarted runner) replacing its row, a new attempt adding
one; a database that is down keeping every verdict, flagging ``resultsStored: false`` in the
termination message and keeping the password out of the log; a DSN without a run key; no database
configured; the flag never pushing the message past 4 KiB; ``main`` end to end with a real
scenario and PostgreSQL; SIGTERM (the pod deleted) keeping what finished and making the running
and unstarted scenarios Error, and a real runner stopping within seconds of it.
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import pytest

from simtest_operator import results
from simtest_operator.render import RunSpec, ScenarioRef, messages
from simtest_operator.runner import delivering, entrypoint, scenario_execution
from simtest_operator.settings import RESULTS_DSN, RESULTS_RUN_KEY
from simtest_operator.verdicts import ScenarioOutcome, Verdict
from tests.runner import podsupport

KEY = "nightly-20250301T115900Z-0badcafe"
REPO = Path(__file__).resolve().parents[2]


def _env(dsn: str, key: str | None = KEY) -> dict[str, str]:
    env = {RESULTS_DSN: dsn}
    if key is not None:
        env[RESULTS_RUN_KEY] = key
    return env


def _dead_dsn() -> str:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    return f"postgresql://runner:s3cret-pw@127.0.0.1:{port}/results"


def test_run_job_numbers_the_attempt_and_lists_local_artifacts(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass"}, attempt=3)
    [attempt] = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    assert attempt.outcome.attempts == 3
    assert attempt.path is not None and attempt.path.name == "a.xosc"
    assert attempt.folder == job.artifacts / "a.xosc"
    assert set(attempt.outcome.artifacts) == {"recording", "log", "result"}
    assert attempt.outcome.artifacts["result"] == str(attempt.folder / "result.json")


@pytest.mark.postgres
def test_the_pod_writes_its_attempts_into_postgresql(tmp_path: Path, postgres_dsn: str) -> None:
    job = podsupport.job(
        tmp_path, {"a": "pass", "b": "fail"}, attempt=2, artifacts_uri="pvc://shared/nightly/e0"
    )
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    deliverer = podsupport.deliverer(job, _env(postgres_dsn))
    delivered = deliverer.deliver(attempts)
    assert delivered.unstored == frozenset()
    assert delivered.notes == ()

    with results.open_store(postgres_dsn) as store:
        key = results.RunKey(KEY)
        record = store.campaign(key)
        stored = {s.scenario.scenario_id: s for s in store.outcomes(key, final_only=False)}
    assert record is not None and record.info.name == "nightly" and not record.finished
    assert record.info.sut_version == "2.1.0"
    assert set(stored) == {"a.xosc", "b.xosc"}
    b = stored["b.xosc"]
    assert b.outcome.verdict is Verdict.FAILED
    assert b.outcome.reason == "minTTC 0.9 s < 1.5 s"
    assert b.outcome.attempts == 2
    assert b.outcome.metrics == {"minTTC": 0.9, "maxDecel": 4.0}
    assert b.outcome.versions == {"simtest": "0.1.0", "sut": "idm-driver 2.1.0"}
    assert b.outcome.artifacts == {
        "recording": "pvc://shared/nightly/e0/b.xosc/recording.mcap",
        "log": "pvc://shared/nightly/e0/b.xosc/run.log",
        "result": "pvc://shared/nightly/e0/b.xosc/result.json",
    }
    recording = (job.artifacts / "b.xosc" / "recording.mcap").read_bytes()
    assert b.content_hashes == {
        "scenario": job.spec.scenarios[1].sha256,
        "recording": hashlib.sha256(recording).hexdigest(),
    }
    assert b.scenario.tags == ("highway",)
    assert b.scenario.category == "cut-in"
    assert delivered.outcomes[1] == b.outcome


@pytest.mark.postgres
def test_a_redelivered_attempt_replaces_its_row(tmp_path: Path, postgres_dsn: str) -> None:
    job = podsupport.job(tmp_path / "one", {"a": "pass"}, attempt=1)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    for _ in range(2):  # the runner delivering twice, or a pod re-run with the same attempt
        podsupport.deliverer(job, _env(postgres_dsn)).deliver(attempts)
    retry = podsupport.job(tmp_path / "two", {"a": "fail"}, attempt=2)
    retried = entrypoint.run_job(retry, run_one=podsupport.fake_run_one, fork=False)
    assert retried[0].scenario.id == attempts[0].scenario.id
    # Same id, another file content: a retried pod of the same scenario would share the digest;
    # what matters here is the (run, scenario, attempt) key.
    podsupport.deliverer(retry, _env(postgres_dsn)).deliver(retried)
    with results.open_store(postgres_dsn) as store:
        every = store.outcomes(results.RunKey(KEY), final_only=False)
        final = store.outcomes(results.RunKey(KEY))
    assert [(s.outcome.attempts, s.verdict) for s in every] == [
        (1, Verdict.PASSED),
        (2, Verdict.FAILED),
    ]
    assert [(s.outcome.attempts, s.verdict) for s in final] == [(2, Verdict.FAILED)]


def test_a_database_that_is_down_keeps_every_verdict(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass", "b": "fail"})
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    delivered = podsupport.deliverer(job, _env(_dead_dsn())).deliver(attempts)
    assert delivered.unstored == {"a.xosc", "b.xosc"}
    assert [o.verdict for o in delivered.outcomes] == [Verdict.PASSED, Verdict.FAILED]
    assert [o.reason for o in delivered.outcomes] == ["", "minTTC 0.9 s < 1.5 s"]
    log = "\n".join(delivered.notes)
    assert "cannot connect to the results database postgresql://127.0.0.1" in log
    assert "s3cret-pw" not in log

    path = tmp_path / "termination-log"
    text = entrypoint.write_message(delivered.outcomes, path, unstored=delivered.unstored)
    data = json.loads(path.read_text())
    assert text == path.read_text()
    assert [e[messages.RESULTS_STORED] for e in data["results"]] == [False, False]
    decoded = messages.decode(text)
    assert [o.verdict for o in decoded] == [Verdict.PASSED, Verdict.FAILED]


def test_a_dsn_without_a_run_key_stores_nothing(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass"})
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    delivered = podsupport.deliverer(
        job, _env("postgresql://x@127.0.0.1:1/none", key=None)
    ).deliver(attempts)
    assert delivered.unstored == {"a.xosc"}
    assert delivered.notes == (f"results not stored: no run key (set {RESULTS_RUN_KEY})",)
    assert delivered.outcomes[0].verdict is Verdict.PASSED


def test_without_a_database_nothing_is_flagged(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass"})
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    delivered = podsupport.deliverer(job, {}).deliver(attempts)
    assert delivered.unstored == frozenset() and delivered.notes == ()
    text = entrypoint.write_message(delivered.outcomes, tmp_path / "log")
    assert messages.RESULTS_STORED not in text
    assert delivered.outcomes[0].artifacts["result"] == str(attempts[0].folder / "result.json")


def test_the_flag_keeps_the_message_within_the_limit(tmp_path: Path) -> None:
    outcomes = [
        ScenarioOutcome(
            scenario_id=f"family-{i:03d}/scenario-with-a-long-name.xosc",
            verdict=Verdict.FAILED,
            reason="minTTC 0.2 s below 1.5 s while the cut-in vehicle merged " * 5,
            metrics={"minTTC": 0.2, "minTHW": 0.3, "maxDecel": 8.0},
        )
        for i in range(40)
    ]
    unstored = {o.scenario_id for o in outcomes}
    text = entrypoint.write_message(outcomes, tmp_path / "log", unstored=unstored)
    assert len(text.encode()) <= messages.LIMIT_BYTES
    entries = json.loads(text)["results"]
    assert entries and all(e[messages.RESULTS_STORED] is False for e in entries)


@pytest.mark.postgres
@pytest.mark.slow
def test_main_runs_a_real_scenario_and_stores_its_row(
    tmp_path: Path, postgres_dsn: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    scenario = Path(__file__).parents[2] / "scenarios/smoke/hard-braking_rural_v15_thw2_d4.xosc"
    spec = RunSpec(
        campaign="nightly",
        environment="e0",
        attempt=1,
        scenarios=(
            ScenarioRef(
                id="hard-braking.xosc",
                source=scenario.as_uri(),
                sha256=hashlib.sha256(scenario.read_bytes()).hexdigest(),
            ),
        ),
        timeout_seconds=60,
        artifacts_dir=str(tmp_path / "artifacts"),
    )
    monkeypatch.setenv("SIMTEST_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv(RESULTS_DSN, postgres_dsn)
    monkeypatch.setenv(RESULTS_RUN_KEY, KEY)
    termination = tmp_path / "termination-log"
    entrypoint.main(["--spec", spec.dumps(), "--termination-log", str(termination)])
    [outcome] = messages.decode(termination.read_text())
    assert messages.RESULTS_STORED not in termination.read_text()
    with results.open_store(postgres_dsn) as store:
        [row] = store.outcomes(results.RunKey(KEY))
    assert row.outcome.verdict is outcome.verdict
    assert row.outcome.verdict in (Verdict.PASSED, Verdict.FAILED)
    assert "recording" in row.content_hashes
    assert row.outcome.artifacts["recording"].endswith("hard-braking.xosc/recording.mcap")


def test_a_pinned_source_the_pod_cannot_read_is_an_error_not_invalid(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"gone": "pass", "kept": "pass"})
    (tmp_path / "scenarios" / "gone.xosc").unlink()
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    outcomes = {a.outcome.scenario_id: a.outcome for a in attempts}
    assert outcomes["gone.xosc"].verdict is Verdict.ERROR
    assert "cannot fetch the pinned scenario" in outcomes["gone.xosc"].reason
    assert "SIMTEST_OPERATOR_SCENARIO_CLAIM" in outcomes["gone.xosc"].reason
    assert outcomes["kept.xosc"].verdict is Verdict.PASSED


def test_sigterm_keeps_what_finished_and_makes_the_rest_error(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass", "b": "pass", "c": "pass"})

    def terminated_on_b(request: scenario_execution.RunRequest) -> ScenarioOutcome:
        if request.scenario.name == "b.xosc":
            raise entrypoint.Terminated
        return podsupport.fake_run_one(request)

    attempts = entrypoint.run_job(job, run_one=terminated_on_b, fork=False)
    outcomes = {a.outcome.scenario_id: a.outcome for a in attempts}
    assert outcomes["a.xosc"].verdict is Verdict.PASSED
    assert outcomes["b.xosc"].verdict is Verdict.ERROR
    assert outcomes["b.xosc"].reason == entrypoint.TERMINATED_REASON
    assert outcomes["c.xosc"].verdict is Verdict.ERROR
    assert outcomes["c.xosc"].reason == entrypoint.NOT_STARTED_REASON


def test_the_message_holds_every_verdict_so_far_after_each_scenario(tmp_path: Path) -> None:
    # A warm pod killed mid-queue (SIGKILL, the OOM killer) leaves this file to the kubelet.
    job = podsupport.job(tmp_path, {"a": "pass", "b": "fail", "c": "pass"})
    log = tmp_path / "termination-log"
    seen: list[list[str]] = []

    def progress(done: Sequence[delivering.Attempt]) -> None:
        entrypoint._report(done, log)
        seen.append([o.scenario_id for o in messages.decode(log.read_text())])

    entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False, progress=progress)
    assert seen == [["a.xosc"], ["a.xosc", "b.xosc"], ["a.xosc", "b.xosc", "c.xosc"]]


def test_stopped_scenarios_are_flagged_in_the_message(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass", "b": "pass"})

    def terminated_on_b(request: scenario_execution.RunRequest) -> ScenarioOutcome:
        if request.scenario.name == "b.xosc":
            raise entrypoint.Terminated
        return podsupport.fake_run_one(request)

    attempts = entrypoint.run_job(job, run_one=terminated_on_b, fork=False)
    stopped = frozenset(a.scenario.id for a in attempts if a.stopped)
    text = entrypoint.write_message(
        [a.outcome for a in attempts], tmp_path / "log", stopped=stopped
    )
    assert messages.flagged(text, messages.STOPPED, True) == {"b.xosc"}


GRACE_SECONDS = 30
"""A pod's default termination grace period: the kubelet kills the container after it."""


@pytest.mark.slow
def test_the_runner_stops_on_sigterm_within_seconds(tmp_path: Path) -> None:
    scenario = REPO / "scenarios" / "smoke" / "following_highway_v25_thw2_drop5_d2.xosc"
    spec = RunSpec(
        campaign="c",
        environment="c-e0",
        attempt=1,
        scenarios=(
            ScenarioRef(
                id=scenario.name,
                source=scenario.as_uri(),
                sha256=hashlib.sha256(scenario.read_bytes()).hexdigest(),
            ),
        ),
        isolation="PerScenario",
        timeout_seconds=60,
        artifacts_dir=str(tmp_path / "artifacts"),
        simulator={"realTimeFactor": 1.0},
    )
    log = tmp_path / "termination-log"
    recording = tmp_path / "artifacts" / entrypoint.safe_name(scenario.name) / "recording.mcap"
    runner = subprocess.Popen(
        [str(Path(sys.executable).parent / "simtest-runner"), "--spec", spec.dumps(),
         "--termination-log", str(log)],
        env={**os.environ, "SIMTEST_CACHE_DIR": str(tmp_path / "cache")},
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    # The recording is opened just before the first step: the runner is past its start-up (and
    # its SIGTERM handler) and simulating in real time (10 s). No fixed sleep: start-up takes
    # 0.7 s on an idle machine and several seconds on a loaded one.
    deadline = time.monotonic() + 60
    while not recording.exists():
        assert runner.poll() is None, "the runner exited before it started the scenario"
        assert time.monotonic() < deadline, "the runner never started the scenario"
        time.sleep(0.05)
    runner.send_signal(signal.SIGTERM)
    stopped = time.monotonic()
    runner.wait(timeout=GRACE_SECONDS)
    assert time.monotonic() - stopped < GRACE_SECONDS, "the kubelet would have killed it"
    (outcome,) = messages.decode(log.read_text())
    assert outcome.verdict is Verdict.ERROR, outcome
    assert "SIGTERM" in outcome.reason
    # The mechanism, not the machine's speed: the scenario ends at 10 s simulated in real time,
    # so only a run cut short by SIGTERM (not one left to finish) takes less wall time.
    assert 0 < outcome.wall_seconds < 10, outcome.wall_seconds
