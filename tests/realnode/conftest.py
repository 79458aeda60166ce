"""Fixtures of the real-node end-to-end tests: the scenarios as a PVC, the operator, and the
campaigns and Secrets the results tests share."""

from __future__ import annotations

import base64
import contextlib
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.fixtures.forwarding import Forwarder
from tests.results.s3server import BUCKET

SCENARIOS = support.REPO / "scenarios"
SMOKE = SCENARIOS / "smoke-campaign.yaml"
T = TypeVar("T")
PREFIX = "nightly/team-a"
"""Where the results tests' campaigns put their artifacts in the S3 bucket."""


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


def create_secret(cluster: support.Cluster, name: str, data: dict[str, str]) -> None:
    cluster.core.create_namespaced_secret(
        cluster.namespace,
        {
            "apiVersion": "v1",
            "kind": "Secret",
            "metadata": {"name": name},
            "data": {k: base64.b64encode(v.encode()).decode() for k, v in data.items()},
        },
    )


def results_campaign(
    tmp_path: Path,
    name: str,
    names: Sequence[str],
    *,
    database: str | None,
    s3: str | None = None,
    pvc: dict[str, str] | None = None,
    prefix: str = PREFIX,
) -> dict[str, Any]:
    """The smoke campaign cut to ``names`` (two at a time, no retries) storing its results in
    the database of Secret ``database`` and its artifacts in S3 at ``s3`` or on ``pvc``."""
    path = smoke_variant(
        tmp_path,
        name,
        "*.xosc",
        maxParallel=2,
        batchSize=2,
        retries=0,
        timeoutSeconds=60,
        resources={"requests": {"cpu": "500m"}},
    )
    body: dict[str, Any] = yaml.safe_load(path.read_text())
    spec = body["spec"]
    spec["scenarios"]["include"] = list(names)
    spec["evaluation"] = {"criteria": {"minTtc": 1.0}}
    if database is not None:
        spec["results"] = {"databaseSecretRef": {"name": database, "key": "dsn"}}
    if s3 is not None:
        spec["artifacts"] = {
            "s3": {"endpoint": s3, "bucket": BUCKET, "prefix": prefix, "secretRef": "artifacts-s3"}
        }
    if pvc is not None:
        spec["artifacts"] = {"pvc": pvc}
    return body


def wait_for(what: str, probe: Callable[[], T | None], *, timeout: float) -> T:
    """Poll ``probe`` until it returns something (no fixed sleeps: a loaded machine is slow)."""
    deadline = time.monotonic() + timeout
    while True:
        value = probe()
        if value is not None:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"{what} not seen after {timeout:.0f}s")
        time.sleep(0.5)
