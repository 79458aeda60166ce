"""Faults the kubelet enforces on the real node, not a test double: each ends in one final verdict.

Covers: a memory limit too low for the simulator — the kernel OOM-kills the container, the
kubelet reports ``OOMKilled``, the operator records ``Error`` with that reason and retries it as
often as the campaign allows (every attempt killed the same way); a simulator pod deleted while
its scenario runs (real time) — ``Error``, retried, and the retry passes; every scenario ends
with exactly one result.
"""

from __future__ import annotations

import time
from pathlib import Path

import yaml
from kubernetes import client

from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.realnode.conftest import smoke_variant


def test_a_memory_limit_too_low_is_oomkilled_error_and_retried(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    memory = {"requests": {"cpu": "500m", "memory": "48Mi"}, "limits": {"memory": "48Mi"}}
    path = smoke_variant(tmp_path, "oom", "hard-braking_*.xosc", retries=1, resources=memory)
    submitted = support.submit(
        path, namespace=real_namespace, kubeconfig=real_cluster.kubeconfig, timeout=180
    )
    assert submitted.returncode == 2, submitted.stdout + submitted.stderr
    (result,) = support.Cluster(real_api_client, real_namespace).results("oom").values()
    assert result["verdict"] == "Error"
    assert "OOMKilled" in result["reason"]
    assert result["attempts"] == 2  # retried once, killed again


def test_a_pod_deleted_mid_run_is_error_then_retried(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    path = smoke_variant(
        tmp_path,
        "deleted",
        "hard-braking_*.xosc",
        simulator={"realTimeFactor": 1.0},  # seconds of wall time per simulated second
        retries=1,
        resources={"requests": {"cpu": "500m"}},
    )
    body = yaml.safe_load(path.read_text())
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(body)
    core = client.CoreV1Api(real_api_client)
    deadline = time.monotonic() + 120
    victim = None
    while victim is None:
        assert time.monotonic() < deadline, "no simulator pod ran"
        for pod in cluster.pods():
            statuses = pod.status.container_statuses or []
            if statuses and statuses[0].state.running:
                victim = pod.metadata.name
        time.sleep(0.2)
    time.sleep(2.0)  # well inside the 10 s run
    core.delete_namespaced_pod(victim, real_namespace)
    status = cluster.wait_complete("deleted", timeout=180, alive=real_operator.alive)
    (result,) = cluster.results("deleted").values()
    assert result["verdict"] == "Passed", result
    assert result["attempts"] == 2
    assert status["total"] == 1
