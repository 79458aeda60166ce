"""Admission through Kueue with real pods: the real-node dev cluster with Kueue added
(``simtest dev-cluster up --kueue`` on a running cluster), the operator as a process.

Covers: a campaign whose LocalQueue has no free ``simtest.dev/simulator`` quota (another
workload holds all of it) creates no pod and waits with ``Admitted=False`` and Kueue's reason;
once the quota frees it is admitted for fewer simulators than it asked for (partial admission:
the quota is 1, the node has 2 slots, the campaign asks for 2), runs to Complete in real
containers on the real node with never more simulator pods at once than the admitted count, and
releases its Workload.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.e2e.test_kueue import Queues, _condition, _wait
from tests.realnode.conftest import smoke_variant

HIGHWAY = "*_highway_*.xosc"


def _running_simulators(cluster: support.Cluster) -> int:
    """Simulator pods that still run a container. On a real node the kubelet turns a pod's
    phase terminal up to a relist (~1 s) after its container exited; the operator counts the
    slot free at the container's exit (``PodView.terminated``), so a pod whose containers have
    all terminated holds no slot even while its phase still says Running."""
    live = 0
    for pod in cluster.pods():
        if pod.status.phase in ("Succeeded", "Failed") or pod.metadata.deletion_timestamp:
            continue
        states = [c.state for c in pod.status.container_statuses or []]
        if states and all(state.terminated is not None for state in states):
            continue
        live += 1
    return live


"""Three smoke scenarios: two pass, one the driver model cannot avoid (Failed)."""


@pytest.fixture
def queues(
    real_cluster_control: DevCluster, real_api_client: client.ApiClient, real_namespace: str
) -> Iterator[Queues]:
    info = real_cluster_control.up(with_kueue=True)  # Kueue added to the running real cluster
    assert "workloads.kueue.x-k8s.io" in info.crds
    admin = Queues(real_api_client, real_namespace)
    try:
        yield admin
    finally:
        admin.close()


def test_a_campaign_over_quota_waits_then_runs_on_the_real_node_within_its_admission(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    queues: Queues,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    cq = f"sims-{real_namespace}"
    queues.cluster_queue(cq, simulators=1)
    queues.local_queue("team-a", cq)
    queues.create_workload("other-team", "team-a", simulators=1)  # all of the quota
    _wait(
        lambda: any(
            _condition(w.get("status") or {}, "Admitted").get("status") == "True"
            for w in queues.workloads()
        ),
        timeout=60,
        what="the other team's workload admitted",
    )
    path = smoke_variant(
        tmp_path,
        "queued",
        HIGHWAY,
        queueName="team-a",
        maxParallel=2,  # the node has 2 slots; the queue admits 1
        batchSize=3,
        retries=0,
        timeoutSeconds=60,
        resources={"requests": {"cpu": "500m"}},
    )
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(yaml.safe_load(path.read_text()))
    _wait(
        lambda: _condition(cluster.status("queued"), "Admitted").get("reason") == "Pending",
        timeout=60,
        what="campaign condition Admitted=False with Kueue's reason",
    )
    status = cluster.status("queued")
    admitted = _condition(status, "Admitted")
    assert admitted["status"] == "False"
    assert "insufficient quota for simtest.dev/simulator" in admitted["message"]
    assert status["phase"] == "Pending"
    time.sleep(3)  # it stays that way while the quota is taken
    assert cluster.pods() == [] and cluster.items("simenvironments") == []

    queues.delete_workload("other-team")
    peak = 0
    admitted_counts: list[int] = []
    nodes: set[str] = set()

    def sample() -> None:
        nonlocal peak
        peak = max(peak, _running_simulators(cluster))
        nodes.update(p.spec.node_name for p in cluster.pods() if p.spec.node_name)
        for workload in queues.workloads():
            if workload["metadata"]["name"] != "queued-simulators":
                continue
            admission = (workload.get("status") or {}).get("admission", {})
            admitted_counts.extend(int(a["count"]) for a in admission.get("podSetAssignments", []))

    final = cluster.wait_complete("queued", timeout=300, alive=real_operator.alive, during=sample)
    _wait(
        lambda: not any(w["metadata"]["name"] == "queued-simulators" for w in queues.workloads()),
        timeout=60,
        what="the campaign's Workload deleted (quota released)",
    )
    assert final["phase"] in ("Succeeded", "Failed"), final
    results = cluster.results("queued")
    assert {k: v["verdict"] for k, v in results.items()} == {
        "cut-in_highway_v25_gap30_dv5.xosc": "Passed",
        "cut-in_highway_v30_gap8_dv12.xosc": "Failed",
        "following_highway_v25_thw2_drop5_d2.xosc": "Passed",
    }
    assert set(admitted_counts) == {1}, admitted_counts
    assert peak == 1, f"{peak} simulator pods at once; Kueue admitted 1"
    released = _condition(cluster.status("queued"), "Admitted")
    assert (released["status"], released["reason"]) == ("False", "Released")
    assert nodes == set(real_cluster.real_nodes), nodes
