"""A 50-scenario campaign on kwok fake nodes, end to end through the real control plane.

Covers: the campaign completes with correct counters (passed, failed, errored after retries, a
flaky scenario retried once) and printer columns; every scenario has exactly one result; no node
ever runs more simulator pods than its ``simtest.dev/simulator`` slots; finished pods and
SimEnvironments are cleaned up; conditions and events (campaign phases, finished batches) are
posted.
"""

from __future__ import annotations

import collections
import time

from tests.e2e import support


def test_fifty_scenarios_on_kwok(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: support.Path
) -> None:
    names = [f"pass-{i:03d}.xosc" for i in range(44)] + [
        "fail-000.xosc",
        "fail-001.xosc",
        "flaky-000.xosc",
        "flaky-001.xosc",
        "broken-000.xosc",
        "slow-000.xosc",
    ]
    support.scenario_files(sources / "scenarios", names)
    peak: collections.Counter[str] = collections.Counter()

    def sample() -> None:
        running = collections.Counter(
            p.spec.node_name
            for p in cluster.pods()
            if p.status.phase == "Running"
            and p.spec.node_name
            and not p.metadata.deletion_timestamp
        )
        for node, count in running.items():
            peak[node] = max(peak[node], count)

    with support.running(operator):
        cluster.create(
            support.campaign(
                "fifty", execution={"batchSize": 9, "maxSimulatorsPerNode": 3, "retries": 1}
            )
        )
        started = time.monotonic()
        status = cluster.wait_complete("fifty", timeout=150, alive=operator.alive, during=sample)
        elapsed = time.monotonic() - started
        deadline = time.monotonic() + 20
        while (cluster.items("simenvironments") or cluster.pods()) and time.monotonic() < deadline:
            time.sleep(0.5)
        leftovers = len(cluster.items("simenvironments")) + len(cluster.pods())
        events = cluster.core.list_namespaced_event(cluster.namespace).items
    assert status["phase"] == "Error"  # broken-000 ends Error after its retry
    counts = {
        k: status[k]
        for k in ("total", "passed", "failed", "errored", "timedOut", "queued", "running")
    }
    assert counts == {
        "total": 50,
        "passed": 47,
        "failed": 2,
        "errored": 1,
        "timedOut": 0,
        "queued": 0,
        "running": 0,
    }
    assert status["progress"] == "50/50" and status["batches"] == 6
    results = cluster.results("fifty")
    assert len(results) == 50
    assert (
        results["flaky-000.xosc"]["attempts"] == 2
        and results["flaky-000.xosc"]["verdict"] == "Passed"
    )
    assert (
        results["broken-000.xosc"]["attempts"] == 2
        and "exit code 3" in results["broken-000.xosc"]["reason"]
    )
    assert (
        results["fail-000.xosc"]["attempts"] == 1
        and "collided" in results["fail-000.xosc"]["reason"]
    )
    assert max(peak.values()) <= 3, peak
    assert elapsed < 120
    columns, rows = cluster.table("testcampaigns")
    row = dict(zip(columns, rows[0], strict=True))
    assert (row["Phase"], row["Passed"], row["Failed"], row["Errored"], row["Progress"]) == (
        "Error",
        47,
        2,
        1,
        "50/50",
    )
    columns, rows = cluster.table("scenariobatches")
    assert len(rows) == 6 and {dict(zip(columns, r, strict=True))["Campaign"] for r in rows} == {
        "fifty"
    }
    conditions = {c["type"]: c["status"] for c in status["conditions"]}
    assert conditions == {
        "Resolved": "True",
        "Running": "False",
        "Complete": "True",
        "Degraded": "True",
    }
    assert leftovers == 0
    reasons = {e.reason for e in events if e.involved_object.kind == "TestCampaign"}
    assert {"Running", "Error"} <= reasons, reasons
    assert any(e.reason == "BatchSucceeded" for e in events)
