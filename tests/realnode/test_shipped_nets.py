"""Converted road networks shipped with the scenarios, in real pods.

Covers: the scenario folder staged with ``simtest scenario nets`` (a ``.simtest-nets`` folder
beside each map) and mounted read-only into every simulator pod: each pod of a campaign — one pod
per scenario, each with a fresh ``emptyDir`` cache — loads the shipped network and runs no
netconvert (its run log says where the network came from), and the verdicts are those of the
smoke scenarios.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner
from kubernetes import client

from simtest_operator.cli.scenario import scenario
from simtest_operator.devcluster.state import ClusterInfo
from simtest_operator.sim import netcache
from tests.e2e import support
from tests.realnode.conftest import SCENARIOS, host_path_claim, smoke_variant

EXPECTED = {
    "cut-in_highway_v25_gap30_dv5.xosc": "Passed",
    "cut-in_highway_v30_gap8_dv12.xosc": "Failed",
    "following_highway_v25_thw2_drop5_d2.xosc": "Passed",
}


def _readable_by_pods(path: Path) -> None:
    """Pods run as 65532 and a hostPath volume gets no fsGroup: open the folders on the way."""
    for folder in (path, *path.parents):
        if folder == Path("/tmp"):
            return
        folder.chmod(folder.stat().st_mode | 0o755)


@pytest.fixture
def staged(tmp_path: Path) -> Path:
    """The smoke scenarios and their maps, networks shipped beside the maps."""
    folder = tmp_path / "staged"
    shutil.copytree(SCENARIOS / "smoke", folder / "smoke")
    shutil.copytree(SCENARIOS / "roads", folder / "roads")
    shipped = CliRunner().invoke(scenario, ["nets", str(folder)])
    assert shipped.exit_code == 0, shipped.output
    assert " 0 not convertible" in shipped.output, shipped.output
    _readable_by_pods(folder)
    return folder


@pytest.fixture
def operator(
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    staged: Path,
    tmp_path: Path,
) -> Iterator[tuple[support.OperatorProcess, Path]]:
    """The operator over the staged folder, mounted read-only into the pods, and an artifacts
    volume to read the pods' run logs from."""
    artifacts = tmp_path / "artifacts"
    artifacts.mkdir()
    artifacts.chmod(0o1777)
    with (
        host_path_claim(
            real_api_client,
            real_namespace,
            claim="staged",
            folder=staged,
            access="ReadOnlyMany",
        ) as scenarios,
        host_path_claim(
            real_api_client,
            real_namespace,
            claim="artifacts",
            folder=artifacts,
            access="ReadWriteMany",
        ),
    ):
        process = support.OperatorProcess(
            kubeconfig=real_cluster.kubeconfig,
            namespace=real_namespace,
            templates=support.REPO / "helm-templates",
            sources=staged,
            workdir=tmp_path,
            extra_env={
                "SIMTEST_OPERATOR_SCENARIO_CLAIM": scenarios,
                "SIMTEST_OPERATOR_BACKSTOP_GRACE": "30",
            },
        )
        process.start()
        try:
            yield process, artifacts
        finally:
            process.stop()


def test_pods_load_the_shipped_network_and_run_no_netconvert(
    real_api_client: client.ApiClient,
    real_namespace: str,
    operator: tuple[support.OperatorProcess, Path],
    tmp_path: Path,
) -> None:
    process, artifacts = operator
    path = smoke_variant(
        tmp_path,
        "shipped",
        "*_highway_*.xosc",
        batchSize=3,
        retries=0,
        timeoutSeconds=60,
        resources={"requests": {"cpu": "500m"}},
    )
    body = yaml.safe_load(path.read_text())
    body["spec"]["artifacts"] = {"pvc": {"claimName": "artifacts", "subPath": "runs"}}
    cluster = support.Cluster(real_api_client, real_namespace)
    cluster.create(body)
    cluster.wait_complete("shipped", timeout=300, alive=process.alive)
    results = cluster.results("shipped")
    assert {k: v["verdict"] for k, v in results.items()} == EXPECTED
    pods = set()
    for scenario_id in EXPECTED:
        (run_log,) = (artifacts / "runs" / "shipped").glob(f"*/{scenario_id}/run.log")
        pods.add(run_log.parent.parent.name)
        (line,) = [x for x in run_log.read_text().splitlines() if x.startswith("network ")]
        assert f"/{netcache.SHIPPED_DIR}/" in line and "(cache hit," in line, line
    assert len(pods) == 3, f"one pod per scenario, each with a fresh cache: {pods}"
