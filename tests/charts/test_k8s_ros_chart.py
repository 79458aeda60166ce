"""The K8s-ROS base chart rendered by the real helm (no cluster).

Covers: `helm lint --strict` for every golden value set and for the bare base chart, which still
refuses to render without an image; the workload per kind (Deployment with
replicas, Job with restartPolicy Never and its limits) meets the restricted profile; ROS and DDS
variables follow ros.rmw / dds.vendor; the generated DDS XML is well-formed and carries peers and
interface; params files become one ConfigMap (strings verbatim, mappings as YAML) and, on request,
--ros-args; the pod checksum changes when a parameter changes; owner references land on every
object; values-level overrides and extra manifests apply; the schema refuses bad values (domain id,
unknown RMW name, XML-breaking peers, params file names, kinds) and a Service without ports fails
with a clear message.
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.charts.helmtools import ROS_CHART, Tool, documents, find, restricted_problems, template
from tests.charts.test_chart_golden import ROS_CASES


def _render(helm: Tool, values: dict[str, Any]) -> list[dict[str, Any]]:
    return documents(
        template(helm, ROS_CHART, release="app", namespace="tests", values=values).stdout
    )


@pytest.mark.parametrize("case", sorted(ROS_CASES))
def test_lint_is_clean(case: str, helm: Tool, tmp_path: Path) -> None:
    values = tmp_path / "values.yaml"
    values.write_text(yaml.safe_dump(ROS_CASES[case]))
    result = helm.run("lint", "--strict", ROS_CHART, "--values", values)
    assert "0 chart(s) failed" in result.stdout


def test_base_chart_lints_bare_but_needs_an_image_to_render(helm: Tool) -> None:
    assert "0 chart(s) failed" in helm.run("lint", "--strict", ROS_CHART).stdout
    result = template(helm, ROS_CHART, release="app", check=False)
    assert result.returncode != 0
    assert "image.repository is required" in result.stderr


def _pod(docs: list[dict[str, Any]], kind: str) -> dict[str, Any]:
    return dict(find(docs, kind, "app-k8s-ros")["spec"]["template"]["spec"])


def _env(pod: dict[str, Any]) -> dict[str, Any]:
    return {item["name"]: item.get("value") for item in pod["containers"][0]["env"]}


def test_deployment_with_cyclonedds_and_params(helm: Tool) -> None:
    docs = _render(helm, ROS_CASES["deployment-cyclonedds"])
    deployment = find(docs, "Deployment", "app-k8s-ros")
    assert deployment["spec"]["replicas"] == 1
    pod = _pod(docs, "Deployment")
    assert restricted_problems(pod) == []
    assert pod["automountServiceAccountToken"] is False
    env = _env(pod)
    assert env["ROS_DOMAIN_ID"] == "42"
    assert env["RMW_IMPLEMENTATION"] == "rmw_cyclonedds_cpp"
    assert env["CYCLONEDDS_URI"] == "file:///etc/ros/dds/cyclonedds.xml"
    assert env["ROS_PARAMS_DIR"] == "/etc/ros/params"
    assert env["ROS_HOME"].startswith("/tmp")
    container = pod["containers"][0]
    assert container["args"] == [
        "--ros-args",
        "--params-file", "/etc/ros/params/limits.yaml",
        "--params-file", "/etc/ros/params/planner.yaml",
    ]  # fmt: skip
    params = find(docs, "ConfigMap", "app-k8s-ros-params")["data"]
    assert params["planner.yaml"] == "planner:\n  ros__parameters:\n    horizon_s: 6.0\n"
    assert yaml.safe_load(params["limits.yaml"]) == {"/**": {"ros__parameters": {"max_accel": 2.0}}}
    xml = find(docs, "ConfigMap", "app-k8s-ros-dds")["data"]["cyclonedds.xml"]
    root = ElementTree.fromstring(xml)
    ns = {"c": "https://cdds.io/config"}
    peers = [p.get("Address") for p in root.iterfind(".//c:Peers/c:Peer", ns)]
    assert peers == ["planner-0.planner.tests.svc"]
    assert root.find(".//c:NetworkInterface", ns).get("name") == "eth0"  # type: ignore[union-attr]
    assert root.findtext(".//c:AllowMulticast", namespaces=ns) == "false"


def test_job_with_fastdds(helm: Tool) -> None:
    docs = _render(helm, ROS_CASES["job-fastdds"])
    job = find(docs, "Job", "app-k8s-ros")
    assert job["spec"]["activeDeadlineSeconds"] == 900
    assert "ttlSecondsAfterFinished" not in job["spec"]  # -1 keeps the Job
    pod = _pod(docs, "Job")
    assert pod["restartPolicy"] == "Never" and restricted_problems(pod) == []
    assert pod["containers"][0]["image"] == "registry.example.com/acme/replay:2.0"
    env = _env(pod)
    assert env["FASTDDS_DEFAULT_PROFILES_FILE"] == "/etc/ros/dds/fastdds.xml"
    assert env["ROS_LOCALHOST_ONLY"] == "1"
    assert "CYCLONEDDS_URI" not in env and "ROS_PARAMS_DIR" not in env
    xml = find(docs, "ConfigMap", "app-k8s-ros-dds")["data"]["fastdds.xml"]
    root = ElementTree.fromstring(xml)
    ns = {"f": "http://www.eprosima.com"}
    assert [a.text for a in root.iterfind(".//f:initialPeersList//f:address", ns)] == ["10.0.0.12"]
    for doc in docs:
        assert doc["metadata"]["ownerReferences"][0]["kind"] == "SimEnvironment"
    assert not [d for d in docs if d["kind"] == "Deployment"]


def test_overrides_and_extra_manifests(helm: Tool) -> None:
    docs = _render(helm, ROS_CASES["overrides"])
    pod = _pod(docs, "Deployment")
    assert pod["hostNetwork"] is True
    assert pod["containers"][0]["workingDir"] == "/ws"
    assert pod["serviceAccountName"] == "app-k8s-ros"
    env = _env(pod)
    assert env["MODE"] == "sim" and env["RATE"] == "10"
    assert "RMW_IMPLEMENTATION" not in env and "CYCLONEDDS_URI" not in env
    assert not [d for d in docs if d["metadata"]["name"].endswith("-dds")]
    assert find(docs, "ConfigMap", "app-extra")["data"] == {"domain": "0"}
    assert find(docs, "ServiceAccount", "app-k8s-ros")["automountServiceAccountToken"] is False


def test_checksum_follows_the_parameters(helm: Tool) -> None:
    values = dict(ROS_CASES["deployment-cyclonedds"])
    first = find(_render(helm, values), "Deployment")
    values["params"] = {**values["params"], "planner.yaml": "planner:\n  ros__parameters: {}\n"}
    second = find(_render(helm, values), "Deployment")
    key = "checksum/config"
    assert (
        first["spec"]["template"]["metadata"]["annotations"][key]
        != second["spec"]["template"]["metadata"]["annotations"][key]
    )


BASE = {"image": "a/b:1"}
BAD = {
    "domain id": ({**BASE, "ros": {"domainId": 233}}, "ros/domainId"),
    "rmw name": ({**BASE, "ros": {"rmw": "cyclone"}}, "ros/rmw"),
    "peer injection": ({**BASE, "dds": {"peers": ['x"/><Evil a="']}}, "dds/peers/0"),
    "params name": ({**BASE, "params": {"a/b.yaml": "x: 1"}}, "invalid propertyName 'a/b.yaml'"),
    "kind": ({**BASE, "kind": "StatefulSet"}, "kind"),
    "typo": ({**BASE, "dds": {"peer": ["a"]}}, "'peer' not allowed"),
    "service without ports": ({**BASE, "service": {"enabled": True}}, "needs at least one entry"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_values_are_refused(case: str, helm: Tool) -> None:
    values, message = BAD[case]
    result = template(helm, ROS_CHART, release="app", values=values, check=False)
    assert result.returncode != 0
    assert message in result.stderr
