"""What ``up`` puts into a fresh cluster through the API: CRDs and fake nodes, and its checks.

Talks to the apiserver with the official ``kubernetes`` client. Each step is idempotent (create,
or replace what exists) so ``up`` on a restarted cluster converges instead of failing.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import yaml
from kubernetes import client, config
from kubernetes.client.exceptions import ApiException

from simtest_operator.devcluster.nodes import NodeShape, node_manifest
from simtest_operator.errors import ClusterError


def api_client(kubeconfig: Path) -> client.ApiClient:
    """A client for the cluster of ``kubeconfig`` (its current context)."""
    api: client.ApiClient = config.new_client_from_config(  # type: ignore[no-untyped-call]
        config_file=str(kubeconfig)
    )
    return api


def _untyped(body: dict[str, Any]) -> Any:
    """The client accepts plain dicts as bodies, although its annotations name the models."""
    return body


def read_crds(crds_dir: Path) -> list[dict[str, Any]]:
    """Every CustomResourceDefinition document in ``crds_dir/*.yaml`` (sorted by file name)."""
    documents: list[dict[str, Any]] = []
    for path in sorted(crds_dir.glob("*.yaml")):
        for doc in yaml.safe_load_all(path.read_text()):
            if isinstance(doc, dict) and doc.get("kind") == "CustomResourceDefinition":
                documents.append(doc)
    return documents


def apply_crds(api: client.ApiClient, documents: Iterable[dict[str, Any]]) -> tuple[str, ...]:
    """Create or replace the CRDs; return their names."""
    ext = client.ApiextensionsV1Api(api)
    names = []
    for doc in documents:
        name = doc["metadata"]["name"]
        try:
            ext.create_custom_resource_definition(body=_untyped(doc))
        except ApiException as exc:
            if exc.status != 409:
                raise ClusterError(f"CRD {name} rejected: {exc.body}") from exc
            current = ext.read_custom_resource_definition(name).metadata
            version = current.resource_version if current else None
            body = {**doc, "metadata": {**doc["metadata"], "resourceVersion": version}}
            ext.replace_custom_resource_definition(name, body=_untyped(body))
        names.append(name)
    return tuple(names)


def crds_established(api: client.ApiClient, names: Iterable[str]) -> bool:
    """Whether every named CRD reports condition Established=True."""
    ext = client.ApiextensionsV1Api(api)
    for name in names:
        status = ext.read_custom_resource_definition(name).status
        conditions = (status.conditions if status else None) or []
        if not any(c.type == "Established" and c.status == "True" for c in conditions):
            return False
    return True


def create_nodes(api: client.ApiClient, names: Iterable[str], shape: NodeShape) -> None:
    """Create the fake nodes; an existing node of that name is replaced with the new shape."""
    core = client.CoreV1Api(api)
    for name in names:
        body = node_manifest(name, shape)
        try:
            core.create_node(body=_untyped(body))
        except ApiException as exc:
            if exc.status != 409:
                raise ClusterError(f"cannot create node {name}: {exc.body}") from exc
            core.delete_node(name)
            core.create_node(body=_untyped(body))


def nodes_ready(api: client.ApiClient, names: Iterable[str]) -> bool:
    """Whether all named nodes exist and are Ready (kwok's node-initialize stage ran)."""
    core = client.CoreV1Api(api)
    ready = {
        node.metadata.name
        for node in core.list_node().items
        if node.metadata
        and node.status
        and any(c.type == "Ready" and c.status == "True" for c in node.status.conditions or [])
    }
    return set(names) <= ready


def default_service_account_exists(api: client.ApiClient, namespace: str) -> bool:
    """Whether the controller-manager created ``default`` in ``namespace`` (pods need it)."""
    try:
        client.CoreV1Api(api).read_namespaced_service_account("default", namespace)
    except ApiException as exc:
        if exc.status == 404:
            return False
        raise
    return True
