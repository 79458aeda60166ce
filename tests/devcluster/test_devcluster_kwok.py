"""kwok plays kubelet on the fake nodes, driven by ``simtest.dev/fake-*`` pod annotations.

Covers: a pod finishes Succeeded after its ``simtest.dev/fake-duration`` with the
``simtest.dev/fake-termination-message``; a non-zero ``simtest.dev/fake-exit-code`` gives Failed
with that code; a pod without a duration keeps running; a Job's pod completes and the real job
controller marks the Job complete.
"""

from __future__ import annotations

import time
from typing import Any

import pytest
from kubernetes import client
from tests.devcluster.podspecs import eventually, simulator_pod

pytestmark = pytest.mark.cluster

DURATION = 3.0


def _terminated(pod: client.V1Pod) -> client.V1ContainerStateTerminated:
    state = pod.status.container_statuses[0].state
    assert state.terminated is not None, state
    return state.terminated


def test_annotated_pods_finish_after_their_duration(
    k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    core = client.CoreV1Api(k8s_api_client)
    pods: dict[str, Any] = {
        "ok": simulator_pod(
            "ok",
            annotations={
                "simtest.dev/fake-duration": f"{DURATION:.0f}s",
                "simtest.dev/fake-termination-message": "scenario done: 0 collisions",
            },
        ),
        "crash": simulator_pod(
            "crash",
            annotations={
                "simtest.dev/fake-duration": "1s",
                "simtest.dev/fake-exit-code": "3",
                "simtest.dev/fake-termination-message": "simulator crashed",
            },
        ),
        "forever": simulator_pod("forever"),
    }
    for body in pods.values():
        core.create_namespaced_pod(k8s_namespace, body)
    read = lambda name: core.read_namespaced_pod(name, k8s_namespace)  # noqa: E731
    eventually(lambda: read("ok").status.phase == "Running", timeout=30, what="'ok' Running")
    running_seen = time.monotonic()

    ok = eventually(
        lambda: (p := read("ok")).status.phase == "Succeeded" and p,
        timeout=DURATION + 20,
        what="'ok' Succeeded",
    )
    finished_seen = time.monotonic()
    terminated = _terminated(ok)
    assert terminated.exit_code == 0
    assert terminated.reason == "Completed"
    assert terminated.message == "scenario done: 0 collisions"
    # The API stores times with 1 s resolution; the poll clock is exact but starts late.
    assert (terminated.finished_at - ok.status.start_time).total_seconds() >= DURATION - 1
    assert finished_seen - running_seen >= DURATION - 1

    crash = eventually(
        lambda: (p := read("crash")).status.phase == "Failed" and p,
        timeout=20,
        what="'crash' Failed",
    )
    terminated = _terminated(crash)
    assert terminated.exit_code == 3
    assert terminated.reason == "Error"
    assert terminated.message == "simulator crashed"

    assert read("forever").status.phase == "Running"


def test_job_pod_completes_and_job_controller_marks_the_job_complete(
    k8s_api_client: client.ApiClient, k8s_namespace: str
) -> None:
    batch = client.BatchV1Api(k8s_api_client)
    pod = simulator_pod("unused")
    job: Any = {
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": {"name": "one-shot"},
        "spec": {"backoffLimit": 0, "template": {"spec": pod["spec"]}},
    }
    batch.create_namespaced_job(k8s_namespace, job)
    done = eventually(
        lambda: (j := batch.read_namespaced_job("one-shot", k8s_namespace)).status.succeeded and j,
        timeout=45,
        what="Job one-shot succeeded",
    )
    assert any(c.type == "Complete" and c.status == "True" for c in done.status.conditions)
