"""The evaluation step through the real control plane (kwok nodes play kubelet).

Covers what needs an API server: the rendered Job (pod failure policy, restricted security
settings, secretKeyRef variables, ConfigMap volume) is accepted and run by the real Job
controller, after the campaign completed and not before; exactly one Job, owned by the campaign;
the Job's end becomes the ``Evaluated`` condition (kwok's pods exit 0 without a termination
message: ``Passed``, no summary) and the server-side table's ``Evaluated`` column. What
``simtest evaluate`` says inside the Job is the real node's part
(``tests/realnode/test_evaluation_step.py``).
"""

from __future__ import annotations

import base64
import time
from typing import Any

from kubernetes import client

from tests.e2e import support


def _evaluated(cluster: support.Cluster, name: str) -> dict[str, Any] | None:
    for condition in cluster.status(name).get("conditions", []):
        if condition["type"] == "Evaluated" and condition["reason"] != "Running":
            return dict(condition)
    return None


def test_the_evaluation_job_runs_once_after_the_verdicts(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: support.Path
) -> None:
    support.scenario_files(sources / "scenarios", [f"pass-{i:03d}.xosc" for i in range(3)])
    cluster.core.create_namespaced_secret(
        cluster.namespace,
        {
            "metadata": {"name": "results-db"},
            "data": {"dsn": base64.b64encode(b"postgresql://nobody@127.0.0.1:1/none").decode()},
        },
    )
    cluster.core.create_namespaced_config_map(
        cluster.namespace, {"metadata": {"name": "crit"}, "data": {"c.yaml": "name: c\n"}}
    )
    body = support.campaign("evald", execution={"batchSize": 3})
    body["spec"]["results"] = {"databaseSecretRef": {"name": "results-db", "key": "dsn"}}
    body["spec"]["evaluation"] = {
        "offline": {"criteria": {"configMapRef": {"name": "crit", "key": "c.yaml"}}}
    }
    batch = client.BatchV1Api(cluster.api)

    def jobs() -> list[Any]:
        found: list[Any] = batch.list_namespaced_job(cluster.namespace).items
        return found

    early: list[str] = []

    def watch_for_early_jobs() -> None:
        if jobs() and cluster.status("evald").get("phase") not in ("Succeeded", "Failed", "Error"):
            early.append(cluster.status("evald").get("phase", ""))

    with support.running(operator):
        cluster.create(body)
        status = cluster.wait_complete(
            "evald", timeout=120, alive=operator.alive, during=watch_for_early_jobs
        )
        deadline = time.monotonic() + 90
        condition = _evaluated(cluster, "evald")
        while condition is None and time.monotonic() < deadline:
            assert operator.alive(), "the operator process died"
            time.sleep(0.5)
            condition = _evaluated(cluster, "evald")
        columns, rows = cluster.table("testcampaigns")
        final = cluster.status("evald")
        found = jobs()
    assert status["phase"] == "Succeeded" and not early, early
    assert condition is not None, final
    assert (condition["status"], condition["reason"]) == ("True", "Passed"), condition
    assert "no summary" in condition["message"]
    assert final["phase"] == "Succeeded" and final["evaluation"] == {"job": "evald-evaluate"}
    assert [j.metadata.name for j in found] == ["evald-evaluate"]
    (owner,) = found[0].metadata.owner_references
    assert (owner.kind, owner.name) == ("TestCampaign", "evald")
    assert found[0].spec.pod_failure_policy.rules[0].action == "FailJob"
    assert rows[0][columns.index("Evaluated")] == "Passed"
