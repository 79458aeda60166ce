"""The kustomize base and overlay in deploy/kustomize, built by the real `kubectl kustomize`.

Covers: the base builds and holds the Namespace (enforcing restricted Pod Security) plus exactly
the operator chart's default manifests (the golden file test_chart_golden keeps equal to
`helm template`); the example overlay moves everything to its namespace, including the
ClusterRoleBinding's subject, and pins the image; the overlay passes a server-side dry-run
against the dev control plane.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from tests.charts.helmtools import REPO, Tool, documents, find

BASE = REPO / "deploy" / "kustomize" / "base"
OVERLAY = REPO / "deploy" / "kustomize" / "overlays" / "example"


def _build(kubectl: Tool, folder: Path) -> list[dict[str, Any]]:
    return documents(kubectl.run("kustomize", folder).stdout)


def test_base_is_the_namespace_plus_the_chart(kubectl: Tool) -> None:
    docs = _build(kubectl, BASE)
    namespace = find(docs, "Namespace", "simtest-system")
    assert namespace["metadata"]["labels"]["pod-security.kubernetes.io/enforce"] == "restricted"
    chart = documents((BASE / "simtest-operator.yaml").read_text())
    key = lambda d: (d["kind"], d["metadata"]["name"])  # noqa: E731
    assert sorted(map(key, docs)) == sorted([*map(key, chart), ("Namespace", "simtest-system")])
    deployment = find(docs, "Deployment", "simtest-operator")
    assert deployment["metadata"]["namespace"] == "simtest-system"


def test_overlay_moves_everything(kubectl: Tool) -> None:
    docs = _build(kubectl, OVERLAY)
    find(docs, "Namespace", "simtest-ci")
    for doc in docs:
        if doc["kind"] not in (
            "Namespace",
            "CustomResourceDefinition",
            "ClusterRole",
            "ClusterRoleBinding",
        ):
            assert doc["metadata"]["namespace"] == "simtest-ci", doc["kind"]
    binding = find(docs, "ClusterRoleBinding", "simtest-operator")
    assert binding["subjects"][0]["namespace"] == "simtest-ci"
    container = find(docs, "Deployment")["spec"]["template"]["spec"]["containers"][0]
    assert container["image"] == "ghcr.io/simtest-dev/simtest-operator:0.1.0"


def test_overlay_passes_a_server_side_dry_run(kubectl: Tool, kubeconfig_path: Path) -> None:
    text = kubectl.run("kustomize", OVERLAY).stdout
    # A dry run creates nothing, so the namespace the objects go to must exist for real.
    namespace = yaml.safe_dump(find(documents(text), "Namespace", "simtest-ci"))
    kubectl.run(
        "--kubeconfig", kubeconfig_path, "apply", "--server-side", "-f", "-", stdin=namespace
    )
    try:
        result = kubectl.run(
            "--kubeconfig", kubeconfig_path, "apply", "--server-side", "--dry-run=server",
            "--force-conflicts", "--field-manager=simtest-tests", "-f", "-", stdin=text,
        )  # fmt: skip
    finally:
        kubectl.run(
            "--kubeconfig", kubeconfig_path, "delete", "namespace", "simtest-ci", "--wait=false"
        )
    assert result.stdout.count("(server dry run)") == len(documents(text))
