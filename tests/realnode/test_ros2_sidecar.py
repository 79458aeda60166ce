"""A ROS 2-style stack drives the ego on the real node: the stack and the ROS 2 bridge are
sidecars of each simulator pod (template ``ros2``, ``stack.placement: pod``), DDS between them
on the pod's loopback.

Covers: the smoke campaign behind the bridge and the same driving logic behind the OSI protocol
(the reference SUT as a sidecar) give the same verdict and reason, scenario by scenario, both in
warm pods (``isolation: Reuse``, three scenarios each) under the kubelet; each scenario's
``sut.log`` artifact holds what the stack and the bridge printed during that scenario, and only
that (the stack starts a run per scenario, so its log has one run line), and its result lists it
as ``sutLog``; each pod had the stack as a sidecar started before the bridge, both native
sidecars with the restricted security context.

The stack is ``tests/sut/ros2_stack.py`` (an independent DDS participant, no bridge code), run by
the runner image's Python (which has ``cyclonedds``, ``rosbags`` and the driver model): its
source goes in through the container's environment, so no image of its own has to be built.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster import images
from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.realnode.conftest import SCENARIOS, host_path_claim

STACK = Path(__file__).parents[1] / "sut" / "ros2_stack.py"
SMOKE = SCENARIOS / "smoke-campaign.yaml"
LOADER = "import os; exec(compile(os.environ['SIMTEST_TEST_STACK'], 'ros2_stack.py', 'exec'))"
"""Runs the stack's source from the environment as ``__main__`` (``sys.argv[1:]`` its args)."""
STEP_DEADLINE_MS = 2000
"""Per step: the Python stack on a loaded two-core machine (p50 a few ms; a deadline that a slow
moment misses would turn a verdict into Error, and this test is about verdicts)."""


def _campaign(
    base: Path, name: str, sut: dict[str, Any], batch: int, **environment: Any
) -> dict[str, Any]:
    """``base``'s scenarios and criteria in warm pods of ``batch`` scenarios, artifacts on the
    claim ``artifacts``, no retries (an Error shows)."""
    body: dict[str, Any] = yaml.safe_load(base.read_text())
    body["metadata"]["name"] = name
    spec = body["spec"]
    spec["environment"]["sut"].update(sut)
    spec["environment"].update(environment)
    spec["environment"].setdefault("simulator", {})["record"] = False
    spec["execution"].update(
        isolation="Reuse",
        batchSize=batch,
        retries=0,
        timeoutSeconds=120,
        resources={"requests": {"cpu": "500m"}},
    )
    spec["artifacts"] = {"pvc": {"claimName": "artifacts", "subPath": "runs"}}
    return body


def osi_campaign(base: Path = SMOKE, batch: int = 3) -> dict[str, Any]:
    """``base`` with the reference SUT (the driver model behind the OSI protocol) as sidecar."""
    return _campaign(
        base,
        "osi",
        {
            "name": "reference-sut",
            "external": {
                "image": images.RUNNER_IMAGE,
                "command": ["{python}", "-m", "simtest_operator.sut.reference", "--port", "{port}"],
                "resources": {"requests": {"cpu": "100m", "memory": "256Mi"}},
                "stepDeadlineMilliseconds": STEP_DEADLINE_MS,
                "startupTimeoutSeconds": 60,
            },
        },
        batch,
    )


def ros2_campaign(base: Path = SMOKE, batch: int = 3) -> dict[str, Any]:
    """``base`` with the test stack (the same driver model over DDS) and the bridge in the pod."""
    control = {
        "command": ["python", "-c", LOADER],
        # The kubelet expands $(ROS_DOMAIN_ID) from the container's environment (the template's).
        "args": ["--domain-id", "$(ROS_DOMAIN_ID)"],
        "env": {"SIMTEST_TEST_STACK": STACK.read_text()},
        "resources": {"requests": {"cpu": "100m", "memory": "256Mi"}, "limits": {"memory": "1Gi"}},
    }
    off = {"enabled": False}
    return _campaign(
        base,
        "ros2",
        {
            "name": "ros2-test-stack",
            "image": images.RUNNER_IMAGE,  # the stack's image: the runner's Python
            "external": {
                "image": images.RUNNER_IMAGE,
                "command": ["simtest-ros2-bridge", "--port", "{port}"],
                "resources": {"requests": {"cpu": "100m", "memory": "256Mi"}},
                "stepDeadlineMilliseconds": STEP_DEADLINE_MS,
                "startupTimeoutSeconds": 120,  # READY waits for the stack's nodes
            },
        },
        batch,
        template="ros2",
        values={
            "stack": {
                "placement": "pod",
                "components": {
                    "perception": off,
                    "planning": off,
                    "evaluator": off,
                    "control": {"chartValues": control},
                },
            }
        },
    )


@pytest.fixture
def artifacts(
    real_api_client: client.ApiClient, real_namespace: str, tmp_path: Path
) -> Iterator[Path]:
    """The campaigns' artifacts claim: a hostPath volume the test reads the sut.log files from."""
    folder = tmp_path / "artifacts-volume"
    folder.mkdir()
    folder.chmod(0o1777)  # the pods run as 65532; hostPath volumes get no fsGroup ownership
    with host_path_claim(
        real_api_client, real_namespace, claim="artifacts", folder=folder, access="ReadWriteMany"
    ):
        yield folder


@pytest.mark.timeout(1200)
def test_a_ros2_stack_in_the_pod_gives_the_osi_suts_verdicts_and_a_sut_log_per_scenario(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    artifacts: Path,
) -> None:
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(ros2_campaign())
    cluster.create(osi_campaign())  # the two share the node's two simulator slots
    pods: dict[str, Any] = {}
    started = time.monotonic()

    def note_pods() -> None:
        for pod in cluster.pods():
            if pod.metadata.labels.get("simtest.dev/campaign") == "ros2":
                pods[pod.metadata.name] = pod.spec

    cluster.wait_complete("ros2", timeout=900, alive=real_operator.alive, during=note_pods)
    ros2_seconds = time.monotonic() - started
    cluster.wait_complete("osi", timeout=600, alive=real_operator.alive)
    behind_ros2, behind_osi = cluster.results("ros2"), cluster.results("osi")

    assert len(behind_osi) == 6, behind_osi
    assert sorted(r["verdict"] for r in behind_osi.values()).count("Failed") == 1, behind_osi
    assert {k: (r["verdict"], r.get("reason")) for k, r in behind_ros2.items()} == {
        k: (r["verdict"], r.get("reason")) for k, r in behind_osi.items()
    }, (behind_ros2, behind_osi, f"ros2 campaign took {ros2_seconds:.0f} s")

    assert pods, "no simulator pod seen"
    for spec in pods.values():
        names = [c.name for c in spec.init_containers]
        assert names == ["stack-control", "sut"], names
        for sidecar in spec.init_containers:
            assert sidecar.restart_policy == "Always"
            assert sidecar.security_context.read_only_root_filesystem

    for scenario, result in behind_ros2.items():
        assert result["artifacts"]["sutLog"].endswith(f"/{scenario}/sut.log"), result
        (log,) = (artifacts / "runs" / "ros2").glob(f"**/{scenario}/sut.log")
        text = log.read_text()
        sections = _sections(text)
        assert set(sections) == {"stack-control", "sut"}, text
        runs = [line for line in sections["stack-control"] if line.startswith("stack: run from")]
        assert len(runs) == 1, text  # this scenario's run, not its neighbours'
        # The bridge's HELLO line of this run and of no other (a previous run's last line,
        # printed as the run closed, may come first: the log starts where the last one ended).
        ready = [line for line in sections["sut"] if "the stack is there" in line]
        assert [f"run {scenario}:" in line for line in ready] == [True], text
        assert "Traceback" not in text, text


def _sections(text: str) -> dict[str, list[str]]:
    """The sut.log's lines by container (``==> name <==`` headers)."""
    found: dict[str, list[str]] = {}
    current: list[str] = []
    for line in text.splitlines():
        if line.startswith("==> ") and line.endswith(" <=="):
            current = found.setdefault(line[4:-4], [])
        else:
            current.append(line)
    return found
