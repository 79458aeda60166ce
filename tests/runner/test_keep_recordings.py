"""``spec.artifacts.keepRecordings: false`` on a simulator pod: the recording is not kept.

Covers: the flag travels planner → run spec (on the wire only when false, so existing pods' run
specs are unchanged) → runner; with it off, each recording is deleted after the run computed its
metrics, its URI is absent from the termination message, the results row and the local
``result.json``, its digest is still recorded, and with S3 it is never uploaded (log and result
file are); with it on (the default) nothing changes.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Any

from simtest_operator import results
from simtest_operator.operator.actions import Kind
from simtest_operator.render import RunSpec
from simtest_operator.runner import entrypoint
from simtest_operator.settings import RESULTS_DSN, RESULTS_RUN_KEY
from tests.operator.fakecluster import FakeCluster, campaign_body, frozen_list
from tests.results.s3server import BUCKET, CREDENTIALS, S3Server, s3
from tests.runner import podsupport

__all__ = ["s3"]  # the fixture, used by name

KEY = "nightly-20250301T115900Z-0badcafe"


def _job(tmp_path: Path, *, keep: bool, uri: str = "") -> entrypoint.Job:
    job = podsupport.job(tmp_path, {"a": "pass", "b": "fail"}, artifacts_uri=uri)
    return dataclasses.replace(job, spec=dataclasses.replace(job.spec, keep_recordings=keep))


def _pod_spec(artifacts: dict[str, Any]) -> RunSpec:
    body = campaign_body(batchSize=1)
    body["spec"]["artifacts"] = artifacts
    cluster = FakeCluster()
    cluster.start_campaign(body, frozen_list(1), batch_size=1)
    cluster.step()
    (pod,) = cluster.of(Kind.POD)
    env = {e["name"]: e.get("value") for e in pod["spec"]["containers"][0]["env"]}
    return RunSpec.loads(env["SIMTEST_RUN_SPEC"])


def test_the_flag_travels_from_the_campaign_to_the_run_spec() -> None:
    assert _pod_spec({"keepRecordings": False}).keep_recordings is False
    kept = _pod_spec({})
    assert kept.keep_recordings is True and "keepRecordings" not in kept.to_json()
    assert RunSpec.loads(_pod_spec({"keepRecordings": False}).dumps()).keep_recordings is False


def test_recordings_are_deleted_after_the_run_and_never_reported(tmp_path: Path) -> None:
    job = _job(tmp_path, keep=False)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    recordings = {a.outcome.scenario_id: a.folder / "recording.mcap" for a in attempts}
    digests = {k: hashlib.sha256(p.read_bytes()).hexdigest() for k, p in recordings.items()}
    database = tmp_path / "results.sqlite"
    env = {RESULTS_DSN: str(database), RESULTS_RUN_KEY: KEY}
    delivered = podsupport.deliverer(job, env).deliver(attempts)

    assert delivered.notes == () and delivered.unstored == frozenset()
    assert not any(p.exists() for p in recordings.values())
    for outcome in delivered.outcomes:
        assert "recording" not in outcome.artifacts
        assert set(outcome.artifacts) == {"log", "result"}
        assert Path(outcome.artifacts["log"]).is_file()
        assert outcome.metrics["minTTC"] in (0.9, 3.2)  # computed by the run, kept
        local = json.loads(Path(outcome.artifacts["result"]).read_text())
        assert "recording" not in local["artifacts"]
    text = entrypoint.write_message(delivered.outcomes, tmp_path / "termination-log")
    assert '"recording"' not in text and "recording.mcap" not in text
    with results.open_store(database) as store:
        rows = {r.scenario.scenario_id: r for r in store.outcomes(results.RunKey(KEY))}
    assert set(rows) == {"a.xosc", "b.xosc"}
    for scenario_id, row in rows.items():
        assert "recording" not in row.outcome.artifacts
        assert row.content_hashes["recording"] == digests[scenario_id]


def test_with_s3_the_recording_is_not_uploaded(tmp_path: Path, s3: S3Server) -> None:
    prefix = f"s3://{BUCKET}/team-a/nightly/nightly-b0-s0-a1"
    job = _job(tmp_path, keep=False, uri=prefix)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    env = {
        "AWS_ENDPOINT_URL_S3": s3.endpoint,
        "AWS_ACCESS_KEY_ID": CREDENTIALS["access_key_id"],
        "AWS_SECRET_ACCESS_KEY": CREDENTIALS["secret_access_key"],
    }
    delivered = podsupport.deliverer(job, env).deliver(attempts)
    base = "team-a/nightly/nightly-b0-s0-a1"
    assert s3.keys() == sorted(
        f"{base}/{s}.xosc/{f}" for s in "ab" for f in ("run.log", "result.json")
    )
    for outcome in delivered.outcomes:
        assert outcome.artifacts == {
            "log": f"{prefix}/{outcome.scenario_id}/run.log",
            "result": f"{prefix}/{outcome.scenario_id}/result.json",
        }
        uploaded = json.loads(s3.read(f"{base}/{outcome.scenario_id}/result.json"))
        assert uploaded["artifacts"] == outcome.artifacts


def test_by_default_recordings_are_kept(tmp_path: Path) -> None:
    job = _job(tmp_path, keep=True)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    delivered = podsupport.deliverer(job, {}).deliver(attempts)
    for outcome in delivered.outcomes:
        assert Path(outcome.artifacts["recording"]).is_file()
