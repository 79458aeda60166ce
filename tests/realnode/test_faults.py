"""Faults the kubelet enforces on the real node, not a test double: each ends in one final verdict.

Covers: a memory limit too low for the simulator — the kernel OOM-kills the container, the
kubelet reports ``OOMKilled``, the operator records ``Error`` with that reason and retries it as
often as the campaign allows (every attempt killed the same way); a simulator pod deleted while
its scenario runs (real time) — ``Error``, retried, and the retry passes; the node's kubelet
stopped while a scenario runs — the node goes NotReady, the operator ends the run ``Error``
(node stopped reporting) and force-deletes the pod, the retry waits until the node is back and
passes; every scenario ends with exactly one result.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster.cluster import DevCluster
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
    # The runner's imports alone take ~39 MiB of anonymous memory; file pages count only when
    # no other cgroup has them cached, so a limit near the peak (48Mi) let a run pass at times.
    memory = {"requests": {"cpu": "500m", "memory": "32Mi"}, "limits": {"memory": "32Mi"}}
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


def _running_pod(cluster: support.Cluster, timeout: float = 120) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for pod in cluster.pods():
            statuses = pod.status.container_statuses or []
            if statuses and statuses[0].state.running:
                return str(pod.metadata.name)
        time.sleep(0.2)
    raise AssertionError("no simulator pod ran")


def _node_ready(core: client.CoreV1Api, node: str) -> bool:
    conditions = core.read_node(node).status.conditions or []
    return any(c.type == "Ready" and c.status == "True" for c in conditions)


@pytest.mark.parametrize(
    "operator_env", [{"SIMTEST_OPERATOR_NODE_NOT_READY_GRACE": "5"}], indirect=True
)
def test_a_stopped_kubelet_ends_the_run_error_and_it_is_retried(
    real_cluster: ClusterInfo,
    real_cluster_control: DevCluster,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    path = smoke_variant(
        tmp_path,
        "kubelet",
        "hard-braking_*.xosc",
        # 20 s of wall time; once the kubelet is gone nobody reports the end, whenever it comes.
        simulator={"realTimeFactor": 0.5},
        retries=1,
        timeoutSeconds=150,
        resources={"requests": {"cpu": "500m"}},
    )
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(yaml.safe_load(path.read_text()))
    core = client.CoreV1Api(real_api_client)
    victim = _running_pod(cluster)
    (node,) = real_cluster.real_nodes
    kubelet = f"kubelet-{node}"
    assert real_cluster_control.stop_component(kubelet)
    try:
        # The node controller marks the node NotReady (node monitor grace period), the
        # operator gives the run up 5 s later and force-deletes the pod.
        deadline = time.monotonic() + 150
        while any(p.metadata.name == victim for p in cluster.pods()):
            assert time.monotonic() < deadline, "the lost pod was never given up"
            assert real_operator.alive()
            time.sleep(0.5)
    finally:
        real_cluster_control.start_component(kubelet)
    deadline = time.monotonic() + 90
    while not _node_ready(core, node):
        assert time.monotonic() < deadline, "the node did not come back"
        time.sleep(0.5)
    # The retry runs on the node once it is back.
    status = cluster.wait_complete("kubelet", timeout=300, alive=real_operator.alive)
    (result,) = cluster.results("kubelet").values()
    assert result["verdict"] == "Passed", result
    assert result["attempts"] == 2
    assert status["total"] == 1
