"""The operator chart's device plugin DaemonSet (`devicePlugin.*`), rendered by the real helm.

Covers: off by default (nothing rendered); `helm lint --strict` with it on; the DaemonSet runs
`simtest-device-plugin` with the slots, the kubelet's device-plugin directory as a hostPath and
NODE_NAME from the downward API, as root without capabilities, privilege escalation or a writable
root file system (the hostPath and uid 0 are its only departures from Pod Security `restricted`);
its labels never match a selector of the operator (Service, Deployment); the label override brings
a ServiceAccount and a ClusterRole with get/watch on nodes only, and without it there are no
credentials and `--slots-label=` turns the lookup off; `devicePlugin.namespace` moves the
DaemonSet and its ServiceAccount; bad values are refused by the schema.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.charts.helmtools import (
    OPERATOR_CHART,
    Tool,
    documents,
    find,
    restricted_problems,
    template,
)

NAME = "simtest-operator-device-plugin"


def _render(helm: Tool, **device_plugin: Any) -> list[dict[str, Any]]:
    values = {"devicePlugin": {"enabled": True, **device_plugin}}
    return documents(template(helm, OPERATOR_CHART, values=values).stdout)


def _plugin(docs: list[dict[str, Any]]) -> tuple[dict[str, Any], dict[str, Any]]:
    daemonset = find(docs, "DaemonSet", NAME)
    return daemonset, daemonset["spec"]["template"]["spec"]


def test_off_by_default(helm: Tool) -> None:
    docs = documents(template(helm, OPERATOR_CHART).stdout)
    assert not [d for d in docs if "device-plugin" in d["metadata"]["name"]]


@pytest.mark.parametrize(
    "values",
    [{}, {"slotsFromNodeLabel": False}, {"namespace": "kube-system", "priorityClassName": ""}],
    ids=["defaults", "no-label", "kube-system"],
)
def test_lint_is_clean(values: dict[str, Any], helm: Tool, tmp_path: Path) -> None:
    path = tmp_path / "values.yaml"
    path.write_text(yaml.safe_dump({"devicePlugin": {"enabled": True, **values}}))
    result = helm.run("lint", "--strict", OPERATOR_CHART, "--values", path)
    assert "1 chart(s) linted, 0 chart(s) failed" in result.stdout
    assert "[WARNING]" not in result.stdout


def test_daemonset(helm: Tool) -> None:
    daemonset, pod = _plugin(_render(helm, slots=3))
    assert daemonset["metadata"]["namespace"] == "simtest-system"
    (container,) = pod["containers"]
    assert container["image"] == "ghcr.io/simtest-dev/simtest-device-plugin:0.1.0"
    assert container["args"] == [
        "--slots=3",
        "--device-plugin-path=/var/lib/kubelet/device-plugins",
    ]
    assert container["env"] == [
        {"name": "NODE_NAME", "valueFrom": {"fieldRef": {"fieldPath": "spec.nodeName"}}}
    ]
    assert container["volumeMounts"] == [
        {"name": "device-plugins", "mountPath": "/var/lib/kubelet/device-plugins"}
    ]
    assert pod["volumes"] == [
        {
            "name": "device-plugins",
            "hostPath": {"path": "/var/lib/kubelet/device-plugins", "type": "Directory"},
        }
    ]
    assert pod["priorityClassName"] == "system-node-critical"
    assert pod["serviceAccountName"] == NAME and pod["automountServiceAccountToken"] is True
    security = container["securityContext"]
    assert security["runAsUser"] == 0
    assert security["capabilities"] == {"drop": ["ALL"]}
    assert security["allowPrivilegeEscalation"] is False
    assert security["readOnlyRootFilesystem"] is True
    assert "privileged" not in security and not pod.get("hostNetwork")
    assert sorted(restricted_problems(pod)) == [
        "device-plugin: runAsNonRoot",
        "device-plugin: runAsUser 0",
        "volume device-plugins: hostPath",
    ]


def test_labels_stay_apart_from_the_operator(helm: Tool) -> None:
    docs = _render(helm)
    daemonset, _ = _plugin(docs)
    pod_labels = daemonset["spec"]["template"]["metadata"]["labels"]
    selector = daemonset["spec"]["selector"]["matchLabels"]
    assert selector.items() <= pod_labels.items()
    service = find(docs, "Service", "simtest-operator-metrics")
    deployment = find(docs, "Deployment", "simtest-operator")
    for operator_selector in (
        service["spec"]["selector"],
        deployment["spec"]["selector"]["matchLabels"],
    ):
        assert not operator_selector.items() <= pod_labels.items()
        assert not selector.items() <= deployment["spec"]["template"]["metadata"]["labels"].items()


def test_label_override_reads_nodes_only(helm: Tool) -> None:
    docs = _render(helm)
    role = find(docs, "ClusterRole", NAME)
    assert role["rules"] == [{"apiGroups": [""], "resources": ["nodes"], "verbs": ["get", "watch"]}]
    binding = find(docs, "ClusterRoleBinding", NAME)
    assert binding["roleRef"]["name"] == NAME
    assert binding["subjects"] == [
        {"kind": "ServiceAccount", "name": NAME, "namespace": "simtest-system"}
    ]
    assert find(docs, "ServiceAccount", NAME)["automountServiceAccountToken"] is False


def test_without_the_label_override_there_are_no_credentials(helm: Tool) -> None:
    docs = _render(helm, slotsFromNodeLabel=False)
    _, pod = _plugin(docs)
    assert "serviceAccountName" not in pod and pod["automountServiceAccountToken"] is False
    assert "--slots-label=" in pod["containers"][0]["args"]
    names = {(d["kind"], d["metadata"]["name"]) for d in docs}
    assert (
        not {("ServiceAccount", NAME), ("ClusterRole", NAME), ("ClusterRoleBinding", NAME)} & names
    )


def test_rbac_create_false_keeps_the_account_only(helm: Tool) -> None:
    docs = documents(
        template(
            helm,
            OPERATOR_CHART,
            values={"devicePlugin": {"enabled": True}, "rbac": {"create": False}},
        ).stdout
    )
    assert find(docs, "ServiceAccount", NAME)
    assert not [
        d for d in docs if d["kind"].startswith("ClusterRole") and d["metadata"]["name"] == NAME
    ]


def test_namespace_and_scheduling_follow_values(helm: Tool) -> None:
    toleration = {"operator": "Exists"}
    docs = _render(
        helm,
        namespace="kube-system",
        hostPath="/opt/kubelet/device-plugins",
        nodeSelector={"simtest.dev/simulator-node": "true"},
        tolerations=[toleration],
        image={"digest": "sha256:" + "cd" * 32},
        extraArgs=["--log-level=debug"],
    )
    daemonset, pod = _plugin(docs)
    assert daemonset["metadata"]["namespace"] == "kube-system"
    assert find(docs, "ServiceAccount", NAME)["metadata"]["namespace"] == "kube-system"
    assert find(docs, "ClusterRoleBinding", NAME)["subjects"][0]["namespace"] == "kube-system"
    assert pod["volumes"][0]["hostPath"]["path"] == "/opt/kubelet/device-plugins"
    assert pod["containers"][0]["volumeMounts"][0]["mountPath"] == "/var/lib/kubelet/device-plugins"
    assert pod["nodeSelector"] == {"simtest.dev/simulator-node": "true"}
    assert pod["tolerations"] == [toleration]
    assert pod["containers"][0]["image"].endswith("@sha256:" + "cd" * 32)
    assert pod["containers"][0]["args"][-1] == "--log-level=debug"


BAD_VALUES: dict[str, tuple[dict[str, Any], str]] = {
    "negative slots": ({"slots": -1}, "devicePlugin/slots"),
    "too many slots": ({"slots": 300}, "devicePlugin/slots"),
    "relative host path": ({"hostPath": "var/lib/kubelet"}, "devicePlugin/hostPath"),
    "bad namespace": ({"namespace": "Kube_System"}, "devicePlugin/namespace"),
    "typo": ({"slot": 2}, "additional properties 'slot' not allowed"),
}


@pytest.mark.parametrize("case", sorted(BAD_VALUES))
def test_bad_values_are_refused(case: str, helm: Tool) -> None:
    values, message = BAD_VALUES[case]
    result = template(
        helm, OPERATOR_CHART, values={"devicePlugin": {"enabled": True, **values}}, check=False
    )
    assert result.returncode != 0
    assert message in result.stderr
