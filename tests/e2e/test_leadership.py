"""Two operator replicas with leader election, end to end on the dev control plane (kwok nodes).

Covers: the first replica takes the Lease and the second follows (and acts on nothing); the
leader is killed with SIGKILL mid-campaign; the follower takes over within the lease duration
(plus one retry period) of its last observation, says so in its log, and completes the campaign
with every scenario exactly once (attempts 1, every pod of attempt 1, no scenario with two
results). The measured takeover time is printed for docs/operator.md.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from kubernetes import client

from tests.e2e import support

LEASE = "simtest-operator"


def _replica(
    name: str, *, kubeconfig: Path, namespace: str, tmp_path: Path, sources: Path
) -> support.OperatorProcess:
    workdir = tmp_path / name
    workdir.mkdir()
    return support.OperatorProcess(
        kubeconfig=kubeconfig,
        namespace=namespace,
        templates=support.templates_root(tmp_path),
        sources=sources,
        workdir=workdir,
        extra_env={
            "SIMTEST_OPERATOR_LEADER_ELECTION": "true",
            "SIMTEST_OPERATOR_IDENTITY": name,
        },
    )


@pytest.fixture
def replicas(
    kubeconfig_path: Path, k8s_namespace: str, tmp_path: Path, sources: Path
) -> Iterator[tuple[support.OperatorProcess, support.OperatorProcess]]:
    pair = tuple(
        _replica(
            name,
            kubeconfig=kubeconfig_path,
            namespace=k8s_namespace,
            tmp_path=tmp_path,
            sources=sources,
        )
        for name in ("replica-a", "replica-b")
    )
    try:
        yield pair  # type: ignore[misc]
    finally:
        for process in pair:
            process.stop()


def _holder(cluster: support.Cluster) -> str:
    try:
        lease: Any = client.CoordinationV1Api(cluster.api).read_namespaced_lease(
            LEASE, cluster.namespace
        )
    except client.exceptions.ApiException as exc:
        if exc.status == 404:
            return ""
        raise
    return str(lease.spec.holder_identity or "")


def _wait(predicate: Any, *, timeout: float, what: str, logs: Any) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.2)
    raise AssertionError(f"not reached within {timeout}s: {what}\n{logs()}")


def test_follower_takes_over_a_killed_leader_and_duplicates_nothing(
    replicas: tuple[support.OperatorProcess, support.OperatorProcess],
    cluster: support.Cluster,
    sources: Path,
) -> None:
    leader, follower = replicas

    def logs() -> str:
        return "\n".join(p.log_text()[-4000:] for p in replicas)

    support.scenario_files(sources / "scenarios", [f"pass-{i:02d}.xosc" for i in range(16)])
    seen: set[str] = set()
    leader.start()
    _wait(lambda: _holder(cluster) == "replica-a", timeout=60, what="a leads", logs=logs)
    follower.start()
    _wait(
        lambda: "held by replica-a: following" in follower.log_text(),
        timeout=60,
        what="b follows",
        logs=logs,
    )
    cluster.create(support.campaign("ha", execution={"maxParallel": 3, "batchSize": 5}))
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and cluster.status("ha").get("passed", 0) < 3:
        seen.update(p.metadata.name for p in cluster.pods())
        time.sleep(0.2)
    assert cluster.status("ha").get("passed", 0) >= 3, logs()
    assert "acquired" not in follower.log_text(), logs()

    leader.stop(kill=True)
    killed = time.monotonic()
    while _holder(cluster) != "replica-b":
        seen.update(p.metadata.name for p in cluster.pods())
        assert time.monotonic() - killed < 60, f"no takeover within 60s\n{logs()}"
        time.sleep(0.2)
    takeover = time.monotonic() - killed
    status = cluster.wait_complete(
        "ha",
        timeout=120,
        alive=follower.alive,
        during=lambda: seen.update(p.metadata.name for p in cluster.pods()),
    )
    print(f"takeover after SIGKILL: {takeover:.1f}s")  # the figure in docs/operator.md

    results = cluster.results("ha")  # fails on a scenario with two results
    assert status["phase"] == "Succeeded", logs()
    assert status["passed"] == 16 and status["total"] == 16 and len(results) == 16
    assert {r["attempts"] for r in results.values()} == {1}, results
    assert all(name.endswith("-a1") for name in seen), sorted(seen)
    # client-go timing: lease duration 15 s after the follower's last observation (every 2 s)
    assert 10 <= takeover <= 15 + 2 + 5, takeover
    assert "acquired by replica-b, taking over from replica-a: leading" in follower.log_text()
