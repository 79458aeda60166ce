"""Warm simulators (``isolation: Reuse``) in real containers, and pods the kubelet stops.

Covers: one warm pod runs a queue of three real scenarios through the forked, reset-verified path
and reports each as it finishes (a ``finished <id>`` line in the log, the termination message
rewritten); the container killed outright (SIGKILL from the node) after the first scenario —
the finished verdict is kept, the interrupted and the unstarted scenarios are ``Error`` and
retried, each scenario ends with exactly one final result; a runner frozen in place (SIGSTOP:
nothing in the pod can react) is ended by the kubelet's ``activeDeadlineSeconds`` — the scenario
it froze in is ``Timeout`` through ``DeadlineExceeded``, the one it finished before stays.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable
from pathlib import Path

import yaml
from kubernetes import client

from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.realnode.conftest import smoke_variant

HIGHWAY = "*_highway_*.xosc"
"""Three smoke scenarios in one batch (sorted): a cut-in that passes, one the driver model cannot
avoid (Failed), a following scenario that passes."""
EXPECTED = {
    "cut-in_highway_v25_gap30_dv5.xosc": "Passed",
    "cut-in_highway_v30_gap8_dv12.xosc": "Failed",
    "following_highway_v25_thw2_drop5_d2.xosc": "Passed",
}
FIRST = "cut-in_highway_v25_gap30_dv5.xosc"


def _runner_pids(pod: str) -> list[int]:
    """Host PIDs of the pod's runner processes (the warm parent and its forked worker)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes()
            environ = (entry / "environ").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"simtest-runner" in cmdline and f"HOSTNAME={pod}".encode() in environ:
            found.append(int(entry.name))
    return sorted(found)


def _parent_of(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("PPid:"):
            return int(line.split()[1])
    raise AssertionError(f"no PPid for {pid}")


def _when_first_finished(
    cluster: support.Cluster, core: client.CoreV1Api, namespace: str, alive: Callable[[], bool]
) -> str:
    """The name of the warm pod once its log says the first scenario finished."""
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        assert alive(), "the operator died"
        for pod in cluster.pods():
            statuses = pod.status.container_statuses or []
            if not (statuses and statuses[0].state.running):
                continue
            log = core.read_namespaced_pod_log(pod.metadata.name, namespace, container="simulator")
            if f"finished {FIRST}" in log:
                return str(pod.metadata.name)
        time.sleep(0.3)
    raise AssertionError("the warm pod never reported its first scenario")


def _warm_campaign(tmp_path: Path, name: str, **execution: object) -> dict[str, object]:
    path = smoke_variant(
        tmp_path,
        name,
        HIGHWAY,
        simulator={"realTimeFactor": 2.0},  # about 5 s of wall time per scenario
        isolation="Reuse",
        batchSize=3,
        maxSimulatorsPerNode=1,  # one slot: all three in one warm queue (queues follow slots)
        resources={"requests": {"cpu": "500m"}},
        **execution,
    )
    body: dict[str, object] = yaml.safe_load(path.read_text())
    return body


def test_a_warm_pod_killed_mid_queue_keeps_what_finished_and_retries_the_rest(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(_warm_campaign(tmp_path, "warm-killed", retries=1, timeoutSeconds=60))
    core = client.CoreV1Api(real_api_client)
    pod = _when_first_finished(cluster, core, real_namespace, real_operator.alive)
    pids = _runner_pids(pod)
    assert len(pids) == 2, f"expected the warm parent and one forked worker, found {pids}"
    (parent,) = [pid for pid in pids if _parent_of(pid) not in pids]
    os.kill(parent, signal.SIGKILL)  # the container's first process: the whole pod dies
    status = cluster.wait_complete("warm-killed", timeout=240, alive=real_operator.alive)
    results = cluster.results("warm-killed")
    assert {k: v["verdict"] for k, v in results.items()} == EXPECTED
    assert results[FIRST]["attempts"] == 1, "the finished scenario must not run again"
    for scenario in set(EXPECTED) - {FIRST}:
        assert results[scenario]["attempts"] == 2, results[scenario]
    assert status["total"] == 3


def test_a_frozen_warm_pod_ends_at_its_deadline_and_keeps_what_finished(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    body = _warm_campaign(tmp_path, "warm-frozen", retries=0, timeoutSeconds=10)
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(body)
    core = client.CoreV1Api(real_api_client)
    pod = _when_first_finished(cluster, core, real_namespace, real_operator.alive)
    for pid in _runner_pids(pod):
        os.kill(pid, signal.SIGSTOP)  # nothing inside the pod can notice, let alone report
    cluster.wait_complete("warm-frozen", timeout=240, alive=real_operator.alive)
    results = cluster.results("warm-frozen")
    ordered = [results[k] for k in sorted(EXPECTED)]
    assert [r["verdict"] for r in ordered] == ["Passed", "Timeout", "Error"], ordered
    assert "activeDeadlineSeconds" in ordered[1]["reason"], ordered[1]
    assert ordered[2]["reason"].startswith("not run"), ordered[2]
