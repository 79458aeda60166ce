"""An external system under test as a sidecar in real pods: the Go SUT image beside the simulator.

Covers: a campaign whose ``spec.environment.sut.external.image`` is the Go SUT
(``deploy/sut-go``, OSI protobuf over the SUT protocol) runs on the real node — each simulator pod
starts the SUT as a native sidecar (init container ``sut``, ``restartPolicy: Always``, TCP startup
probe) before the simulator, and the verdicts equal the built-in model's local ones (the cut-in at
8 m fails) and each result names the SUT image by the ``imageID`` the kubelet reported for the
sidecar (the same name ``simtest run`` gives it from the build index); the SUT killed mid-run
(SIGKILL from the node) makes that run ``Error`` naming the SUT — whose fault it was — and the
retry passes.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from kubernetes import client

from simtest_operator import provenance
from simtest_operator.devcluster import images
from simtest_operator.devcluster.state import ClusterInfo
from simtest_operator.settings import Settings
from tests.e2e import support

EXAMPLE = support.REPO / "scenarios" / "external-sut-go-campaign.yaml"
CUT_INS = {
    "cut-in_highway_v25_gap30_dv5.xosc": "Passed",
    "cut-in_highway_v30_gap8_dv12.xosc": "Failed",
}


def _campaign(tmp_path: Path, name: str, include: list[str], **simulator: Any) -> dict[str, Any]:
    body: dict[str, Any] = yaml.safe_load(EXAMPLE.read_text())
    body["metadata"]["name"] = name
    spec = body["spec"]
    spec["scenarios"]["include"] = include
    spec["environment"]["simulator"].update(simulator)
    spec["execution"]["resources"] = {"requests": {"cpu": "500m"}}
    assert spec["environment"]["sut"]["external"]["image"] == images.SUT_GO_IMAGE
    return body


def _sut_pids() -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if b"simtest-sut-go" in (entry / "cmdline").read_bytes():
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


_LOOPBACK = ("0100007F:", "0000000000000000FFFF00000100007F:", "00000000000000000000000001000000:")
"""127.0.0.1 in /proc/net/tcp, and as /proc/net/tcp6 shows it (v4-mapped, ::1)."""


def _simulator_connected(pid: int) -> bool:
    """Whether the SUT process holds an established TCP connection from the pod's loopback.

    The simulator reaches its sidecar on 127.0.0.1 (the kubelet's startup probe comes from the
    node, not loopback). Read from the pod's network namespace (``/proc/<pid>/net/tcp`` and
    ``tcp6``: Go listens on 0.0.0.0 with a dual-stack socket; state ``01``, remote loopback) and
    matched to the SUT's file descriptors by socket inode: evidence that the run is under way,
    not a guess of how long start-up takes under load.
    """
    proc = Path("/proc") / str(pid)
    try:
        inodes = {
            link[len("socket:[") : -1]
            for fd in (proc / "fd").iterdir()
            if (link := str(fd.readlink())).startswith("socket:[")
        }
        tables = [(proc / "net" / name).read_text() for name in ("tcp", "tcp6")]
    except OSError:
        return False
    for table in tables:
        for line in table.splitlines()[1:]:
            fields = line.split()
            if (
                len(fields) > 9
                and fields[3] == "01"
                and fields[2].startswith(_LOOPBACK)
                and fields[9] in inodes
            ):
                return True
    return False


def test_the_go_sut_as_a_sidecar_gives_the_local_verdicts(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(_campaign(tmp_path, "sut-go", sorted(CUT_INS)))
    seen: dict[str, Any] = {}
    reported: dict[str, str] = {}  # pod -> the SUT container's imageID, as the kubelet says
    deadline = time.monotonic() + 300
    while not reported:
        assert time.monotonic() < deadline, "no simulator pod with a started SUT appeared"
        for pod in cluster.pods():
            seen[pod.metadata.name] = pod.spec
            for status in (pod.status and pod.status.init_container_statuses) or ():
                if status.name == "sut" and status.image_id:
                    reported[pod.metadata.name] = status.image_id
        time.sleep(0.2)
    cluster.wait_complete("sut-go", timeout=300, alive=real_operator.alive)
    results = cluster.results("sut-go")
    assert {k: v["verdict"] for k, v in results.items()} == CUT_INS, results
    assert all(r["attempts"] == 1 for r in results.values()), results
    # Which SUT produced each result: the image the kubelet ran, verbatim (one image, all pods).
    (image_id,) = set(reported.values())
    assert {r.get("sutImageId") for r in results.values()} == {image_id}, (results, reported)
    # ... and `simtest run` names the same image the same way from the build index.
    index = Settings.from_env().cache.image_index
    assert image_id == provenance.built_image_id(images.SUT_GO_IMAGE, index), (image_id, index)
    (spec,) = list(seen.values())[:1]
    (sidecar,) = spec.init_containers
    assert (sidecar.name, sidecar.image, sidecar.restart_policy) == (
        "sut",
        images.SUT_GO_IMAGE,
        "Always",
    )
    assert sidecar.startup_probe is not None and sidecar.startup_probe.tcp_socket is not None


@pytest.mark.parametrize(
    "operator_env", [{"SIMTEST_OPERATOR_KEEP_ENVIRONMENTS": "true"}], indirect=True
)
def test_a_sut_killed_mid_run_is_error_naming_the_sut_then_retried(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    body = _campaign(
        tmp_path, "sut-killed", ["cut-in_highway_v25_gap30_dv5.xosc"], realTimeFactor=1.0
    )
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(body)
    deadline = time.monotonic() + 180
    while not (pids := _sut_pids()):
        assert time.monotonic() < deadline, "the SUT never started"
        time.sleep(0.2)
    # Kill only once the simulator is connected: a SUT killed before that is restarted by the
    # kubelet (restartPolicy Always) and the run would pass against the new one.
    while not any(_simulator_connected(pid) for pid in pids):
        assert time.monotonic() < deadline, "the simulator never connected to the SUT"
        time.sleep(0.05)
        pids = _sut_pids() or pids
    for pid in pids:
        os.kill(pid, signal.SIGKILL)
    # The first attempt's SimEnvironment keeps its verdict (environments kept for the test).
    first: dict[str, Any] = {}
    deadline = time.monotonic() + 120
    while not first:
        assert time.monotonic() < deadline, "the killed attempt never ended"
        for env in cluster.items("simenvironments"):
            for result in (env.get("status") or {}).get("results") or []:
                if result.get("attempts") == 1:
                    first = result
        time.sleep(0.1)
    assert first["verdict"] == "Error", first
    assert "SUT" in first["reason"], first
    cluster.wait_complete("sut-killed", timeout=300, alive=real_operator.alive)
    (result,) = cluster.results("sut-killed").values()
    assert result["verdict"] == "Passed", result
    assert result["attempts"] == 2, result
