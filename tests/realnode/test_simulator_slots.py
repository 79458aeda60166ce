"""Simulator slots on the real node: the chart's device plugin against the real kubelet.

Covers: a pod that asks for a ``simtest.dev/simulator`` unit gets one of the plugin's devices
(its id in the container's environment, as ``Allocate`` answered); the kubelet restarted while
the pod runs — the plugin registers again and the node advertises its slots again, the running
pod keeps its container and its slot (a second pod asking for every slot stays Pending with
``Insufficient simtest.dev/simulator``); once the first one is gone, a pod gets every slot.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from kubernetes import client

from simtest_operator.devcluster import addons, images
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.nodes import SIMULATOR_RESOURCE
from simtest_operator.devcluster.state import ClusterInfo
from tests.fixtures.realnode import REAL_SLOTS

RESTRICTED = {
    "runAsNonRoot": True,
    "allowPrivilegeEscalation": False,
    "capabilities": {"drop": ["ALL"]},
    "seccompProfile": {"type": "RuntimeDefault"},
    "readOnlyRootFilesystem": True,
}


def _pod(name: str, slots: int, command: list[str]) -> dict[str, Any]:
    return {
        "metadata": {"name": name},
        "spec": {
            "restartPolicy": "Never",
            "terminationGracePeriodSeconds": 1,
            # As the operator's simulator pods: no API token. (A token volume of a pod created
            # right after a kubelet restart failed with `"kube-root-ca.crt" not registered` for
            # minutes here — kubelet 1.36.4's ConfigMap manager; simulator pods never mount one.)
            "automountServiceAccountToken": False,
            "securityContext": {"runAsUser": 65532, "runAsGroup": 65532},
            "containers": [
                {
                    "name": "c",
                    "image": images.RUNNER_IMAGE,
                    "imagePullPolicy": "IfNotPresent",
                    "command": command,
                    "securityContext": RESTRICTED,
                    "resources": {"limits": {SIMULATOR_RESOURCE: str(slots), "memory": "128Mi"}},
                }
            ],
        },
    }


def _wait(what: str, check: Callable[[], bool], timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.25)


def test_slots_survive_a_kubelet_restart(
    real_cluster: ClusterInfo,
    real_cluster_control: DevCluster,
    real_api_client: client.ApiClient,
    real_namespace: str,
) -> None:
    core = client.CoreV1Api(real_api_client)
    (node,) = real_cluster.real_nodes
    script = "import os, time; print(os.environ['SIMTEST_SIMULATOR_SLOTS']); time.sleep(300)"
    sleeper = ["python3", "-c", script]
    core.create_namespaced_pod(real_namespace, body=_pod("holder", 1, sleeper))

    def holder() -> Any:
        return core.read_namespaced_pod("holder", real_namespace)

    _wait("holder Running", lambda: holder().status.phase == "Running")
    before = holder().status.container_statuses[0]
    _wait(
        "the slot id in the log",
        lambda: bool(core.read_namespaced_pod_log("holder", real_namespace)),
    )
    slot = core.read_namespaced_pod_log("holder", real_namespace).strip()
    assert slot.startswith("slot-"), slot

    kubelet = f"kubelet-{node}"
    assert real_cluster_control.stop_component(kubelet)
    real_cluster_control.start_component(kubelet)
    _wait(
        "the node advertising its slots again",
        lambda: (
            addons.simulator_slots(real_api_client, node) == REAL_SLOTS
            and _ready(core.read_node(node))
        ),
        timeout=90,
    )
    after = holder().status.container_statuses[0]
    assert after.container_id == before.container_id and after.restart_count == 0
    assert after.state.running is not None

    core.create_namespaced_pod(
        real_namespace, body=_pod("wants-all", REAL_SLOTS, ["python3", "-c", "pass"])
    )
    _wait(
        "wants-all Unschedulable",
        lambda: any(
            c.type == "PodScheduled" and c.reason == "Unschedulable"
            for c in core.read_namespaced_pod("wants-all", real_namespace).status.conditions or []
        ),
    )
    message = next(
        c.message
        for c in core.read_namespaced_pod("wants-all", real_namespace).status.conditions
        if c.type == "PodScheduled"
    )
    assert f"Insufficient {SIMULATOR_RESOURCE}" in message
    # Deleted with a grace period, the pod object goes only once the kubelet has stopped it and
    # released its device; then every slot is free again. (Force deletion would let the
    # scheduler bind the next pod while the kubelet still holds the device: the kubelet then
    # rejects it at admission with UnexpectedAdmissionError, as on any cluster.)
    core.delete_namespaced_pod("wants-all", real_namespace, grace_period_seconds=0)
    core.delete_namespaced_pod("holder", real_namespace, grace_period_seconds=1)
    _wait("holder gone", lambda: not _exists(core, "holder", real_namespace), timeout=60)
    core.create_namespaced_pod(
        real_namespace, body=_pod("after", REAL_SLOTS, ["python3", "-c", "pass"])
    )
    _wait(
        "a pod with every slot to run",
        lambda: core.read_namespaced_pod("after", real_namespace).status.phase == "Succeeded",
        timeout=90,
    )


def _exists(core: client.CoreV1Api, name: str, namespace: str) -> bool:
    try:
        core.read_namespaced_pod(name, namespace)
    except client.exceptions.ApiException as exc:
        if exc.status == 404:
            return False
        raise
    return True


def _ready(node: Any) -> bool:
    return any(c.type == "Ready" and c.status == "True" for c in node.status.conditions or [])
