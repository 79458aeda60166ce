"""The composed-SUT environment: the SUT as its own workload, which the Helmfile provisioner
installs next to the simulator pod, and the simulator pod told where it is.

Covers: the simulator pod has no sidecar and gets ``SIMTEST_SUT_ENDPOINT`` = the Service's
cluster DNS name and the SUT's port; through the real ``helmfile template`` (K8s-ROS chart) the
stack is one Deployment of ``sut.image`` (protocol address variables, the campaign's command with
``{port}`` replaced and env, TCP startup and readiness probes on the protocol port, restricted
profile, owned by the SimEnvironment) and one ClusterIP Service whose name and port are that
endpoint's; a campaign without ``sut.image`` or ``sut.external.endpoint`` is told what to set.
The ``composed-sut`` golden case (tests/render/cases.py) fixes the rendered files byte for byte.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest

from simtest_operator import render
from simtest_operator.api.v1alpha1 import environment
from simtest_operator.errors import RenderError
from tests.charts.helmtools import REPO, Tool, documents, restricted_problems
from tests.render.cases import CASES

LIBRARY = render.TemplateLibrary(REPO / "helm-templates")
SERVICE = "demo-b00003-e007-a2-sut"


def _rendered(**changes: Any) -> render.RenderedEnvironment:
    request = dataclasses.replace(CASES["composed-sut"], charts_dir=str(REPO / "charts"), **changes)
    return render.render_environment(request, LIBRARY)


def test_the_simulator_pod_gets_the_stacks_endpoint_and_no_sidecar() -> None:
    spec = _rendered().pod["spec"]
    assert "initContainers" not in spec
    env = {e["name"]: e.get("value") for e in spec["containers"][0]["env"]}
    assert env["SIMTEST_SUT_ENDPOINT"] == f"{SERVICE}.ci.svc:7461"


@pytest.mark.timeout(120)
def test_the_stack_is_a_deployment_and_a_service_at_that_endpoint(
    tmp_path: Path, helmfile: Tool
) -> None:
    rendered = _rendered()
    assert rendered.helmfile is not None
    (tmp_path / "helmfile.yaml").write_text(rendered.helmfile)
    result = helmfile.run(
        "--file", tmp_path / "helmfile.yaml", "--no-color", "template", "--skip-deps", cwd=tmp_path
    )
    docs = {(d["kind"], d["metadata"]["name"]): d for d in documents(result.stdout)}
    assert set(docs) == {
        ("Pod", "demo-b00003-e007-a2"),
        ("Deployment", SERVICE),
        ("Service", SERVICE),
    }
    service = docs["Service", SERVICE]
    assert service["spec"]["type"] == "ClusterIP" and "clusterIP" not in service["spec"]
    assert service["spec"]["ports"] == [
        {"name": "sut", "port": 7461, "targetPort": "sut", "protocol": "TCP"}
    ]
    deployment = docs["Deployment", SERVICE]
    assert (
        service["spec"]["selector"].items()
        <= deployment["spec"]["template"]["metadata"]["labels"].items()
    )
    pod = deployment["spec"]["template"]["spec"]
    assert restricted_problems(pod) == []
    assert deployment["metadata"]["ownerReferences"][0]["kind"] == "SimEnvironment"
    (container,) = pod["containers"]
    assert container["image"] == "ghcr.io/simtest-dev/simtest-sut-go:0.1.0"
    assert container["ports"] == [{"name": "sut", "containerPort": 7461, "protocol": "TCP"}]
    env = {e["name"]: e.get("value") for e in container["env"]}
    assert (env["SIMTEST_SUT_HOST"], env["SIMTEST_SUT_PORT"], env["SUT_LOG"]) == (
        "0.0.0.0",
        "7461",
        "info",
    )
    for probe in ("startupProbe", "readinessProbe"):
        assert container[probe]["tcpSocket"] == {"port": "sut"}
        assert container[probe]["periodSeconds"] == 1
    assert container["startupProbe"]["failureThreshold"] == 30  # startupTimeoutSeconds


def test_the_campaigns_command_runs_with_its_port() -> None:
    sut = environment.SutConfig.model_validate(
        {
            "image": "ghcr.io/acme/bridge:1",
            "external": {"endpoint": "127.0.0.1:7460", "command": ["/bridge", "--port={port}"]},
        }
    ).to_wire()
    values = _rendered(sut=sut, values={}).values
    assert values["stack"]["command"] == ["/bridge", "--port=7460"]


@pytest.mark.parametrize(
    ("sut", "missing"),
    [
        ({"image": "ghcr.io/acme/planner:1"}, "sut.external.endpoint"),
        ({"external": {"endpoint": "127.0.0.1:7460"}}, "sut.image"),
    ],
)
def test_a_campaign_is_told_what_the_stack_needs(sut: dict[str, Any], missing: str) -> None:
    wire = environment.SutConfig.model_validate(sut).to_wire()
    with pytest.raises(RenderError, match=missing):
        _rendered(sut=wire, values={})
