"""Real execution: a campaign of real SUMO scenarios on the local node agent ends with real
verdicts in status.

Covers: the default environment template and simulator pod (restricted security context,
simulator slot, run spec) admitted by the real API server and bound by the real scheduler to the
agent's node; ``simtest-runner`` runs each scenario (sha256-verified ``file://`` source, SUMO,
online evaluation, recording) and its termination message carries the verdict, metrics and
artifact URIs into ScenarioBatch status; the smoke suite's known failure (a collision) is Failed,
the rest Passed.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from kubernetes import client

from tests.e2e import support
from tests.e2e.local_node_agent import LocalNodeAgent


@pytest.mark.slow
def test_smoke_suite_on_the_local_node_agent(
    k8s_api_client: client.ApiClient,
    operator: support.OperatorProcess,
    cluster: support.Cluster,
    tmp_path: Path,
) -> None:
    node = f"simtest-local-{cluster.namespace}"
    agent = LocalNodeAgent(k8s_api_client, node=node, workdir=tmp_path / "agent", slots=2)
    operator.sources = support.REPO / "scenarios"
    agent.start()
    try:
        with support.running(operator):
            body = support.campaign(
                "real",
                path="smoke",
                template="default",
                execution={
                    "maxParallel": 2,
                    "batchSize": 3,
                    "nodeSelector": {"kubernetes.io/hostname": node},
                },
            )
            body["spec"]["evaluation"] = {"criteria": {"minTtc": 1.0}}
            cluster.create(body)
            status = cluster.wait_complete("real", timeout=240, alive=operator.alive)
            time.sleep(0.5)
    finally:
        agent.stop()
    results = cluster.results("real")
    assert status["total"] == 6 and len(results) == 6
    verdicts = {k: r["verdict"] for k, r in results.items()}
    assert verdicts["cut-in_highway_v30_gap8_dv12.xosc"] == "Failed"
    assert sum(v == "Passed" for v in verdicts.values()) == 5, verdicts
    assert "collided" in results["cut-in_highway_v30_gap8_dv12.xosc"]["reason"]
    passed = results["cut-in_highway_v25_gap30_dv5.xosc"]
    assert passed["metrics"]["minTTC"] > 1.0
    assert passed["artifacts"]["result"].endswith("result.json")
    assert Path(passed["artifacts"]["result"]).is_file()
    assert len(agent.started_pods) == 6
    assert status["phase"] == "Failed"
