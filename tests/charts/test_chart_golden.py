"""Golden files of `helm template` for both charts (rewrite: `pytest tests/render tests/charts
--update-golden`).

Covers: the operator chart with default values equals deploy/kustomize/base/simtest-operator.yaml
(the plain-manifest install, so it cannot drift from the chart); with namespaced watching, and the
device plugin's template when enabled, each equal their golden file; the K8s-ROS base chart for
several value sets equals its golden files; rendering twice gives identical bytes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.charts.helmtools import OPERATOR_CHART, REPO, ROS_CHART, Tool, template

GOLDEN = Path(__file__).parent / "golden"
KUSTOMIZE_BASE = REPO / "deploy" / "kustomize" / "base" / "simtest-operator.yaml"

ROS_CASES: dict[str, dict[str, Any]] = {
    "deployment-cyclonedds": {
        "image": {"repository": "ghcr.io/acme/planner", "tag": "1.4.0"},
        "command": ["ros2", "run", "planner", "planner_node"],
        "ros": {"domainId": 42, "appendParamsArgs": True},
        "params": {
            "planner.yaml": "planner:\n  ros__parameters:\n    horizon_s: 6.0\n",
            "limits.yaml": {"/**": {"ros__parameters": {"max_accel": 2.0}}},
        },
        "dds": {"peers": ["planner-0.planner.tests.svc"], "interface": "eth0"},
        "resources": {"requests": {"cpu": "500m", "memory": "512Mi"}},
        "ports": [{"name": "health", "containerPort": 8081}],
        "service": {"enabled": True, "type": "headless"},
    },
    "job-fastdds": {
        "kind": "Job",
        "image": "registry.example.com/acme/replay:2.0",
        "args": ["--rate", "2.0"],
        "ros": {"rmw": "rmw_fastrtps_cpp", "discoveryRange": "LOCALHOST"},
        "dds": {"peers": ["10.0.0.12"]},
        "job": {"activeDeadlineSeconds": 900, "ttlSecondsAfterFinished": -1},
        "ownerReferences": [
            {
                "apiVersion": "simtest.dev/v1alpha1",
                "kind": "SimEnvironment",
                "name": "env-1",
                "uid": "0d1e2f3a",
                "controller": True,
            }
        ],
    },
    "overrides": {
        "image": "ghcr.io/acme/tool:1",
        "ros": {"rmw": ""},
        "dds": {"vendor": "none"},
        "env": {"MODE": "sim", "RATE": 10},
        "serviceAccount": {"create": True},
        "overrides": {"container": {"workingDir": "/ws"}, "podSpec": {"hostNetwork": True}},
        "extraManifests": [
            "apiVersion: v1\nkind: ConfigMap\nmetadata:\n  name: {{ .Release.Name }}-extra\n"
            "data:\n  domain: {{ .Values.ros.domainId | quote }}\n"
        ],
    },
}


def _check(path: Path, text: str, update: bool) -> None:
    if update:
        path.write_text(text, encoding="utf-8")
    assert path.read_text(encoding="utf-8") == text, f"{path} differs; rerun with --update-golden"


def test_operator_defaults_equal_the_kustomize_base(helm: Tool, update_golden: bool) -> None:
    text = template(helm, OPERATOR_CHART).stdout
    assert template(helm, OPERATOR_CHART).stdout == text
    _check(KUSTOMIZE_BASE, text, update_golden)


def test_operator_namespaced(helm: Tool, update_golden: bool) -> None:
    values = {"watch": {"namespaces": ["team-a", "team-b"]}}
    text = template(helm, OPERATOR_CHART, values=values).stdout
    _check(GOLDEN / "simtest-operator-namespaced.yaml", text, update_golden)


def test_operator_device_plugin(helm: Tool, update_golden: bool) -> None:
    values = {
        "devicePlugin": {
            "enabled": True,
            "namespace": "kube-system",
            "slots": 3,
            "nodeSelector": {"simtest.dev/simulator-node": "true"},
            "tolerations": [
                {"key": "simtest.dev/simulator", "operator": "Exists", "effect": "NoSchedule"}
            ],
        }
    }
    only = ("--show-only", "templates/device-plugin.yaml")
    text = template(helm, OPERATOR_CHART, values=values, extra=only).stdout
    _check(GOLDEN / "simtest-operator-device-plugin.yaml", text, update_golden)


@pytest.mark.parametrize("case", sorted(ROS_CASES))
def test_k8s_ros(case: str, helm: Tool, update_golden: bool) -> None:
    text = template(
        helm, ROS_CHART, release="app", namespace="tests", values=ROS_CASES[case]
    ).stdout
    _check(GOLDEN / f"k8s-ros-{case}.yaml", text, update_golden)
