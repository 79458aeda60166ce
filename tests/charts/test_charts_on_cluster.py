"""Both charts against the dev control plane (marker ``cluster``, added by the fixtures).

Covers: the operator chart's manifests (CRDs included, cluster-wide and namespaced) pass a
server-side dry-run; `helm install --wait` of the operator chart into a namespace that enforces
Pod Security "restricted" gets an available Deployment (kwok plays kubelet); the installed RBAC
grants the operator's ServiceAccount exactly the checked verbs and denies the rest (`kubectl auth
can-i --as`), lets it bind the provisioner ClusterRole in a namespace but not `admin`, and
`helm uninstall` leaves the CRDs when `crds.keep`; the K8s-ROS chart installs a Deployment and a Job
into a restricted namespace.
"""

from __future__ import annotations

import secrets
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.charts.helmtools import OPERATOR_CHART, ROS_CHART, Tool, documents, template
from tests.charts.test_chart_golden import ROS_CASES


def _kubectl(
    kubectl: Tool, kubeconfig: Path, *args: str, stdin: str | None = None, check: bool = True
) -> Any:
    return kubectl.run("--kubeconfig", str(kubeconfig), *args, stdin=stdin, check=check)


def _dry_run(kubectl: Tool, kubeconfig: Path, text: str) -> str:
    result = _kubectl(
        kubectl, kubeconfig, "apply", "--server-side", "--dry-run=server", "--force-conflicts",
        "--field-manager=simtest-tests", "-f", "-", stdin=text,
    )  # fmt: skip
    return str(result.stdout)


def _restricted(kubectl: Tool, kubeconfig: Path, namespace: str) -> None:
    _kubectl(
        kubectl, kubeconfig, "label", "namespace", namespace,
        "pod-security.kubernetes.io/enforce=restricted",
        "pod-security.kubernetes.io/enforce-version=latest",
    )  # fmt: skip


@pytest.mark.parametrize("watch", ["cluster", "namespaced"])
def test_operator_chart_passes_a_server_side_dry_run(
    watch: str, helm: Tool, kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str
) -> None:
    values = {"watch": {"namespaces": [k8s_namespace]}} if watch == "namespaced" else {}
    text = template(helm, OPERATOR_CHART, namespace=k8s_namespace, values=values).stdout
    out = _dry_run(kubectl, kubeconfig_path, text)
    assert out.count("serverside-applied (server dry run)") == len(documents(text))


def _helm(helm: Tool, kubeconfig: Path, *args: str, check: bool = True) -> Any:
    return helm.run(*args, "--kubeconfig", str(kubeconfig), check=check)


ALLOWED = [
    ("list", "testcampaigns.simtest.dev", None),
    ("watch", "scenariobatches.simtest.dev", None),
    ("create", "simenvironments.simtest.dev", None),
    ("delete", "simenvironments.simtest.dev", None),
    ("patch", "testcampaigns.simtest.dev", "status"),
    ("create", "pods", None),
    ("delete", "pods", None),
    ("create", "configmaps", None),
    ("create", "serviceaccounts", None),
    ("create", "events", None),
    ("get", "secrets", None),
    ("create", "jobs.batch", None),
    ("create", "rolebindings.rbac.authorization.k8s.io", None),
    ("list", "nodes", None),
]
DENIED = [
    ("update", "testcampaigns.simtest.dev", None),
    ("delete", "testcampaigns.simtest.dev", None),
    ("create", "testcampaigns.simtest.dev", None),
    ("list", "secrets", None),
    ("create", "pods", "exec"),
    ("get", "pods", "log"),
    ("patch", "pods", None),
    ("delete", "configmaps", None),
    ("create", "deployments.apps", None),
    ("create", "roles.rbac.authorization.k8s.io", None),
    ("delete", "nodes", None),
    ("create", "clusterrolebindings.rbac.authorization.k8s.io", None),
]


def _can_i(
    kubectl: Tool,
    kubeconfig: Path,
    user: str,
    namespace: str,
    verb: str,
    resource: str,
    sub: str | None,
) -> bool:
    args = ["auth", "can-i", verb, resource, "--as", user, "-n", namespace]
    if sub:
        args.append(f"--subresource={sub}")
    result = _kubectl(kubectl, kubeconfig, *args, check=False)
    return str(result.stdout).strip() == "yes"


def test_operator_chart_installs_with_least_privilege(
    helm: Tool, kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str, tmp_path: Path
) -> None:
    _restricted(kubectl, kubeconfig_path, k8s_namespace)
    release = f"op-{secrets.token_hex(3)}"
    values = tmp_path / "values.yaml"
    values.write_text(yaml.safe_dump({"crds": {"install": False}}))
    _helm(
        helm, kubeconfig_path, "install", release, str(OPERATOR_CHART),
        "--namespace", k8s_namespace, "--values", str(values), "--wait", "--timeout", "120s",
    )  # fmt: skip
    try:
        deployment = yaml.safe_load(
            _kubectl(kubectl, kubeconfig_path, "-n", k8s_namespace, "get", "deployment",
                     f"{release}-simtest-operator", "-o", "yaml").stdout
        )  # fmt: skip
        assert deployment["status"]["availableReplicas"] == 1
        user = f"system:serviceaccount:{k8s_namespace}:{release}-simtest-operator"
        other = "default"  # any namespace: the ClusterRoleBinding is cluster-wide
        for verb, resource, sub in ALLOWED:
            assert _can_i(kubectl, kubeconfig_path, user, other, verb, resource, sub), (
                verb,
                resource,
                sub,
            )
        for verb, resource, sub in DENIED:
            assert not _can_i(kubectl, kubeconfig_path, user, other, verb, resource, sub), (
                verb,
                resource,
                sub,
            )
        # `bind` only on the provisioner role: a RoleBinding to it may be created, to admin not.
        provisioner = f"{release}-simtest-operator-helmfile-provisioner"
        for role, allowed in ((provisioner, True), ("admin", False)):
            result = _kubectl(
                kubectl, kubeconfig_path, "-n", k8s_namespace, "create", "rolebinding",
                f"bind-{role[:20]}", f"--clusterrole={role}", "--serviceaccount=x:y",
                "--as", user, "--dry-run=server", check=False,
            )  # fmt: skip
            assert (result.returncode == 0) is allowed, result.stderr
    finally:
        _helm(helm, kubeconfig_path, "uninstall", release, "--namespace", k8s_namespace, "--wait")
    crds = _kubectl(
        kubectl, kubeconfig_path, "get", "crd", "testcampaigns.simtest.dev", check=False
    )
    assert crds.returncode == 0  # crds.install=false: the release never owned them


@pytest.mark.parametrize("case", ["deployment-cyclonedds", "job-fastdds"])
def test_k8s_ros_installs_into_a_restricted_namespace(
    case: str, helm: Tool, kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str, tmp_path: Path
) -> None:
    _restricted(kubectl, kubeconfig_path, k8s_namespace)
    values = {key: value for key, value in ROS_CASES[case].items() if key != "ownerReferences"}
    path = tmp_path / "values.yaml"
    path.write_text(yaml.safe_dump(values))
    _helm(
        helm, kubeconfig_path, "install", "app", str(ROS_CHART), "--namespace", k8s_namespace,
        "--values", str(path), "--wait", "--wait-for-jobs", "--timeout", "120s",
    )  # fmt: skip
    pods = yaml.safe_load(
        _kubectl(kubectl, kubeconfig_path, "-n", k8s_namespace, "get", "pods", "-o", "yaml").stdout
    )
    assert pods["items"], "no pod was admitted"
    assert {p["status"]["phase"] for p in pods["items"]} <= {"Running", "Succeeded"}
    _helm(helm, kubeconfig_path, "uninstall", "app", "--namespace", k8s_namespace, "--wait")
