"""The simtest-operator chart rendered by the real helm (no cluster).

Covers: `helm lint --strict` for the defaults and for each optional feature; the schema refuses
typos and bad values, and the templates refuse inconsistent combinations, with clear messages;
the CRDs rendered are the generated ones (plus labels and the keep policy, or nothing when
disabled); the Deployment (one replica, Recreate, probes on /healthz and /readyz of the metrics
port, restricted security, arguments and SIMTEST_OPERATOR_* variables from values, template and
scenario volumes); the RBAC shape for cluster-wide and namespaced watching and its
least-privilege invariants (no wildcards, Secrets only by name, no pod exec/logs, `bind` only on
the provisioner role); the Service and ServiceMonitor select the operator pod.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.charts.helmtools import (
    OPERATOR_CHART,
    REPO,
    Tool,
    documents,
    find,
    restricted_problems,
    template,
)

FEATURES: dict[str, dict[str, Any]] = {
    "defaults": {},
    "namespaced": {"watch": {"namespaces": ["team-b", "team-a"]}},
    "monitoring": {"metrics": {"serviceMonitor": {"enabled": True, "labels": {"release": "p"}}}},
    "pinned": {"image": {"digest": "sha256:" + "ab" * 32}, "imagePullSecrets": [{"name": "r"}]},
    "volumes": {"operator": {"scenarioClaim": "scenarios", "templates": {"ros": "ros-templates"}}},
    "minimal-rbac": {"rbac": {"readSecrets": False}, "helmfileProvisioner": {"enabled": False}},
    "external-crds": {"crds": {"install": False}},
    "own-account": {"serviceAccount": {"create": False, "name": "ops"}},
}


def _render(helm: Tool, values: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    return documents(template(helm, OPERATOR_CHART, values=values or {}).stdout)


@pytest.mark.parametrize("feature", sorted(FEATURES))
def test_lint_is_clean(feature: str, helm: Tool, tmp_path: Path) -> None:
    values = tmp_path / "values.yaml"
    values.write_text(yaml.safe_dump(FEATURES[feature]))
    result = helm.run("lint", "--strict", OPERATOR_CHART, "--values", values)
    assert "1 chart(s) linted, 0 chart(s) failed" in result.stdout
    assert "[WARNING]" not in result.stdout


BAD_VALUES = {
    "typo top-level": ({"wach": {}}, "additional properties 'wach' not allowed"),
    "typo nested": ({"metrics": {"serviceMonitor": {"enable": True}}}, "'enable' not allowed"),
    "namespace name": ({"watch": {"namespaces": ["Team_A"]}}, "watch/namespaces/0"),
    "duplicate namespace": ({"watch": {"namespaces": ["a", "a"]}}, "items at 0 and 1 are equal"),
    "reuse queue": ({"operator": {"reuseQueue": 0}}, "reuseQueue"),
    "bad digest": ({"image": {"digest": "sha256:xyz"}}, "image/digest"),
    "bad template name": ({"operator": {"templates": {"Bad": "cm"}}}, "invalid propertyName 'Bad'"),
    "bad interval": ({"metrics": {"serviceMonitor": {"interval": "often"}}}, "interval"),
    "monitor without service": (
        {"metrics": {"service": {"enabled": False}, "serviceMonitor": {"enabled": True}}},
        "metrics.serviceMonitor.enabled needs metrics.service.enabled",
    ),
    "account without name": (
        {"serviceAccount": {"create": False}},
        "serviceAccount.name is required when serviceAccount.create is false",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_VALUES))
def test_bad_values_are_refused(case: str, helm: Tool) -> None:
    values, message = BAD_VALUES[case]
    result = template(helm, OPERATOR_CHART, values=values, check=False)
    assert result.returncode != 0
    assert message in result.stderr


def test_crds_are_the_generated_ones(helm: Tool) -> None:
    crds = [d for d in _render(helm) if d["kind"] == "CustomResourceDefinition"]
    generated = {
        doc["metadata"]["name"]: doc
        for path in sorted((REPO / "crds").glob("*.yaml"))
        for doc in [yaml.safe_load(path.read_text())]
    }
    assert sorted(c["metadata"]["name"] for c in crds) == sorted(generated)
    for crd in crds:
        meta = crd["metadata"]
        assert crd["spec"] == generated[meta["name"]]["spec"]
        assert meta["annotations"] == {"helm.sh/resource-policy": "keep"}
        assert meta["labels"]["app.kubernetes.io/part-of"] == "simtest"
    unkept = _render(helm, {"crds": {"keep": False}})
    assert all(
        "annotations" not in d["metadata"]
        for d in unkept
        if d["kind"] == "CustomResourceDefinition"
    )
    assert not [
        d for d in _render(helm, FEATURES["external-crds"]) if d["kind"].startswith("Custom")
    ]


def _operator(docs: list[dict[str, Any]]) -> tuple[dict[str, Any], dict[str, Any]]:
    deployment = find(docs, "Deployment", "simtest-operator")
    return deployment, deployment["spec"]["template"]["spec"]["containers"][0]


def test_deployment(helm: Tool) -> None:
    deployment, container = _operator(_render(helm))
    spec = deployment["spec"]
    assert spec["replicas"] == 1 and spec["strategy"] == {"type": "Recreate"}
    pod = spec["template"]["spec"]
    assert restricted_problems(pod) == []
    assert pod["serviceAccountName"] == "simtest-operator"
    assert container["image"] == "ghcr.io/simtest-dev/simtest-operator:0.1.0"
    assert container["args"] == ["operator"]  # the whole cluster
    assert container["ports"] == [
        {"name": "http-metrics", "containerPort": 8080, "protocol": "TCP"}
    ]
    assert container["livenessProbe"]["httpGet"] == {"path": "/healthz", "port": "http-metrics"}
    assert container["readinessProbe"]["httpGet"] == {"path": "/readyz", "port": "http-metrics"}
    env = {item["name"]: item.get("value") for item in container["env"]}
    assert env["SIMTEST_OPERATOR_METRICS_PORT"] == "8080"
    assert env["SIMTEST_OPERATOR_TEMPLATES"] == "/opt/simtest/helm-templates"
    assert env["SIMTEST_OPERATOR_KEEP_ENVIRONMENTS"] == "false"
    assert env["SIMTEST_OPERATOR_HELMFILE_IMAGE"] == "ghcr.io/simtest-dev/simtest-helmfile:0.1.0"
    assert env["SIMTEST_OPERATOR_HELMFILE_ROLE"] == "simtest-operator-helmfile-provisioner"
    assert "SIMTEST_OPERATOR_SCENARIO_CLAIM" not in env
    assert container["resources"]["limits"]["memory"] == "1Gi"


def test_deployment_follows_values(helm: Tool) -> None:
    values = {
        **FEATURES["namespaced"],
        **FEATURES["volumes"],
        "operator": {**FEATURES["volumes"]["operator"], "verbose": True, "reuseQueue": 4},
        "image": {"digest": "sha256:" + "ab" * 32},
        "helmfileProvisioner": {"nodeSelector": {"zone": "b", "node-role/infra": "true"}},
    }
    deployment, container = _operator(_render(helm, values))
    assert container["args"] == [
        "operator",
        "--namespace=team-a",
        "--namespace=team-b",
        "--verbose",
    ]
    assert container["image"] == "ghcr.io/simtest-dev/simtest-operator@sha256:" + "ab" * 32
    env = {item["name"]: item.get("value") for item in container["env"]}
    assert env["SIMTEST_OPERATOR_SCENARIO_CLAIM"] == "scenarios"
    assert env["SIMTEST_OPERATOR_SOURCES"] == "/scenarios"
    assert env["SIMTEST_OPERATOR_REUSE_QUEUE"] == "4"
    assert env["SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR"] == "node-role/infra=true,zone=b"
    mounts = {m["name"]: m for m in container["volumeMounts"]}
    assert mounts["scenarios"] == {"name": "scenarios", "mountPath": "/scenarios", "readOnly": True}
    assert mounts["template-ros"]["mountPath"] == "/opt/simtest/helm-templates/ros"
    volumes = {v["name"]: v for v in deployment["spec"]["template"]["spec"]["volumes"]}
    assert volumes["template-ros"] == {
        "name": "template-ros",
        "configMap": {"name": "ros-templates"},
    }
    assert volumes["scenarios"]["persistentVolumeClaim"]["readOnly"] is True


def _rules(role: dict[str, Any]) -> dict[tuple[str, str], set[str]]:
    table: dict[tuple[str, str], set[str]] = {}
    for rule in role["rules"]:
        for group in rule["apiGroups"]:
            for resource in rule["resources"]:
                table.setdefault((group, resource), set()).update(rule["verbs"])
    return table


NAMESPACED = {
    ("simtest.dev", "testcampaigns"): {"get", "list", "watch"},
    ("simtest.dev", "scenariobatches"): {"get", "list", "watch", "create"},
    ("simtest.dev", "simenvironments"): {"get", "list", "watch", "create", "delete"},
    ("simtest.dev", "testcampaigns/status"): {"patch"},
    ("", "pods"): {"get", "list", "watch", "create", "delete"},
    ("", "configmaps"): {"get", "create"},
    ("", "serviceaccounts"): {"create"},
    ("", "events"): {"create"},
    ("", "secrets"): {"get"},
    ("batch", "jobs"): {"get", "list", "watch", "create", "delete"},
    ("kueue.x-k8s.io", "workloads"): {"get", "list", "watch", "create", "delete"},
    ("rbac.authorization.k8s.io", "rolebindings"): {"create"},
    ("rbac.authorization.k8s.io", "clusterroles"): {"bind"},
}
CLUSTER = {
    ("", "nodes"): {"list", "watch"},
    ("apiextensions.k8s.io", "customresourcedefinitions"): {"list", "watch"},
}


def _check_invariants(role: dict[str, Any]) -> None:
    for rule in role["rules"]:
        for field in ("apiGroups", "resources", "verbs"):
            assert "*" not in rule[field], f"wildcard in {rule}"
        assert not {"escalate", "impersonate", "deletecollection"} & set(rule["verbs"])
        if "bind" in rule["verbs"]:
            assert rule["resourceNames"] == ["simtest-operator-helmfile-provisioner"]
    table = _rules(role)
    assert ("", "pods/exec") not in table and ("", "pods/log") not in table
    assert table.get(("", "secrets"), {"get"}) == {"get"}


def test_cluster_wide_rbac(helm: Tool) -> None:
    docs = _render(helm)
    role = find(docs, "ClusterRole", "simtest-operator")
    _check_invariants(role)
    table = _rules(role)
    for key, verbs in {**NAMESPACED, **CLUSTER}.items():
        assert table[key] == verbs, key
    assert ("", "namespaces") not in table
    binding = find(docs, "ClusterRoleBinding", "simtest-operator")
    assert binding["subjects"] == [
        {"kind": "ServiceAccount", "name": "simtest-operator", "namespace": "simtest-system"}
    ]
    assert not [d for d in docs if d["kind"] in ("Role", "RoleBinding")]
    provisioner = find(docs, "ClusterRole", "simtest-operator-helmfile-provisioner")
    assert ("", "secrets") not in _rules(provisioner)
    _check_invariants(provisioner)


def test_namespaced_rbac(helm: Tool) -> None:
    docs = _render(helm, FEATURES["namespaced"])
    cluster_table = _rules(find(docs, "ClusterRole", "simtest-operator"))
    assert cluster_table == {**CLUSTER, ("", "namespaces"): {"list", "watch"}}
    roles = [d for d in docs if d["kind"] == "Role"]
    assert [r["metadata"]["namespace"] for r in roles] == ["team-a", "team-b"]
    for role in roles:
        _check_invariants(role)
        assert _rules(role) == {
            key: verbs
            for key, verbs in _rules(role).items()
            if key in NAMESPACED or key[1].endswith(("/status", "/finalizers"))
        }
        assert _rules(role)[("", "pods")] == NAMESPACED[("", "pods")]
    bindings = [d for d in docs if d["kind"] == "RoleBinding"]
    assert [b["metadata"]["namespace"] for b in bindings] == ["team-a", "team-b"]
    assert all(b["roleRef"]["kind"] == "Role" for b in bindings)


def test_optional_permissions_go_away(helm: Tool) -> None:
    docs = _render(helm, FEATURES["minimal-rbac"])
    table = _rules(find(docs, "ClusterRole", "simtest-operator"))
    assert ("", "secrets") not in table
    # Jobs stay: the operator watches them and the evaluation step creates one per campaign.
    assert table[("batch", "jobs")] == NAMESPACED[("batch", "jobs")]
    assert ("rbac.authorization.k8s.io", "rolebindings") not in table
    assert ("rbac.authorization.k8s.io", "clusterroles") not in table
    assert [d["metadata"]["name"] for d in docs if d["kind"] == "ClusterRole"] == [
        "simtest-operator"
    ]
    _, container = _operator(docs)
    assert not [e for e in container["env"] if e["name"].startswith("SIMTEST_OPERATOR_HELMFILE")]


def test_service_and_monitor_select_the_operator(helm: Tool) -> None:
    docs = _render(helm, FEATURES["monitoring"])
    deployment, _ = _operator(docs)
    pod_labels = deployment["spec"]["template"]["metadata"]["labels"]
    service = find(docs, "Service", "simtest-operator-metrics")
    assert service["spec"]["selector"].items() <= pod_labels.items()
    assert service["spec"]["ports"][0]["targetPort"] == "http-metrics"
    monitor = find(docs, "ServiceMonitor", "simtest-operator")
    assert (
        monitor["spec"]["selector"]["matchLabels"].items() <= service["metadata"]["labels"].items()
    )
    assert monitor["spec"]["endpoints"][0]["port"] == "http-metrics"
    assert monitor["metadata"]["labels"]["release"] == "p"
