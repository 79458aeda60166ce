"""The SUT sidecar in the simulator pod: an external SUT with an image becomes a native sidecar
(init container with restartPolicy Always and a TCP startup probe, so the simulator starts only
once the SUT listens), with the campaign's command, env and resources, under the restricted
profile; the simulator learns the endpoint from SIMTEST_SUT_ENDPOINT; the in-process model and
endpoint/command SUTs add no container."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from simtest_operator import render
from simtest_operator.api import converting
from simtest_operator.api.v1alpha1 import environment
from simtest_operator.drivermodel import Launch
from tests.render.cases import request

REPO = Path(__file__).resolve().parents[2]
SIDECAR = {
    "name": "acme-planner",
    "version": "2.1.0",
    "config": {"mode": "urban"},
    "external": {
        "image": "ghcr.io/acme/planner@sha256:" + "ab" * 32,
        "command": ["{python}", "-m", "acme.planner", "--port", "{port}"],
        "env": {"ACME_LOG": "debug"},
        "resources": {"requests": {"cpu": "250m", "memory": "128Mi"}},
        "port": 7600,
        "stepDeadlineMilliseconds": 40,
        "startupTimeoutSeconds": 30,
    },
}


def rendered(sut: dict[str, Any], template: str = "default") -> dict[str, Any]:
    wire = environment.SutConfig.model_validate(sut).to_wire()
    library = render.TemplateLibrary(REPO / "helm-templates")
    return dict(render.render_environment(request(sut=wire, template=template), library).pod)


@pytest.mark.parametrize("template", ["default", "ros2"])
def test_an_image_becomes_a_native_sidecar_the_simulator_waits_for(template: str) -> None:
    spec = rendered(SIDECAR, template)["spec"]
    (sidecar,) = spec["initContainers"]
    assert sidecar["name"] == "sut"
    assert sidecar["image"] == SIDECAR["external"]["image"]  # type: ignore[index]
    assert sidecar["restartPolicy"] == "Always"
    assert sidecar["command"] == ["python", "-m", "acme.planner", "--port", "7600"]
    env = {item["name"]: item["value"] for item in sidecar["env"]}
    assert env["SIMTEST_SUT_PORT"] == "7600"
    assert env["ACME_LOG"] == "debug"
    assert sidecar["startupProbe"]["tcpSocket"]["port"] == 7600
    assert sidecar["startupProbe"]["failureThreshold"] == 30
    assert sidecar["resources"]["limits"] == {"cpu": "250m", "memory": "128Mi"}
    assert sidecar["securityContext"]["readOnlyRootFilesystem"] is True
    simulator = spec["containers"][0]
    sim_env = {item["name"]: item.get("value") for item in simulator["env"]}
    assert sim_env["SIMTEST_SUT_ENDPOINT"] == "127.0.0.1:7600"
    # the sidecar takes no simulator slot: the pod still requests exactly one
    assert "simtest.dev/simulator" not in sidecar["resources"]["requests"]


@pytest.mark.parametrize(
    "sut",
    [
        {"name": "idm-driver"},
        {"name": "remote", "external": {"endpoint": "planner.acme.svc:7460"}},
        {"name": "local", "external": {"command": ["{python}", "-m", "x"]}},
    ],
    ids=["in-process", "endpoint", "command"],
)
def test_no_sidecar_without_an_image(sut: dict[str, Any]) -> None:
    spec = rendered(sut)["spec"]
    assert "initContainers" not in spec
    env = {item["name"] for item in spec["containers"][0]["env"]}
    assert "SIMTEST_SUT_ENDPOINT" not in env


def test_the_runner_gets_the_sidecar_settings_in_domain_units() -> None:
    domain = converting.sut(environment.SutConfig.model_validate(SIDECAR))
    external = domain.external
    assert external is not None
    assert external.launch is Launch.SIDECAR
    assert external.step_deadline == pytest.approx(0.04)
    assert external.startup_timeout == 30.0
    assert dict(external.config) == {"mode": "urban"}
    assert external.port == 7600


def test_in_the_ros2_template_the_sidecar_joins_the_stacks_dds_domain() -> None:
    """The ROS 2 bridge as the sidecar gets the stack's ROS_DOMAIN_ID and a Cyclone DDS
    configuration with the stack's Services as unicast peers (what the K8s-ROS chart gives the
    stack), ahead of the campaign's env; the default template adds neither."""
    bridge = {
        "name": "acme-stack",
        "version": "3.1.0",
        "external": {
            "image": "ghcr.io/simtest-dev/simtest-runner:0.1.0",
            "command": ["simtest-ros2-bridge", "--port", "{port}"],
        },
    }
    spec = rendered(bridge, "ros2")["spec"]
    (sidecar,) = spec["initContainers"]
    env = {item["name"]: item["value"] for item in sidecar["env"]}
    domain = {item["name"]: item.get("value") for item in spec["containers"][0]["env"]}
    assert env["ROS_DOMAIN_ID"] == domain["ROS_DOMAIN_ID"]
    uri = env["CYCLONEDDS_URI"]
    assert "<AllowMulticast>false</AllowMulticast>" in uri
    assert "<ParticipantIndex>auto</ParticipantIndex>" in uri
    environment = rendered(bridge, "ros2")["metadata"]["name"]  # the releases derive from it
    for component in ("control", "evaluator", "perception", "planning"):
        assert f'<Peer Address="{environment}-{component}"/>' in uri
    plain = rendered(bridge, "default")["spec"]["initContainers"][0]["env"]
    assert not {"ROS_DOMAIN_ID", "CYCLONEDDS_URI"} & {item["name"] for item in plain}
