"""A search on the dev cluster's real node: proposals run in real simulator containers.

Covers: ``scenarios/search-campaign.yaml`` with a small budget, submitted with ``simtest
submit --wait``, runs its proposals in real containers (each with the proposal's parameter
values) and completes with ``status.search`` counting every one; the cluster's proposed list,
rerun on this machine with ``simtest run --frozen``, gives the same verdicts -- the pods ran
exactly the concrete scenarios the searcher proposed.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import yaml
from kubernetes import client

from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.realnode.conftest import SCENARIOS

BUDGET = 4


def test_a_search_runs_its_proposals_in_real_containers(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    tmp_path: Path,
) -> None:
    manifest = yaml.safe_load((SCENARIOS / "search-campaign.yaml").read_text())
    manifest["spec"]["search"]["budget"] = BUDGET
    manifest["spec"]["search"]["strategy"] = "random"
    path = tmp_path / "search.yaml"  # the operator resolves path sources in its own folder
    path.write_text(yaml.safe_dump(manifest))
    submitted = support.submit(
        path, namespace=real_namespace, kubeconfig=real_cluster.kubeconfig, timeout=400
    )
    assert submitted.returncode in (0, 1), submitted.stdout + submitted.stderr
    cluster = support.Cluster(real_api_client, real_namespace)
    status = cluster.status("search-cut-in")
    assert status["search"]["asked"] == status["search"]["told"] == BUDGET
    results = cluster.results("search-cut-in")
    scenario = manifest["spec"]["search"]["scenario"]
    assert sorted(results) == sorted(f"{scenario}#search-{i}" for i in range(BUDGET))
    assert {r["verdict"] for r in results.values()} <= {"Passed", "Failed"}
    entries = [
        entry
        for batch in sorted(cluster.items("scenariobatches"), key=lambda b: b["spec"]["index"])
        for entry in batch["spec"]["scenarios"]
    ]
    frozen = tmp_path / "frozen.json"
    frozen.write_text(json.dumps({"format": "simtest.dev/frozen-list/v1",
                                  "campaign": "search-cut-in", "scenarios": entries}))  # fmt: skip
    out = tmp_path / "local"
    subprocess.run(
        [str(Path(sys.executable).parent / "simtest"), "run", str(path), "--frozen",
         str(frozen), "-o", str(out)],
        capture_output=True, check=False, timeout=600,
    )  # fmt: skip
    local = {
        data["scenarioId"]: data["verdict"]
        for data in (json.loads(p.read_text()) for p in out.glob("**/result.json"))
    }
    assert local == {ident: r["verdict"] for ident, r in results.items()}
