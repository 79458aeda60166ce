"""The simtest-operator chart with leader election, rendered by the real helm (no cluster).

Covers: off by default (one replica, Recreate, no Lease RBAC, no election variables); on, it
defaults to two replicas with a rolling update, passes the Lease name, namespace and holder
identity (pod name, through the downward API) and client-go's timing, adds a Role in the release
namespace with exactly get/create/update on Leases, and spreads replicas with a soft (or hard, or
no) pod anti-affinity unless `affinity` is set; more than one replica without election is refused;
`helm lint --strict` stays clean.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from tests.charts.helmtools import OPERATOR_CHART, Tool, documents, find, template

ELECTION = {"leaderElection": {"enabled": True}}


def _render(helm: Tool, values: dict[str, Any]) -> list[dict[str, Any]]:
    return documents(template(helm, OPERATOR_CHART, values=values).stdout)


def _deployment(docs: list[dict[str, Any]]) -> dict[str, Any]:
    return find(docs, "Deployment", "simtest-operator")


def _leases_roles(docs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [
        d
        for d in docs
        if d["kind"] in ("Role", "ClusterRole")
        and any("leases" in r.get("resources", []) for r in d.get("rules", []))
    ]


def test_off_by_default(helm: Tool) -> None:
    docs = _render(helm, {})
    spec = _deployment(docs)["spec"]
    assert spec["replicas"] == 1 and spec["strategy"] == {"type": "Recreate"}
    env = {e["name"] for e in spec["template"]["spec"]["containers"][0]["env"]}
    assert not {n for n in env if "LEASE" in n or "LEADER" in n or "IDENTITY" in n}
    assert not _leases_roles(docs)
    assert "affinity" not in spec["template"]["spec"]


def test_on(helm: Tool) -> None:
    docs = _render(helm, ELECTION)
    spec = _deployment(docs)["spec"]
    assert spec["replicas"] == 2
    assert spec["strategy"] == {
        "type": "RollingUpdate",
        "rollingUpdate": {"maxUnavailable": 0, "maxSurge": 1},
    }
    env = {e["name"]: e for e in spec["template"]["spec"]["containers"][0]["env"]}
    assert env["SIMTEST_OPERATOR_LEADER_ELECTION"]["value"] == "true"
    assert env["SIMTEST_OPERATOR_LEASE_NAME"]["value"] == "simtest-operator"
    assert env["SIMTEST_OPERATOR_LEASE_NAMESPACE"]["valueFrom"] == {
        "fieldRef": {"fieldPath": "metadata.namespace"}
    }
    assert env["SIMTEST_OPERATOR_IDENTITY"]["valueFrom"] == {
        "fieldRef": {"fieldPath": "metadata.name"}
    }
    timing = [
        env[f"SIMTEST_OPERATOR_{k}"]["value"]
        for k in ("LEASE_DURATION", "RENEW_DEADLINE", "RETRY_PERIOD")
    ]
    assert timing == ["15", "10", "2"]
    (role,) = _leases_roles(docs)
    assert role["kind"] == "Role" and role["metadata"]["namespace"] == "simtest-system"
    assert role["rules"] == [
        {
            "apiGroups": ["coordination.k8s.io"],
            "resources": ["leases"],
            "verbs": ["get", "create", "update"],
        }
    ]
    binding = find(docs, "RoleBinding", role["metadata"]["name"])
    assert binding["roleRef"]["name"] == role["metadata"]["name"]
    assert binding["subjects"] == [
        {"kind": "ServiceAccount", "name": "simtest-operator", "namespace": "simtest-system"}
    ]
    spread = spec["template"]["spec"]["affinity"]["podAntiAffinity"]
    (term,) = spread["preferredDuringSchedulingIgnoredDuringExecution"]
    assert term["podAffinityTerm"]["topologyKey"] == "kubernetes.io/hostname"


def test_anti_affinity_modes_and_explicit_affinity(helm: Tool) -> None:
    hard = _deployment(_render(helm, {**ELECTION, "podAntiAffinity": "hard", "replicas": 3}))
    assert hard["spec"]["replicas"] == 3
    spread = hard["spec"]["template"]["spec"]["affinity"]["podAntiAffinity"]
    assert "requiredDuringSchedulingIgnoredDuringExecution" in spread
    off = _deployment(_render(helm, {**ELECTION, "podAntiAffinity": ""}))
    assert "affinity" not in off["spec"]["template"]["spec"]
    own = {"nodeAffinity": {"requiredDuringSchedulingIgnoredDuringExecution": {}}}
    mine = _deployment(_render(helm, {**ELECTION, "affinity": own}))
    assert mine["spec"]["template"]["spec"]["affinity"] == own
    one = _deployment(_render(helm, {**ELECTION, "replicas": 1}))
    assert one["spec"]["replicas"] == 1 and "affinity" not in one["spec"]["template"]["spec"]


def test_several_replicas_need_election(helm: Tool) -> None:
    result = template(helm, OPERATOR_CHART, values={"replicas": 2}, check=False)
    assert result.returncode != 0
    assert "replicas > 1 needs leaderElection.enabled=true" in result.stderr
    bad = template(helm, OPERATOR_CHART, values={"podAntiAffinity": "always"}, check=False)
    assert bad.returncode != 0 and "podAntiAffinity" in bad.stderr


def test_lint_is_clean(helm: Tool, tmp_path: Path) -> None:
    values = tmp_path / "values.yaml"
    values.write_text(yaml.safe_dump({**ELECTION, "podAntiAffinity": "hard"}))
    result = helm.run("lint", "--strict", OPERATOR_CHART, "--values", values)
    assert "1 chart(s) linted, 0 chart(s) failed" in result.stdout
