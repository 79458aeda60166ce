"""The control plane is the real thing: stamped versions, RBAC, garbage collection, CRDs.

Covers: ``/version`` reports the pinned Kubernetes version (ldflags stamping); a service account
without bindings is forbidden by RBAC while the admin is allowed; deleting an owner makes the
garbage collector delete its ConfigMap and Pod children; every CRD in ``crds/`` is Established
and served, and the apiserver rejects a custom object whose spec has the wrong type with a
field-level message.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from kubernetes import client
from kubernetes.client.exceptions import ApiException
from tests.devcluster.podspecs import eventually, simulator_pod

from simtest_operator.devcluster import provisioning
from simtest_operator.devcluster.state import ClusterInfo

pytestmark = pytest.mark.cluster

REPO_ROOT = Path(__file__).resolve().parents[2]


def _pinned(key: str) -> str:
    for line in (REPO_ROOT / "deploy/devcluster/versions.env").read_text().splitlines():
        if line.startswith(f"{key}="):
            return line.split("=", 1)[1].strip()
    raise AssertionError(f"{key} not pinned")


def test_version_is_stamped(k8s_api_client: client.ApiClient) -> None:
    info = client.VersionApi(k8s_api_client).get_code()
    assert info.git_version == f"v{_pinned('KUBERNETES_VERSION')}"
    assert info.git_tree_state == "clean"


def test_rbac_forbids_an_unbound_service_account(
    dev_cluster: ClusterInfo, k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    core = client.CoreV1Api(k8s_api_client)
    body: Any = {"metadata": {"name": "nobody"}}
    core.create_namespaced_service_account(k8s_namespace, body)
    request: Any = {"spec": {"expirationSeconds": 600}}
    token = core.create_namespaced_service_account_token(
        "nobody", k8s_namespace, request
    ).status.token
    config = client.Configuration()
    config.host = dev_cluster.server
    config.ssl_ca_cert = str(dev_cluster.ca_file)
    config.api_key = {"authorization": f"Bearer {token}"}
    with client.ApiClient(config) as as_nobody, pytest.raises(ApiException) as denied:
        client.CoreV1Api(as_nobody).list_namespaced_pod(k8s_namespace)
    assert denied.value.status == 403
    assert f"system:serviceaccount:{k8s_namespace}:nobody" in denied.value.body
    core.list_namespaced_pod(k8s_namespace)  # the admin may


def test_deleting_an_owner_garbage_collects_its_children(
    k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    core = client.CoreV1Api(k8s_api_client)
    owner_body: Any = {"metadata": {"name": "owner"}, "data": {"k": "v"}}
    owner = core.create_namespaced_config_map(k8s_namespace, owner_body)
    ref = {"apiVersion": "v1", "kind": "ConfigMap", "name": "owner", "uid": owner.metadata.uid}
    child: Any = {"metadata": {"name": "child", "ownerReferences": [ref]}}
    core.create_namespaced_config_map(k8s_namespace, child)
    pod: Any = simulator_pod("child-pod")
    pod["metadata"]["ownerReferences"] = [ref]
    core.create_namespaced_pod(k8s_namespace, pod)

    core.delete_namespaced_config_map("owner", k8s_namespace, propagation_policy="Background")

    def children_gone() -> bool:
        names = {c.metadata.name for c in core.list_namespaced_config_map(k8s_namespace).items}
        pods = core.list_namespaced_pod(k8s_namespace).items
        return "child" not in names and not pods

    eventually(children_gone, timeout=30, what="ConfigMap and Pod children deleted")


def test_crds_are_established_served_and_validate(
    dev_cluster: ClusterInfo, k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    documents = provisioning.read_crds(REPO_ROOT / "crds")
    assert documents, "crds/ holds no CRDs"
    names = {d["metadata"]["name"] for d in documents}
    assert names == set(dev_cluster.crds)
    assert provisioning.crds_established(k8s_api_client, names)

    custom = client.CustomObjectsApi(k8s_api_client)
    for doc in documents:
        spec = doc["spec"]
        version = next(v["name"] for v in spec["versions"] if v.get("served"))
        plural, kind = spec["names"]["plural"], spec["names"]["kind"]
        namespaced = spec["scope"] == "Namespaced"
        listed = (
            custom.list_namespaced_custom_object(spec["group"], version, k8s_namespace, plural)
            if namespaced
            else custom.list_cluster_custom_object(spec["group"], version, plural)
        )
        assert listed["items"] == []
        bad: Any = {
            "apiVersion": f"{spec['group']}/{version}",
            "kind": kind,
            "metadata": {"name": "bad"},
            "spec": "not-an-object",
        }
        with pytest.raises(ApiException) as rejected:
            if namespaced:
                custom.create_namespaced_custom_object(
                    spec["group"], version, k8s_namespace, plural, bad
                )
            else:
                custom.create_cluster_custom_object(spec["group"], version, plural, bad)
        assert rejected.value.status == 422, rejected.value.body
        causes = json.loads(rejected.value.body)["details"]["causes"]
        assert any(c["field"] == "spec" for c in causes), causes
