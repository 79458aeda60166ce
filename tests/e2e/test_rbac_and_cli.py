"""Least privilege and the CI entry points, end to end.

Covers: the operator runs a campaign to completion with exactly the RBAC the chart ships
(``helm template charts/simtest-operator``: ServiceAccount, ClusterRole, Role and bindings for a
watched namespace), authenticated with a token of the chart's ServiceAccount and nothing else;
``simtest submit --wait --junit`` exits 1 for a campaign with a failure and writes JUnit with one
testcase per scenario; ``kubectl wait --for=condition=Complete`` returns when it is done.
"""

from __future__ import annotations

import subprocess
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster.toolchain import BUILD_SCRIPT, Toolchain, build
from simtest_operator.settings import Settings
from tests.e2e import support


@pytest.fixture(scope="module")
def helm(dev_toolchain: Toolchain) -> Path:
    if dev_toolchain.missing(("helm",)):
        settings = Settings.from_env()
        build(
            support.REPO / BUILD_SCRIPT,
            cache_root=settings.cache.root,
            log_file=settings.cache.toolchain / "build.log",
            components=("helm",),
        )
    return dev_toolchain.binary("helm")


@pytest.fixture
def chart_kubeconfig(
    helm: Path,
    dev_toolchain: Toolchain,
    kubeconfig_path: Path,
    k8s_api_client: client.ApiClient,
    k8s_namespace: str,
    tmp_path: Path,
) -> Iterator[Path]:
    documents = support.chart_rbac(
        helm,
        release=f"rbac-{k8s_namespace}",
        namespace=k8s_namespace,
        templates=("rbac", "serviceaccount"),
    )
    kinds = sorted(str(d["kind"]) for d in documents)
    assert kinds == [
        "ClusterRole",
        "ClusterRoleBinding",
        "Role",
        "RoleBinding",
        "ServiceAccount",
    ], kinds
    with support.identity_kubeconfig(
        documents,
        kubectl=dev_toolchain.binary("kubectl"),
        kubeconfig=kubeconfig_path,
        api=k8s_api_client,
        namespace=k8s_namespace,
        folder=tmp_path,
    ) as path:
        yield path


def test_operator_runs_with_exactly_the_chart_rbac(
    chart_kubeconfig: Path,
    operator: support.OperatorProcess,
    cluster: support.Cluster,
    sources: Path,
) -> None:
    support.scenario_files(
        sources / "scenarios", ["pass-0.xosc", "pass-1.xosc", "flaky-0.xosc", "fail-0.xosc"]
    )
    operator.kubeconfig = chart_kubeconfig
    with support.running(operator):
        cluster.create(support.campaign("rbac", execution={"maxParallel": 4}))
        status = cluster.wait_complete("rbac", timeout=90, alive=operator.alive)
    assert (status["passed"], status["failed"], status["total"]) == (3, 1, 4)
    assert "Forbidden" not in operator.log_text() and "403" not in operator.log_text()


def test_submit_wait_junit_and_kubectl_wait(
    operator: support.OperatorProcess,
    cluster: support.Cluster,
    sources: Path,
    kubeconfig_path: Path,
    dev_toolchain: Toolchain,
    tmp_path: Path,
) -> None:
    support.scenario_files(sources / "scenarios", ["pass-0.xosc", "pass-1.xosc", "fail-0.xosc"])
    manifest = tmp_path / "campaign.yaml"
    manifest.write_text(yaml.safe_dump(support.campaign("submitted", execution={"maxParallel": 3})))
    report = tmp_path / "junit.xml"
    with support.running(operator):
        submitted = support.submit(
            manifest,
            namespace=cluster.namespace,
            kubeconfig=kubeconfig_path,
            timeout=90,
            extra=["--junit", str(report)],
        )
        waited = subprocess.run(
            [
                str(dev_toolchain.binary("kubectl")),
                "--kubeconfig",
                str(kubeconfig_path),
                "-n",
                cluster.namespace,
                "wait",
                "--for=condition=Complete",
                "testcampaign/submitted",
                "--timeout=30s",
            ],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert submitted.returncode == 1, submitted.stdout + submitted.stderr
    assert "Failed" in submitted.stdout and "fail-0.xosc" in submitted.stdout
    assert waited.returncode == 0, waited.stderr
    suite = ET.parse(report).getroot().find("testsuite")
    assert suite is not None
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("3", "1", "0")
