"""Faults, end to end on the dev control plane with kwok nodes: every scenario still ends with
exactly one final verdict, and nothing runs twice except a retry of an Error.

Covers: a simulator pod deleted mid-run (Error, retried as attempt 2); the operator killed with
SIGKILL mid-campaign and restarted (no scenario lost, none started twice); a node deleted while
its pods run (node lost -> Error -> retried elsewhere); 409 conflicts from a concurrent writer
bumping the batches' resourceVersion while the operator records results.
"""

from __future__ import annotations

import contextlib
import threading
import time
from typing import Any

from kubernetes import client

from simtest_operator.devcluster.nodes import NodeShape, node_manifest
from tests.e2e import support


def _pod_names(cluster: support.Cluster, seen: set[str]) -> None:
    seen.update(p.metadata.name for p in cluster.pods())


def _unfinished_on(cluster: support.Cluster, node: str) -> set[str]:
    return {
        p.metadata.name
        for p in cluster.pods()
        if p.spec.node_name == node and p.status.phase not in ("Succeeded", "Failed")
    }


def test_deleted_pod_is_retried_once(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: support.Path
) -> None:
    support.scenario_files(sources / "scenarios", [f"slow-{i}.xosc" for i in range(4)])
    with support.running(operator):
        cluster.create(support.campaign("delpod", execution={"maxParallel": 4}))
        victim = None
        deadline = time.monotonic() + 60
        while victim is None and time.monotonic() < deadline:
            running = [p for p in cluster.pods() if p.status.phase == "Running"]
            if running:
                victim = running[0].metadata.name
                cluster.core.delete_namespaced_pod(
                    victim, cluster.namespace, grace_period_seconds=0
                )
            time.sleep(0.2)
        assert victim is not None
        status = cluster.wait_complete("delpod", timeout=60, alive=operator.alive)
    results = cluster.results("delpod")
    assert status["passed"] == 4 and len(results) == 4
    retried = {k: r for k, r in results.items() if r["attempts"] == 2}
    assert len(retried) == 1 and all(r["verdict"] == "Passed" for r in results.values())


def test_operator_killed_and_restarted(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: support.Path
) -> None:
    support.scenario_files(sources / "scenarios", [f"pass-{i:02d}.xosc" for i in range(16)])
    seen: set[str] = set()
    operator.start()
    try:
        cluster.create(support.campaign("restart", execution={"maxParallel": 3, "batchSize": 5}))
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and cluster.status("restart").get("passed", 0) < 4:
            _pod_names(cluster, seen)
            time.sleep(0.2)
        operator.stop(kill=True)
        for _ in range(12):  # pods keep finishing while nobody watches
            _pod_names(cluster, seen)
            time.sleep(0.25)
        operator.start()
        status = cluster.wait_complete(
            "restart", timeout=90, alive=operator.alive, during=lambda: _pod_names(cluster, seen)
        )
    finally:
        operator.stop()
    results = cluster.results("restart")
    assert status["passed"] == 16 and status["total"] == 16 and len(results) == 16
    assert {r["attempts"] for r in results.values()} == {1}
    assert all(name.endswith("-a1") for name in seen), sorted(seen)
    assert len(operator.logs) == 2


def test_node_deleted_while_its_pods_run(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: support.Path
) -> None:
    pool = cluster.namespace
    names = [f"simtest-node-{pool}-{i}" for i in range(2)]
    for name in names:
        body: dict[str, Any] = node_manifest(name, NodeShape(simulator_slots=2))
        body["metadata"]["labels"]["simtest.dev/pool"] = pool
        cluster.core.create_node(body=body)
    support.scenario_files(sources / "scenarios", [f"slow-{i}.xosc" for i in range(4)])
    try:
        with support.running(operator):
            cluster.create(
                support.campaign(
                    "nodeloss",
                    execution={
                        "maxParallel": 4,
                        "nodeSelector": {"simtest.dev/pool": pool},
                        "pendingTimeoutSeconds": 60,
                    },
                )
            )
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                on_victim = [
                    p
                    for p in cluster.pods()
                    if p.spec.node_name == names[0] and p.status.phase == "Running"
                ]
                if on_victim:
                    break
                time.sleep(0.2)
            assert on_victim
            # every unfinished pod bound to the node is lost with it, running or not yet
            lost = _unfinished_on(cluster, names[0])
            cluster.core.delete_node(names[0])
            lost |= _unfinished_on(cluster, names[0])
            status = cluster.wait_complete("nodeloss", timeout=90, alive=operator.alive)
    finally:
        for name in names:
            with contextlib.suppress(client.exceptions.ApiException):
                cluster.core.delete_node(name)
    results = cluster.results("nodeloss")
    assert status["passed"] == 4 and len(results) == 4
    retried = sum(1 for r in results.values() if r["attempts"] == 2)
    assert retried == len(lost), (sorted(lost), results)


def test_conflicting_writers(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: support.Path
) -> None:
    # slow scenarios (6 s each, two rounds of 6) keep results arriving for ~12 s, so the writer
    # below overlaps many of the operator's status writes even on a loaded machine
    support.scenario_files(sources / "scenarios", [f"slow-{i:02d}.xosc" for i in range(12)])
    stop = threading.Event()
    bumps = [0]

    def meddle() -> None:
        names: list[str] = []
        listed = 0.0
        while not stop.is_set():
            if time.monotonic() - listed > 0.5:  # batches are created lazily: look again
                names = [b["metadata"]["name"] for b in cluster.items("scenariobatches")]
                listed = time.monotonic()
            for name in names:
                patch = {"metadata": {"annotations": {"test/bump": str(time.monotonic())}}}
                try:
                    cluster.custom.patch_namespaced_custom_object(
                        support.GROUP,
                        support.VERSION,
                        cluster.namespace,
                        "scenariobatches",
                        name,
                        patch,
                    )
                    bumps[0] += 1
                except client.exceptions.ApiException:
                    pass
            if not names:
                time.sleep(0.05)

    meddlers = [threading.Thread(target=meddle, daemon=True) for _ in range(2)]
    with support.running(operator):
        cluster.create(support.campaign("conflicts", execution={"maxParallel": 6, "batchSize": 6}))
        for meddler in meddlers:
            meddler.start()
        try:
            status = cluster.wait_complete("conflicts", timeout=120, alive=operator.alive)
        finally:
            stop.set()
            for meddler in meddlers:
                meddler.join()
    results = cluster.results("conflicts")
    log = operator.log_text()
    conflicts = log.count("planning again from fresh state")
    summary = f"status={status} bumps={bumps[0]} conflicts={conflicts}"
    assert status["passed"] == 12 and len(results) == 12, summary
    assert {r["attempts"] for r in results.values()} == {1}, (summary, results)
    # the point of the test: the concurrent writer really made the operator's writes conflict
    assert bumps[0] > 20 and conflicts > 0 and "409" in log, summary
