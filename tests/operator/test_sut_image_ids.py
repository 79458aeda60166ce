"""Which SUT image produced a result: the kubelet's ``imageID`` of the SUT container, carried
from the pod status into the SimEnvironment and ScenarioBatch results and the results database.

Covers: a pod status shaped as a real kubelet (1.29+, containerd) writes it for a native sidecar
(``initContainerStatuses[name=sut]``) with the registry form ``repo@sha256:…``, the bare
``sha256:…`` form (an image the runtime knows no registry digest of), cri-dockerd's
``docker-pullable://`` prefix, the SUT as a plain container, no SUT, an image still being pulled
(empty ``imageID``); the runner's verdicts and the operator's own (a pod that died) both name the
image; the records keep it on the wire (SimEnvironment status -> ScenarioBatch status); the
recorder merges it into the rows the pods wrote when the campaign finishes
(tests/operator/test_recording_results.py).
"""

from __future__ import annotations

import datetime
import json
from typing import Any

import pytest
import yaml

from simtest_operator.operator import environments, observed
from simtest_operator.operator.status import environmentstatus
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.verdicts import Verdict

SUT_DIGEST = "sha256:" + "5e" * 32
REGISTRY_FORM = f"ghcr.io/simtest-dev/simtest-sut-go@{SUT_DIGEST}"
BARE_FORM = "sha256:" + "c0" * 32

# The status of a finished simulator pod with the Go SUT as a native sidecar, as a containerd
# kubelet reports it (fields and shapes from `kubectl get pod -o yaml` on the real node).
POD = f"""
apiVersion: v1
kind: Pod
metadata:
  name: c-b00000-e000-a1
  namespace: ns
  uid: 7d0c1f2e-0000-4000-8000-000000000001
  creationTimestamp: "2030-01-01T00:00:00Z"
  labels: {{simtest.dev/campaign: c}}
spec:
  nodeName: n0
status:
  phase: Succeeded
  hostIP: 10.0.2.15
  podIP: 10.88.0.7
  qosClass: Burstable
  startTime: "2030-01-01T00:00:01Z"
  conditions:
  - {{type: PodReadyToStartContainers, status: "False", lastTransitionTime: "2030-01-01T00:00:13Z"}}
  - {{type: Initialized, status: "True", lastTransitionTime: "2030-01-01T00:00:02Z"}}
  - {{type: Ready, status: "False", lastTransitionTime: "2030-01-01T00:00:12Z"}}
  - {{type: PodScheduled, status: "True", lastTransitionTime: "2030-01-01T00:00:01Z"}}
  initContainerStatuses:
  - name: sut
    containerID: containerd://9b1f0e6c2a4d
    image: ghcr.io/simtest-dev/simtest-sut-go:0.1.0
    imageID: {REGISTRY_FORM}
    ready: false
    restartCount: 0
    started: false
    state:
      terminated:
        containerID: containerd://9b1f0e6c2a4d
        exitCode: 0
        reason: Completed
        startedAt: "2030-01-01T00:00:01Z"
        finishedAt: "2030-01-01T00:00:13Z"
  containerStatuses:
  - name: simulator
    containerID: containerd://51aa07e3c9f8
    image: ghcr.io/simtest-dev/simtest-runner:0.1.0
    imageID: ghcr.io/simtest-dev/simtest-runner@sha256:{"ab" * 32}
    ready: false
    restartCount: 0
    started: false
    state:
      terminated:
        containerID: containerd://51aa07e3c9f8
        exitCode: 0
        reason: Completed
        message: '{{"scenarioId": "a.xosc", "verdict": "Failed", "reason": "Ego collided"}}'
        startedAt: "2030-01-01T00:00:02Z"
        finishedAt: "2030-01-01T00:00:12Z"
"""


NOW = datetime.datetime(2030, 1, 1, 0, 0, 20, tzinfo=datetime.UTC)
LIMITS = environments.Limits(
    timeout_seconds=60,
    pending_seconds=300,
    deadline_seconds=90,
    backstop_grace=30,
    missing_grace=10,
)
ENV = observed.environment_view(
    {
        "metadata": {"name": "c-b00000-e000-a1", "namespace": "ns", "uid": "u",
                     "creationTimestamp": "2030-01-01T00:00:00Z"},
        "spec": {"campaign": "c", "batch": "c-b00000", "attempt": 1,
                 "scenarios": [{"id": "a.xosc", "source": "file:///a.xosc", "sha256": "0" * 64}]},
        "status": {"pod": "c-b00000-e000-a1"},
    }
)  # fmt: skip


def assess(body: dict[str, Any]) -> environments.Assessment:
    return environments.assess(ENV, observed.pod_view(body), nodes={}, now=NOW, limits=LIMITS)


def kubelet_pod(image_id: str | None = REGISTRY_FORM, *, sidecar: bool = True) -> dict[str, Any]:
    body: dict[str, Any] = yaml.safe_load(POD)
    status = body["status"]
    (sut,) = status.pop("initContainerStatuses")
    if image_id is None:
        return body
    sut["imageID"] = image_id
    if sidecar:
        status["initContainerStatuses"] = [sut]
    else:
        status["containerStatuses"].append(sut)
    return body


@pytest.mark.parametrize(
    ("reported", "recorded"),
    [
        (REGISTRY_FORM, REGISTRY_FORM),
        (f"docker.io/library/planner@{SUT_DIGEST}", f"docker.io/library/planner@{SUT_DIGEST}"),
        (BARE_FORM, BARE_FORM),
        (
            f"docker-pullable://ghcr.io/acme/planner@{SUT_DIGEST}",
            f"ghcr.io/acme/planner@{SUT_DIGEST}",
        ),
        (f"docker://{BARE_FORM}", BARE_FORM),
        ("", ""),  # the kubelet has not resolved the image yet (ErrImagePull, pulling)
        ("ghcr.io/acme/planner:2.1.0", ""),  # not an image id: never recorded as one
    ],
)
def test_the_pod_view_reads_the_sidecars_image_id(reported: str, recorded: str) -> None:
    assert observed.pod_view(kubelet_pod(reported)).sut_image_id == recorded


def test_a_sut_as_a_plain_container_or_no_sut() -> None:
    assert observed.pod_view(kubelet_pod(BARE_FORM, sidecar=False)).sut_image_id == BARE_FORM
    view = observed.pod_view(kubelet_pod(None))
    assert view.sut_image_id == ""
    assert view.container.state == "terminated"  # the simulator container is still the one read


@pytest.mark.parametrize("image_id", [REGISTRY_FORM, BARE_FORM])
def test_the_runners_verdict_names_the_image_through_to_the_batch(image_id: str) -> None:
    result = assess(kubelet_pod(image_id))
    assert result.results is not None
    (record,) = result.results
    assert (record.verdict, record.sut_image_id) == (Verdict.FAILED, image_id)
    status = environmentstatus.desired_status(ENV, result)  # SimEnvironment status
    (wire,) = status["results"]
    assert wire["sutImageId"] == image_id
    assert ResultRecord.from_wire(json.loads(json.dumps(wire))) == record  # read back for the batch


def test_an_environment_verdict_of_a_pod_that_died_names_the_image_too() -> None:
    body = kubelet_pod(BARE_FORM)
    status = body["status"]
    status["phase"] = "Running"
    status["containerStatuses"][0]["state"] = {"running": {"startedAt": "2030-01-01T00:00:02Z"}}
    body["metadata"]["deletionTimestamp"] = "2030-01-01T00:00:05Z"
    status["conditions"].append(
        {"type": "DisruptionTarget", "status": "True", "reason": "EvictionByEvictionAPI"}
    )
    result = assess(body)
    assert result.results is not None
    (record,) = result.results
    assert (record.verdict, record.sut_image_id) == (Verdict.ERROR, BARE_FORM)


def test_without_a_sut_the_records_carry_nothing() -> None:
    result = assess(kubelet_pod(None))
    assert result.results is not None
    assert result.results[0].sut_image_id == ""
    assert "sutImageId" not in result.results[0].to_wire()
