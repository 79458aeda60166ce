"""The evaluation step (``spec.evaluation.offline``) on the real node: a real Job in the runner
image re-scores a campaign's recordings from PostgreSQL and S3 after its runs.

As in ``test_results_from_pods.py``: real SUMO smoke scenarios in real containers under the
kubelet, a throw-away PostgreSQL server for the results database and moto's S3 server for the
artifacts, both reached through the node network; the real ``simtest operator`` process; the
namespace enforces the ``restricted`` Pod Security profile, so the Job's pod is admitted only if
it meets it.

Covers:

* after the campaign's verdicts, exactly one Job ``<campaign>-evaluate`` owned by the campaign;
  its pod reads the DSN and the S3 keys through ``secretKeyRef`` and the criteria from the
  mounted ConfigMap, downloads the ``s3://`` recordings and stores a new, finished evaluation of
  the run with the ConfigMap's criteria set and complete evidence; the campaign's condition
  ``Evaluated`` is True/``Failed`` (the collision of the smoke cut-in) with the summary line as
  its message, ``status.evaluation.id`` names the stored evaluation, the phase stays ``Failed``,
  and the events say so;
* a criteria set that does not load: exit 2, ``Evaluated`` False/``Error`` naming the file and
  the field, not retried (one pod), nothing stored.
"""

from __future__ import annotations

import urllib.parse
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from kubernetes import client

from simtest_operator import results
from simtest_operator.operator import observed, recording_results
from tests.e2e import support
from tests.realnode.conftest import create_secret, results_campaign, wait_for
from tests.results.s3server import BUCKET, CREDENTIALS, S3Server, s3

__all__ = ["s3"]  # the fixture, used by name

FAILING = "cut-in_highway_v30_gap8_dv12.xosc"
PASSING = "cut-in_highway_v25_gap30_dv5.xosc"
STRICT = "name: strict-cm\ncollision: true\nbaseScenarios:\n  cut-in: {minTTC: 0.5}\n"
"""Checks collisions on cut-ins (the failing scenario's), other types keep the defaults."""
BROKEN = "name: broken\nbaseScenarios:\n  cut-in: {minTCC: 1.2}\n"


@pytest.fixture
def cluster(real_api_client: client.ApiClient, real_namespace: str) -> support.Cluster:
    return support.Cluster(real_api_client, real_namespace)


def _setup(
    cluster: support.Cluster, *, postgres_dsn: str, s3: S3Server, expose: Callable[[int], str]
) -> str:
    """Secrets (DSN reachable from pods, S3 keys) and the criteria ConfigMap; the S3 endpoint."""
    port = urllib.parse.urlsplit(postgres_dsn).port
    assert port is not None
    dsn = postgres_dsn.replace(f"127.0.0.1:{port}", expose(port))
    secrets = {
        "results-db": {"dsn": dsn},
        "artifacts-s3": {
            "AWS_ACCESS_KEY_ID": CREDENTIALS["access_key_id"],
            "AWS_SECRET_ACCESS_KEY": CREDENTIALS["secret_access_key"],
        },
    }
    for name, data in secrets.items():
        create_secret(cluster, name, data)
    cluster.core.create_namespaced_config_map(
        cluster.namespace,
        {"metadata": {"name": "criteria"}, "data": {"strict.yaml": STRICT, "broken.yaml": BROKEN}},
    )
    return f"http://{expose(s3.port)}"


def _campaign(
    tmp_path: Path, name: str, names: tuple[str, ...], *, endpoint: str, key: str
) -> dict[str, Any]:
    body = results_campaign(
        tmp_path, name, names, database="results-db", s3=endpoint, prefix="eval"
    )
    body["spec"]["evaluation"]["offline"] = {
        "criteria": {"configMapRef": {"name": "criteria", "key": key}},
        "backoffLimit": 1,
    }
    return body


def _evaluated(cluster: support.Cluster, name: str) -> dict[str, Any] | None:
    for condition in cluster.status(name).get("conditions", []):
        if condition["type"] == "Evaluated" and condition["reason"] != "Running":
            return dict(condition)
    return None


def _job_pods(cluster: support.Cluster, job: str) -> list[Any]:
    return list(
        cluster.core.list_namespaced_pod(cluster.namespace, label_selector=f"job-name={job}").items
    )


@pytest.mark.postgres
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_the_evaluation_step_rescores_the_run_from_the_database(
    real_operator: support.OperatorProcess,
    cluster: support.Cluster,
    postgres_dsn: str,
    s3: S3Server,
    expose: Callable[[int], str],
    tmp_path: Path,
) -> None:
    endpoint = _setup(cluster, postgres_dsn=postgres_dsn, s3=s3, expose=expose)
    names = (FAILING, PASSING)
    cluster.create(_campaign(tmp_path, "evaluated", names, endpoint=endpoint, key="strict.yaml"))
    status = cluster.wait_complete("evaluated", timeout=600, alive=real_operator.alive)
    assert status["phase"] == "Failed"
    condition = wait_for(
        "the Evaluated condition", lambda: _evaluated(cluster, "evaluated"), timeout=300
    )
    status = cluster.status("evaluated")
    assert (condition["status"], condition["reason"]) == ("True", "Failed"), condition
    assert status["phase"] == "Failed"  # evidence added, not a re-run
    message = condition["message"]
    assert "with criteria 'strict-cm': 1 failed, 1 passed" in message, message
    assert f"1 of 2 scenarios not passed (first: {FAILING}: Failed" in message, message
    evaluation_id = status["evaluation"]["id"]
    assert status["evaluation"]["job"] == "evaluated-evaluate"

    # The database: a finished evaluation of the campaign's run, with the ConfigMap's criteria,
    # from the s3:// recordings, with complete evidence.
    campaign = cluster.get("testcampaigns", "evaluated")
    key = recording_results.run_key(observed.campaign_view(campaign))
    with results.open_store(postgres_dsn) as store:
        (evaluation,) = store.evaluations(key)
        runs = {r.scenario_id: r for r in store.evaluated_runs(evaluation.evaluation_id)}
    assert evaluation.evaluation_id == evaluation_id and evaluation.finished_at is not None
    assert evaluation.info.criteria["name"] == "strict-cm"
    assert evaluation.info.criteria["baseScenarios"]["cut-in"] == {"minTTC": 0.5}
    assert sorted(runs) == sorted(names)
    assert all(r.evidence == "complete" for r in runs.values()), runs
    assert all(r.recording.startswith(f"s3://{BUCKET}/eval/evaluated/") for r in runs.values())
    assert runs[FAILING].verdict.value == "Failed" and runs[PASSING].verdict.value == "Passed"

    # The Job: one, owned by the campaign, its one pod's termination message the summary.
    batch = client.BatchV1Api(cluster.api)
    jobs: list[Any] = batch.list_namespaced_job(
        cluster.namespace, label_selector="simtest.dev/campaign"
    ).items
    assert [j.metadata.name for j in jobs] == ["evaluated-evaluate"]
    (owner,) = jobs[0].metadata.owner_references
    assert (owner.kind, owner.uid) == ("TestCampaign", campaign["metadata"]["uid"])
    (pod,) = _job_pods(cluster, "evaluated-evaluate")
    terminated = pod.status.container_statuses[0].state.terminated
    assert terminated.exit_code == 1
    said = results.EvaluationMessage.from_text(terminated.message)
    assert said.evaluation_id == evaluation_id and said.summary == message
    env = {e.name: e for e in pod.spec.containers[0].env}
    assert env["SIMTEST_RESULTS_DSN"].value_from.secret_key_ref.name == "results-db"
    assert env["SIMTEST_RESULTS_DSN"].value is None

    events = cluster.core.list_namespaced_event(cluster.namespace).items
    reasons = [e.reason for e in events if e.involved_object.name == "evaluated"]
    assert "EvaluationStarted" in reasons and "EvaluationFailed" in reasons, reasons


@pytest.mark.postgres
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_a_criteria_set_that_does_not_load_is_an_error_not_retried(
    real_operator: support.OperatorProcess,
    cluster: support.Cluster,
    postgres_dsn: str,
    s3: S3Server,
    expose: Callable[[int], str],
    tmp_path: Path,
) -> None:
    endpoint = _setup(cluster, postgres_dsn=postgres_dsn, s3=s3, expose=expose)
    cluster.create(_campaign(tmp_path, "badcrit", (PASSING,), endpoint=endpoint, key="broken.yaml"))
    status = cluster.wait_complete("badcrit", timeout=600, alive=real_operator.alive)
    assert status["phase"] == "Succeeded"
    condition = wait_for(
        "the Evaluated condition", lambda: _evaluated(cluster, "badcrit"), timeout=300
    )
    assert (condition["status"], condition["reason"]) == ("False", "Error"), condition
    assert "broken.yaml" in condition["message"], condition
    assert "minTCC" in condition["message"], condition
    assert cluster.status("badcrit")["phase"] == "Succeeded"
    assert "id" not in cluster.status("badcrit")["evaluation"]
    assert len(_job_pods(cluster, "badcrit-evaluate")) == 1  # exit 2 ends the Job: no retry
    campaign = cluster.get("testcampaigns", "badcrit")
    key = recording_results.run_key(observed.campaign_view(campaign))
    with results.open_store(postgres_dsn) as store:
        assert store.evaluations(key) == ()
