"""A simulator pod's artifacts in an S3-compatible bucket (moto's real server, boto3 unpatched).

Covers: with an ``s3://`` artifacts URI and the standard ``AWS_*`` variables, recording, log and
result file land at ``<prefix>/<campaign>/<environment>/<scenario>/`` and the reported URIs (the
termination message's and the database row's) point there, the uploaded result file included; an
upload that fails keeps the local path, says so in the reason and keeps the verdict; a pod without
credentials does the same without trying.
"""

from __future__ import annotations

import json
from pathlib import Path

from simtest_operator import results
from simtest_operator.results import uploading
from simtest_operator.runner import delivering, entrypoint
from simtest_operator.settings import RESULTS_DSN, RESULTS_RUN_KEY
from simtest_operator.verdicts import Verdict
from tests.results.s3server import BUCKET, CREDENTIALS, S3Server, free_port, s3
from tests.runner import podsupport

__all__ = ["s3"]  # the fixture, used by name

PREFIX = f"s3://{BUCKET}/team-a/nightly/nightly-b0-s0-a1"
KEY = "nightly-20250301T115900Z-0badcafe"


def _aws_env(s3: S3Server) -> dict[str, str]:
    return {
        "AWS_ENDPOINT_URL_S3": s3.endpoint,
        "AWS_ACCESS_KEY_ID": CREDENTIALS["access_key_id"],
        "AWS_SECRET_ACCESS_KEY": CREDENTIALS["secret_access_key"],
    }


def test_artifacts_are_uploaded_and_reported_as_s3_uris(tmp_path: Path, s3: S3Server) -> None:
    job = podsupport.job(tmp_path, {"a": "pass", "b": "fail"}, artifacts_uri=PREFIX)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    database = tmp_path / "results.sqlite"
    env = {
        **_aws_env(s3),
        RESULTS_DSN: str(database),
        RESULTS_RUN_KEY: KEY,
    }
    delivered = podsupport.deliverer(job, env).deliver(attempts)
    assert delivered.notes == () and delivered.unstored == frozenset()

    base = "team-a/nightly/nightly-b0-s0-a1"
    assert s3.keys() == sorted(
        f"{base}/{s}.xosc/{f}" for s in "ab" for f in ("recording.mcap", "run.log", "result.json")
    )
    b = delivered.outcomes[1]
    assert b.verdict is Verdict.FAILED and b.reason == "minTTC 0.9 s < 1.5 s"
    assert b.artifacts == {
        "recording": f"{PREFIX}/b.xosc/recording.mcap",
        "log": f"{PREFIX}/b.xosc/run.log",
        "result": f"{PREFIX}/b.xosc/result.json",
    }
    local = job.artifacts / "b.xosc"
    assert s3.read(f"{base}/b.xosc/recording.mcap") == (local / "recording.mcap").read_bytes()
    uploaded = json.loads(s3.read(f"{base}/b.xosc/result.json"))
    assert uploaded["artifacts"] == b.artifacts
    assert uploaded["verdict"] == "Failed"

    text = entrypoint.write_message(delivered.outcomes, tmp_path / "termination-log")
    assert f"{PREFIX}/b.xosc/result.json" in text
    with results.open_store(database) as store:
        rows = {s.scenario.scenario_id: s for s in store.outcomes(results.RunKey(KEY))}
    assert rows["b.xosc"].outcome.artifacts == b.artifacts


def test_a_failed_upload_keeps_the_local_path_and_the_verdict(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "pass"}, artifacts_uri=PREFIX)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    down = S3Server(port=free_port())  # never started: every connection is refused
    pauses: list[float] = []
    deliverer = delivering.Deliverer(
        campaign="nightly",
        artifacts_root=job.artifacts,
        uri_prefix=PREFIX,
        uploader=uploading.Uploader(
            uploading.S3Location.parse(PREFIX),
            down.credentials(),
            policy=uploading.UploadPolicy(attempts=2, connect_timeout_seconds=1.0),
            sleep=pauses.append,
        ),
    )
    [outcome] = deliverer.deliver(attempts).outcomes
    assert outcome.verdict is Verdict.PASSED
    assert outcome.artifacts == attempts[0].outcome.artifacts  # local paths
    assert outcome.reason == (
        "artifacts kept on the pod's volume, upload failed: recording, log, result"
    )
    assert pauses == [0.5, 0.5, 0.5]  # one backoff per file, then given up
    written = json.loads((job.artifacts / "a.xosc" / "result.json").read_text())
    assert (written["verdict"], written["reason"]) == ("Passed", outcome.reason)
    assert written["artifacts"] == outcome.artifacts


def test_a_pod_without_credentials_does_not_try(tmp_path: Path) -> None:
    job = podsupport.job(tmp_path, {"a": "fail"}, artifacts_uri=PREFIX)
    attempts = entrypoint.run_job(job, run_one=podsupport.fake_run_one, fork=False)
    deliverer = podsupport.deliverer(job, {})
    assert deliverer.uploader is None
    delivered = deliverer.deliver(attempts)
    [outcome] = delivered.outcomes
    assert outcome.verdict is Verdict.FAILED
    assert outcome.reason.startswith("minTTC 0.9 s < 1.5 s; artifacts kept on the pod's volume")
    assert outcome.artifacts == attempts[0].outcome.artifacts
    assert "AWS_ACCESS_KEY_ID" in delivered.notes[0]
