"""The evaluation step's Job (render/evaluationjobs.py), rendered from plain values.

Covers: the pod template passes the restricted Pod Security checks the simulator pods are held
to; the DSN and the S3 keys come only through ``secretKeyRef`` (no secret value can appear: the
renderer is never given one); the criteria ConfigMap key and an artifacts claim are mounted
read-only and named in the command; the TestCampaign owns the Job; exit 1 and 2 end the Job
without a retry, crashes are retried ``backoffLimit`` times and node drains are not counted;
the summary goes to the termination message.
"""

from __future__ import annotations

import json
from typing import Any

from simtest_operator.render import ArtifactTarget, OwnerRef, PvcVolume, S3Target, SecretKey
from simtest_operator.render import evaluationjobs as ej
from simtest_operator.render.podchecks import security_problems

SECRET_VALUE = "postgresql://simtest:hunter2@db:5432/results"


def _request(**changes: Any) -> ej.EvaluationJobRequest:
    fields: dict[str, Any] = {
        "name": "camp-evaluate",
        "namespace": "ns",
        "labels": {"simtest.dev/campaign": "camp"},
        "owner": OwnerRef(
            api_version="simtest.dev/v1alpha1", kind="TestCampaign", name="camp", uid="cu"
        ),
        "service_account": "camp-simulator",
        "image": "ghcr.io/simtest-dev/simtest-runner:0.1.0",
        "run_key": "camp-20300101T000000Z-7416feb0",
        "results_dsn": SecretKey(name="results-db", key="dsn"),
        "artifacts": ArtifactTarget(
            s3=S3Target(endpoint="http://minio:9000", secret_name="artifacts-s3"),
            uri_prefix="s3://bucket/camp",
        ),
        "criteria": ej.ConfigMapKey(name="crit", key="strict.yaml"),
        "backoff_limit": 2,
    }
    return ej.EvaluationJobRequest(**(fields | changes))


def _container(job: dict[str, Any]) -> dict[str, Any]:
    (container,) = job["spec"]["template"]["spec"]["containers"]
    return dict(container)


def test_the_pod_meets_the_restricted_profile() -> None:
    job = ej.job(_request(artifacts=ArtifactTarget(pvc=PvcVolume(claim_name="runs"))))
    spec = job["spec"]["template"]["spec"]
    assert security_problems(spec) == []
    assert spec["automountServiceAccountToken"] is False
    assert spec["serviceAccountName"] == "camp-simulator"
    assert spec["restartPolicy"] == "Never"
    assert not any(spec.get(k) for k in ("hostNetwork", "hostPID", "hostIPC"))


def test_secrets_only_by_reference() -> None:
    job = ej.job(_request())
    env = {e["name"]: e for e in _container(job)["env"]}
    refs = {
        name: (e["valueFrom"]["secretKeyRef"]["name"], e["valueFrom"]["secretKeyRef"]["key"])
        for name, e in env.items()
        if "valueFrom" in e
    }
    assert refs == {
        "SIMTEST_RESULTS_DSN": ("results-db", "dsn"),
        "AWS_ACCESS_KEY_ID": ("artifacts-s3", "AWS_ACCESS_KEY_ID"),
        "AWS_SECRET_ACCESS_KEY": ("artifacts-s3", "AWS_SECRET_ACCESS_KEY"),
    }
    assert env["AWS_ENDPOINT_URL_S3"]["value"] == "http://minio:9000"
    text = json.dumps(job)
    assert "postgresql://" not in text and SECRET_VALUE not in text
    # The DSN is not on the command line either: simtest evaluate reads it from the variable.
    assert not any("$(" in arg for arg in _container(job)["args"])


def test_command_mounts_and_ownership() -> None:
    job = ej.job(_request(artifacts=ArtifactTarget(pvc=PvcVolume(claim_name="runs", sub_path="x"))))
    container = _container(job)
    assert container["command"] == ["simtest"]
    assert container["args"] == [
        "evaluate",
        "--run",
        "camp-20300101T000000Z-7416feb0",
        "--summary-file",
        "/dev/termination-log",
        "--criteria",
        "/etc/simtest/criteria/strict.yaml",
        "--pvc-root",
        "/pvc",
    ]
    mounts = {m["name"]: m for m in container["volumeMounts"]}
    assert mounts["criteria"] == {
        "name": "criteria",
        "mountPath": "/etc/simtest/criteria",
        "readOnly": True,
    }
    assert mounts["artifacts"] == {"name": "artifacts", "mountPath": "/pvc/runs", "readOnly": True}
    volumes = {v["name"]: v for v in job["spec"]["template"]["spec"]["volumes"]}
    assert volumes["criteria"]["configMap"] == {
        "name": "crit",
        "items": [{"key": "strict.yaml", "path": "strict.yaml"}],
    }
    assert volumes["artifacts"]["persistentVolumeClaim"] == {"claimName": "runs", "readOnly": True}
    assert container["terminationMessagePath"] == "/dev/termination-log"
    assert container["terminationMessagePolicy"] == "FallbackToLogsOnError"
    (owner,) = job["metadata"]["ownerReferences"]
    assert owner == {
        "apiVersion": "simtest.dev/v1alpha1",
        "kind": "TestCampaign",
        "name": "camp",
        "uid": "cu",
        "controller": True,
        "blockOwnerDeletion": True,
    }
    assert job["spec"]["template"]["metadata"]["labels"] == {"simtest.dev/campaign": "camp"}


def test_default_criteria_and_no_volume_without_a_claim() -> None:
    job = ej.job(_request(criteria=None))
    container = _container(job)
    assert "--criteria" not in container["args"] and "--pvc-root" not in container["args"]
    assert {v["name"] for v in job["spec"]["template"]["spec"]["volumes"]} == {"tmp"}


def test_answers_are_final_crashes_are_retried() -> None:
    spec = ej.job(_request(backoff_limit=3))["spec"]
    assert spec["backoffLimit"] == 3
    fail_job, ignore = spec["podFailurePolicy"]["rules"]
    assert fail_job == {
        "action": "FailJob",
        "onExitCodes": {"containerName": "evaluate", "operator": "In", "values": [1, 2]},
    }
    assert ignore == {"action": "Ignore", "onPodConditions": [{"type": "DisruptionTarget"}]}
    assert isinstance(spec["activeDeadlineSeconds"], int)
