"""The real kube-scheduler fits pods against the fake nodes' ``simtest.dev/simulator`` capacity.

Covers: a one-slot pod lands on a fake node and kwok runs it; a pod asking for more slots than
any node has stays Pending with reason Unschedulable; with 3 nodes x 3 slots, 12 one-slot pods
give exactly 9 Running (3 per node) and 3 Pending.
"""

from __future__ import annotations

from typing import Any

import pytest
from kubernetes import client
from tests.devcluster.podspecs import eventually, simulator_pod

from simtest_operator.devcluster.nodes import NAME_PREFIX, SIMULATOR_RESOURCE
from simtest_operator.devcluster.state import ClusterInfo

pytestmark = pytest.mark.cluster


def _unschedulable(pod: client.V1Pod) -> bool:
    return any(
        c.type == "PodScheduled" and c.status == "False" and c.reason == "Unschedulable"
        for c in (pod.status.conditions or [])
    )


def _foreign_simulator_pods(core: client.CoreV1Api, namespace: str) -> list[str]:
    """Simulator pods of other tests still holding slots (namespace deletion is asynchronous)."""
    return [
        f"{p.metadata.namespace}/{p.metadata.name}"
        for p in core.list_pod_for_all_namespaces().items
        if p.metadata.namespace != namespace
        and p.spec.node_name
        and any(
            SIMULATOR_RESOURCE in ((c.resources.limits or {}) if c.resources else {})
            for c in p.spec.containers
        )
    ]


def test_pod_fits_a_fake_node_and_oversized_pod_is_unschedulable(
    dev_cluster: ClusterInfo, k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    core = client.CoreV1Api(k8s_api_client)
    body: Any = simulator_pod("fits", slots=1)
    core.create_namespaced_pod(k8s_namespace, body)
    body = simulator_pod("too-big", slots=4)
    core.create_namespaced_pod(k8s_namespace, body)

    fits = eventually(
        lambda: (
            (p := core.read_namespaced_pod("fits", k8s_namespace)).status.phase == "Running" and p
        ),
        timeout=30,
        what="pod 'fits' Running",
    )
    assert fits.spec.node_name in dev_cluster.nodes
    assert fits.spec.node_name.startswith(NAME_PREFIX)

    big = eventually(
        lambda: _unschedulable(p := core.read_namespaced_pod("too-big", k8s_namespace)) and p,
        timeout=30,
        what="pod 'too-big' Unschedulable",
    )
    assert big.status.phase == "Pending"
    assert big.spec.node_name is None
    message = next(c.message for c in big.status.conditions if c.type == "PodScheduled")
    assert f"Insufficient {SIMULATOR_RESOURCE}" in message


def test_twelve_pods_on_three_by_three_slots_leave_three_pending(
    dev_cluster: ClusterInfo, k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    assert len(dev_cluster.nodes) == 3
    core = client.CoreV1Api(k8s_api_client)
    eventually(
        lambda: not _foreign_simulator_pods(core, k8s_namespace),
        timeout=60,
        what="slots freed by earlier tests",
    )
    for i in range(12):
        body: Any = simulator_pod(f"sim-{i:02d}")
        core.create_namespaced_pod(k8s_namespace, body)

    def settled() -> tuple[list[client.V1Pod], list[client.V1Pod]] | None:
        pods = core.list_namespaced_pod(k8s_namespace).items
        running = [p for p in pods if p.status.phase == "Running"]
        pending = [p for p in pods if p.status.phase == "Pending" and _unschedulable(p)]
        return (running, pending) if len(running) + len(pending) == 12 else None

    running, pending = eventually(settled, timeout=60, what="12 pods Running or Unschedulable")
    assert len(running) == 9
    assert len(pending) == 3
    per_node = sorted(
        sum(1 for p in running if p.spec.node_name == node) for node in dev_cluster.nodes
    )
    assert per_node == [3, 3, 3]
