"""The dev cluster's real node: a kubelet that runs the operator's pods in real containers.

Covers: the node registers with its own client certificate (``system:node:<name>``) and its
bridge address, and advertises simulator slots through the chart's device-plugin DaemonSet; the
smoke campaign, submitted with ``simtest submit --wait`` as a CI step would, runs on it in real
containers (image ``ghcr.io/simtest-dev/simtest-runner``, user 65532, read-only root file
system, in a namespace enforcing Pod Security ``restricted``, scenarios from a PVC) and ends with
the verdicts ``simtest run`` gives on this machine; a simulator image that does not exist ends
``Error`` with the kubelet's reason instead of hanging.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

from kubernetes import client, watch

from simtest_operator.devcluster import images
from simtest_operator.devcluster.nodeconfig import REAL_NODE_LABEL
from simtest_operator.devcluster.nodes import SIMULATOR_RESOURCE
from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.fixtures.realnode import REAL_SLOTS
from tests.realnode.conftest import SMOKE, smoke_variant


def test_real_node_registers_with_its_own_identity_and_advertises_slots(
    real_cluster: ClusterInfo, real_api_client: client.ApiClient
) -> None:
    (name,) = real_cluster.real_nodes
    node = client.CoreV1Api(real_api_client).read_node(name)
    assert node.metadata.labels[REAL_NODE_LABEL] == "true"
    assert node.status.node_info.kubelet_version == "v1.36.4"
    assert node.status.node_info.container_runtime_version.startswith("containerd://1.6")
    addresses = {a.type: a.address for a in node.status.addresses}
    assert addresses["InternalIP"].startswith("10.244.")
    assert node.status.allocatable[SIMULATOR_RESOURCE] == str(REAL_SLOTS)
    plugin_pods = client.CoreV1Api(real_api_client).list_namespaced_pod(
        "kube-system", label_selector="app.kubernetes.io/name=simtest-device-plugin"
    )
    assert [p.spec.node_name for p in plugin_pods.items] == [name]
    assert all(p.status.phase == "Running" for p in plugin_pods.items)


def _local_verdicts(tmp_path: Path) -> dict[str, str]:
    out = tmp_path / "local"
    subprocess.run(
        [str(Path(sys.executable).parent / "simtest"), "run", str(SMOKE), "-o", str(out)],
        capture_output=True,
        check=False,
    )
    results = {}
    for result in out.glob("**/result.json"):
        data = json.loads(result.read_text())
        results[data["scenarioId"]] = data["verdict"]
    return results


class PodWatch:
    """The last state of every simulator pod in a namespace, seen through a watch."""

    def __init__(self, api: client.ApiClient, namespace: str) -> None:
        self.pods: dict[str, Any] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(api, namespace), daemon=True)

    def _run(self, api: client.ApiClient, namespace: str) -> None:
        core = client.CoreV1Api(api)
        while not self._stop.is_set():
            stream = watch.Watch().stream(
                core.list_namespaced_pod,
                namespace,
                label_selector="simtest.dev/campaign",
                timeout_seconds=2,
            )
            for event in stream:
                pod = event["object"]
                if event["type"] != "DELETED" or pod.metadata.name not in self.pods:
                    self.pods[pod.metadata.name] = pod

    def __enter__(self) -> PodWatch:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=10)


def test_smoke_campaign_runs_in_real_containers_with_the_local_verdicts(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    with PodWatch(real_api_client, real_namespace) as seen:
        submitted = support.submit(
            SMOKE, namespace=real_namespace, kubeconfig=real_cluster.kubeconfig, timeout=300
        )
    assert submitted.returncode == 1, submitted.stdout + submitted.stderr  # one scenario fails
    cluster = support.Cluster(real_api_client, real_namespace)
    results = cluster.results("smoke")
    verdicts = {scenario: r["verdict"] for scenario, r in results.items()}
    assert verdicts == _local_verdicts(tmp_path)
    assert verdicts["cut-in_highway_v30_gap8_dv12.xosc"] == "Failed"
    assert "collided" in results["cut-in_highway_v30_gap8_dv12.xosc"]["reason"]
    pods = list(seen.pods.values())
    assert len(pods) == 6
    for pod in pods:
        (status,) = pod.status.container_statuses
        assert pod.spec.node_name == real_cluster.real_nodes[0]
        assert status.image == images.RUNNER_IMAGE
        assert status.container_id.startswith("containerd://")
        assert status.state.terminated is not None, status.state
        assert pod.spec.security_context.run_as_user == 65532
        assert pod.spec.containers[0].security_context.read_only_root_filesystem is True


def test_an_image_that_does_not_exist_ends_error_with_the_kubelet_reason(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    path = smoke_variant(
        tmp_path,
        "no-image",
        "hard-braking_*.xosc",
        simulator={"image": "ghcr.io/simtest-dev/not-built:0.0.0"},
        retries=0,
    )
    submitted = support.submit(
        path, namespace=real_namespace, kubeconfig=real_cluster.kubeconfig, timeout=180
    )
    assert submitted.returncode == 2, submitted.stdout + submitted.stderr
    (result,) = support.Cluster(real_api_client, real_namespace).results("no-image").values()
    assert result["verdict"] == "Error"
    assert "ErrImagePull" in result["reason"] or "ImagePullBackOff" in result["reason"]
