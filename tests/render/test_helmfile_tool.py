"""Rendered helmfiles through the real helmfile and helm, and against the dev control plane.

Covers: for every golden case of both templates, `helmfile template` on the rendered helmfile
(charts from the repository's charts/) succeeds, and the Pod it produces is the rendered pod
exactly (name, labels, ownerReferences, spec — the operator's contract); every other object is in
the environment's namespace, owned by the SimEnvironment, labelled with the environment, and its
pods meet the restricted profile with the environment's ROS_DOMAIN_ID; template markup inside
resource data is not evaluated by helmfile or helm. Against the dev control plane: everything
`helmfile template` produced for the default (with a SUT release) and the ros2 template passes a
server-side dry-run.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator import render
from tests.charts.helmtools import REPO, Tool, documents, restricted_problems
from tests.render.cases import CASES, SCENARIO

LIBRARY = render.TemplateLibrary(REPO / "helm-templates")
CHARTS = str(REPO / "charts")

pytestmark = pytest.mark.timeout(120)


def _render(case: str, **changes: Any) -> render.RenderedEnvironment:
    request = dataclasses.replace(CASES[case], charts_dir=CHARTS, **changes)
    return render.render_environment(request, LIBRARY)


def _template(helmfile: Tool, tmp_path: Path, rendered: render.RenderedEnvironment) -> list[Any]:
    assert rendered.helmfile is not None
    path = tmp_path / "helmfile.yaml"
    path.write_text(rendered.helmfile)
    result = helmfile.run("--file", path, "--no-color", "template", "--skip-deps", cwd=tmp_path)
    return documents(result.stdout)


@pytest.mark.parametrize("case", sorted(CASES))
def test_helmfile_template_installs_the_rendered_pod_unchanged(
    case: str, tmp_path: Path, helmfile: Tool
) -> None:
    rendered = _render(case)
    docs = _template(helmfile, tmp_path, rendered)
    pods = [d for d in docs if d["kind"] == "Pod"]
    assert pods == [rendered.pod]
    others = [d for d in docs if d["kind"] != "Pod"]
    simulator_only = ("minimal", "gpu-pvc-placement", "s3-artifacts", "scenario-sources")
    simulator_only += ("ros2-stack-in-pod",)  # the stack's components are the pod's sidecars
    assert bool(others) == (case not in simulator_only)  # SUT/stack releases
    domain = rendered.values.get("ros", {}).get("domainId")
    for doc in others:
        meta = doc["metadata"]
        assert meta["namespace"] == "ci"
        assert meta["ownerReferences"][0]["uid"] == "0d1e2f3a"
        assert meta["labels"]["simtest.dev/environment"] == "demo-b00003-e007-a2"
        if doc["kind"] == "Deployment":
            pod = doc["spec"]["template"]["spec"]
            assert restricted_problems(pod) == []
            env = {e["name"]: e.get("value") for e in pod["containers"][0]["env"]}
            if domain is not None:
                assert env["ROS_DOMAIN_ID"] == str(domain)


def test_the_ros2_stack_has_a_workload_per_enabled_component(
    tmp_path: Path, helmfile: Tool
) -> None:
    docs = _template(helmfile, tmp_path, _render("ros2-overrides"))
    deployments = sorted(d["metadata"]["name"] for d in docs if d["kind"] == "Deployment")
    assert deployments == [
        f"demo-b00003-e007-a2-{c}" for c in ("evaluator", "perception", "planning")
    ]
    services = [d for d in docs if d["kind"] == "Service"]
    assert {s["spec"]["clusterIP"] for s in services} == {"None"}  # headless: peer DNS names
    dds = [d for d in docs if d["kind"] == "ConfigMap" and "fastdds.xml" in d.get("data", {})]
    assert len(dds) == 3  # rmw_fastrtps_cpp override -> Fast DDS profiles


def test_markup_in_resource_data_is_not_evaluated(tmp_path: Path, helmfile: Tool) -> None:
    markup = '{{ fail "evaluated" }}'
    scenario = dataclasses.replace(SCENARIO, overrides={"Speed": markup})
    rendered = _render("ros2-minimal", scenarios=(scenario,), sut={"config": {"k": markup}})
    docs = _template(helmfile, tmp_path, rendered)
    assert [d for d in docs if d["kind"] == "Pod"] == [rendered.pod]
    params = [d for d in docs if d["kind"] == "ConfigMap" and "stack.yaml" in d.get("data", {})]
    assert params and all(markup in d["data"]["stack.yaml"] for d in params)


@pytest.mark.parametrize("case", ["reuse-values-override", "ros2-minimal"])
def test_templated_manifests_pass_a_server_side_dry_run(
    case: str,
    tmp_path: Path,
    helmfile: Tool,
    kubectl: Tool,
    kubeconfig_path: Path,
    k8s_namespace: str,
) -> None:
    rendered = _render(case, namespace=k8s_namespace)
    docs = _template(helmfile, tmp_path, rendered)
    kube = ("--kubeconfig", str(kubeconfig_path), "--namespace", k8s_namespace)
    kubectl.run(*kube, "create", "serviceaccount", "demo-simulator")
    result = kubectl.run(
        *kube, "apply", "--server-side", "--dry-run=server", "--field-manager=simtest-tests",
        "-f", "-", stdin=yaml.safe_dump_all(docs),
    )  # fmt: skip
    assert result.stdout.count("serverside-applied (server dry run)") == len(docs)
