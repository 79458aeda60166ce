"""Fixtures of the real-node end-to-end tests: the scenarios as a PVC, and the operator."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.fixtures.forwarding import Forwarder

SCENARIOS = support.REPO / "scenarios"
SMOKE = SCENARIOS / "smoke-campaign.yaml"


def smoke_variant(
    tmp_path: Path,
    name: str,
    include: str,
    *,
    simulator: Mapping[str, Any] | None = None,
    **execution: Any,
) -> Path:
    """The smoke campaign renamed, cut to ``include``, with changed execution/simulator fields."""
    manifest = yaml.safe_load(SMOKE.read_text())
    manifest["metadata"]["name"] = name
    manifest["spec"]["scenarios"]["include"] = [include]
    manifest["spec"]["execution"].update(execution)
    manifest["spec"]["environment"]["simulator"].update(simulator or {})
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(manifest))
    return path


@contextlib.contextmanager
def host_path_claim(
    api: client.ApiClient, namespace: str, *, claim: str, folder: Path, access: str
) -> Iterator[str]:
    """A PVC named ``claim`` bound to a hostPath PersistentVolume on ``folder`` (a local-path
    style volume on the real node); the volume is deleted afterwards."""
    core = client.CoreV1Api(api)
    volume = f"{claim}-{namespace}"
    core.create_persistent_volume(
        body={
            "metadata": {"name": volume},
            "spec": {
                "capacity": {"storage": "1Gi"},
                "accessModes": [access],
                "persistentVolumeReclaimPolicy": "Retain",
                "storageClassName": "",
                "hostPath": {"path": str(folder), "type": "Directory"},
                "claimRef": {"namespace": namespace, "name": claim},
            },
        }
    )
    core.create_namespaced_persistent_volume_claim(
        namespace,
        body={
            "metadata": {"name": claim},
            "spec": {
                "accessModes": [access],
                "storageClassName": "",
                "volumeName": volume,
                "resources": {"requests": {"storage": "1Gi"}},
            },
        },
    )
    try:
        yield claim
    finally:
        core.delete_persistent_volume(volume)


@pytest.fixture
def scenario_claim(real_api_client: client.ApiClient, real_namespace: str) -> Iterator[str]:
    """A PVC with the repository's scenarios: a hostPath volume, bound to this namespace.

    The operator resolves ``path`` sources against the same folder and mounts the claim
    read-only into every simulator pod, as it would an NFS share on a real cluster.
    """
    with host_path_claim(
        real_api_client, real_namespace, claim="scenarios", folder=SCENARIOS, access="ReadOnlyMany"
    ) as claim:
        yield claim


@pytest.fixture
def operator_env(request: pytest.FixtureRequest) -> Mapping[str, str]:
    """Extra ``SIMTEST_OPERATOR_*`` settings; a test sets them with
    ``@pytest.mark.parametrize("operator_env", [{...}], indirect=True)``."""
    return dict(getattr(request, "param", {}))


@pytest.fixture
def real_operator(
    real_cluster: ClusterInfo,
    real_namespace: str,
    scenario_claim: str,
    operator_env: Mapping[str, str],
    tmp_path: Path,
) -> Iterator[support.OperatorProcess]:
    process = support.OperatorProcess(
        kubeconfig=real_cluster.kubeconfig,
        namespace=real_namespace,
        templates=support.REPO / "helm-templates",
        sources=SCENARIOS,
        workdir=tmp_path,
        extra_env={
            "SIMTEST_OPERATOR_SCENARIO_CLAIM": scenario_claim,
            # The product's default: a real kubelet enforces activeDeadlineSeconds and needs the
            # pod's termination grace period (10 s) to kill it; the backstop must come later.
            "SIMTEST_OPERATOR_BACKSTOP_GRACE": "30",
            **operator_env,
        },
    )
    process.start()
    try:
        yield process
    finally:
        process.stop()


@pytest.fixture
def pod_host(real_api_client: client.ApiClient, real_cluster: ClusterInfo) -> str:
    """The address pods reach the host at: the real node's InternalIP (its bridge gateway)."""
    node = client.CoreV1Api(real_api_client).read_node(real_cluster.real_nodes[0])
    (address,) = [a.address for a in node.status.addresses if a.type == "InternalIP"]
    return str(address)


@pytest.fixture
def expose(pod_host: str) -> Iterator[Callable[[int], str]]:
    """``expose(port)`` -> ``host:port`` where pods reach the loopback server at ``port``."""
    forwarders: list[Forwarder] = []

    def forward(port: int) -> str:
        forwarders.append(Forwarder(pod_host, port))
        return f"{pod_host}:{forwarders[-1].port}"

    try:
        yield forward
    finally:
        for forwarder in forwarders:
            forwarder.close()
