"""``simtest dev-cluster up|status|kubeconfig|down`` on a second, one-node cluster.

Covers: ``up`` starts all five components and reports the server; a second ``up`` reuses the
running cluster; ``status`` lists every component as running; ``kubeconfig --path`` gives a file
the built kubectl can use; ``down`` stops exactly the recorded processes, after which ``status``
exits 1.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.processes import is_alive
from simtest_operator.devcluster.state import ClusterState
from simtest_operator.devcluster.toolchain import Toolchain

pytestmark = pytest.mark.cluster

COMPONENTS = ["etcd", "kube-apiserver", "kube-controller-manager", "kube-scheduler", "kwok"]


def test_up_status_kubeconfig_down(dev_toolchain: Toolchain, tmp_path: Path) -> None:
    runner = CliRunner(env={"SIMTEST_CACHE_DIR": str(dev_toolchain.root.parent)})
    root = ["--root", str(tmp_path / "cli-cluster")]
    try:
        up = runner.invoke(cli, ["dev-cluster", "up", *root, "--nodes", "1", "--crds", "absent"])
        assert up.exit_code == 0, up.output
        assert "dev cluster up in" in up.output
        state = ClusterState.from_json((tmp_path / "cli-cluster" / "state.json").read_text())
        assert [p.name for p in state.processes] == COMPONENTS
        assert all(is_alive(p) for p in state.processes)

        again = runner.invoke(cli, ["dev-cluster", "up", *root, "--nodes", "1", "--crds", "absent"])
        assert again.exit_code == 0, again.output
        assert state.server in again.output

        status = runner.invoke(cli, ["dev-cluster", "status", *root])
        assert status.exit_code == 0, status.output
        assert "(ready)" in status.output
        assert status.output.count("running") == len(COMPONENTS)

        path = runner.invoke(cli, ["dev-cluster", "kubeconfig", "--path", *root]).output.strip()
        nodes = subprocess.run(
            [dev_toolchain.binary("kubectl"), "--kubeconfig", path, "get", "nodes", "-ojson"],
            capture_output=True,
            text=True,
            check=True,
            timeout=30,
        )
        names = [n["metadata"]["name"] for n in json.loads(nodes.stdout)["items"]]
        assert names == ["simtest-node-0"]

        down = runner.invoke(cli, ["dev-cluster", "down", *root])
        assert down.exit_code == 0, down.output
        assert down.output.strip() == f"stopped: {', '.join(reversed(COMPONENTS))}"
        assert not any(is_alive(p) for p in state.processes)
        after = runner.invoke(cli, ["dev-cluster", "status", *root])
        assert after.exit_code == 1
        assert "not started" in after.output
    finally:
        DevCluster(tmp_path / "cli-cluster", dev_toolchain).down()  # after a failure
