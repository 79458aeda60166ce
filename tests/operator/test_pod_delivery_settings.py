"""What a simulator pod is told about results and artifacts (planner → render → pod).

Covers: with ``spec.results.databaseSecretRef`` every pod gets the DSN from the Secret and the
campaign's results run key — the same key the operator records the run under; without it, no
key; with ``spec.artifacts.s3`` the run spec's artifacts URI is ``s3://bucket/prefix/campaign/env``
and the endpoint and keys come from the named Secret (never inlined).
"""

from __future__ import annotations

import json
from typing import Any

from simtest_operator.operator import observed, recording_results
from simtest_operator.operator.actions import Kind
from tests.operator.fakecluster import FakeCluster, campaign_body, frozen_list


def _started(spec: dict[str, Any]) -> tuple[FakeCluster, list[dict[str, Any]]]:
    body = campaign_body(batchSize=2)
    body["spec"].update(spec)
    cluster = FakeCluster()
    cluster.start_campaign(body, frozen_list(2), batch_size=2)
    cluster.step()
    pods = cluster.of(Kind.POD)
    assert pods
    return cluster, pods


def _env(pod: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {item["name"]: item for item in pod["spec"]["containers"][0]["env"]}


def test_results_database_pods_get_the_campaigns_run_key() -> None:
    cluster, pods = _started({"results": {"databaseSecretRef": {"name": "db", "key": "dsn"}}})
    campaign = observed.campaign_view(cluster.get(Kind.CAMPAIGN, "camp") or {})
    expected = recording_results.run_key(campaign)
    assert expected.startswith("camp-")
    for pod in pods:
        env = _env(pod)
        dsn = env["SIMTEST_RESULTS_DSN"]["valueFrom"]["secretKeyRef"]
        assert dsn == {"name": "db", "key": "dsn"}
        assert env["SIMTEST_RESULTS_RUN_KEY"]["value"] == expected


def test_without_a_database_there_is_no_run_key() -> None:
    _, pods = _started({})
    assert all("SIMTEST_RESULTS_RUN_KEY" not in _env(pod) for pod in pods)


def test_s3_artifacts_reach_the_runner_from_the_secret() -> None:
    s3 = {
        "endpoint": "https://s3.example.org",
        "bucket": "runs",
        "prefix": "nightly",
        "secretRef": "s3-keys",
    }
    _, pods = _started({"artifacts": {"s3": s3}})
    for pod in pods:
        env = _env(pod)
        spec = json.loads(env["SIMTEST_RUN_SPEC"]["value"])
        assert spec["artifactsUri"] == f"s3://runs/nightly/camp/{pod['metadata']['name']}"
        assert env["AWS_ENDPOINT_URL_S3"]["value"] == "https://s3.example.org"
        for key in ("AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY"):
            assert env[key]["valueFrom"]["secretKeyRef"] == {"name": "s3-keys", "key": key}
            assert "value" not in env[key]
