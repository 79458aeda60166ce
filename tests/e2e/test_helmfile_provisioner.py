"""``provisioner: Helmfile`` end to end: real helmfile and helm against the dev control plane.

Covers: the operator, running with exactly the chart's RBAC (operator ClusterRole/Role and the
provisioner ClusterRole), provisions each SimEnvironment with a ``helmfile sync`` Job — created
with its ConfigMap, the campaign's ServiceAccounts and the RoleBinding to the provisioner role,
and placed on the helmfile Job agent's node (test infrastructure: it runs the Job's own command
with the REAL helmfile binary, as the Job's ServiceAccount); ``helmfile sync`` installs the
simulator pod through the simtest-simulator chart (a Helm-managed pod with the rendered name and
campaign label); kwok "runs" it and the operator records the verdicts from its termination
message (one Passed, one Failed); SimEnvironment status records the provisioner, both Job names
and the rendered hash; teardown runs ``helmfile destroy`` in a Job owned by the batch, which
really uninstalls the releases (no Helm release records remain, in ConfigMaps or Secrets), and
the finished Jobs and their ConfigMaps are deleted.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from kubernetes import client

from simtest_operator.devcluster.toolchain import Toolchain
from tests.e2e import support
from tests.e2e.helmfile_job_agent import HelmfileJobAgent

TEMPLATE = "helmfile-kwok"


@pytest.fixture
def chart_identity(
    dev_toolchain: Toolchain,
    kubeconfig_path: Path,
    k8s_api_client: client.ApiClient,
    k8s_namespace: str,
    tmp_path: Path,
) -> Iterator[tuple[Path, str]]:
    """(kubeconfig with a token of the chart's operator ServiceAccount, provisioner role)."""
    documents = support.chart_rbac(
        dev_toolchain.binary("helm"),
        release=f"hf-{k8s_namespace}",
        namespace=k8s_namespace,
        templates=("rbac", "serviceaccount", "provisioner-rbac"),
    )
    role = next(
        d["metadata"]["name"]
        for d in documents
        if d["kind"] == "ClusterRole"
        and d["metadata"].get("labels", {}).get("app.kubernetes.io/component")
        == "helmfile-provisioner"
    )
    with support.identity_kubeconfig(
        documents,
        kubectl=dev_toolchain.binary("kubectl"),
        kubeconfig=kubeconfig_path,
        api=k8s_api_client,
        namespace=k8s_namespace,
        folder=tmp_path,
    ) as path:
        yield path, role


def test_helmfile_provisioner_syncs_runs_and_destroys(
    k8s_api_client: client.ApiClient,
    kubeconfig_path: Path,
    dev_toolchain: Toolchain,
    chart_identity: tuple[Path, str],
    operator: support.OperatorProcess,
    cluster: support.Cluster,
    sources: Path,
    tmp_path: Path,
) -> None:
    operator_kubeconfig, role = chart_identity
    namespace = cluster.namespace
    node = f"helmfile-agent-{namespace}"
    shutil.copytree(Path(__file__).parent / "templates" / TEMPLATE, operator.templates / TEMPLATE)
    support.scenario_files(sources / "scenarios", ["pass-0.xosc", "fail-0.xosc"])
    operator.kubeconfig = operator_kubeconfig
    operator.extra_env.update(
        {
            "SIMTEST_OPERATOR_HELMFILE_IMAGE": "simtest.dev/helmfile:test",  # never pulled
            "SIMTEST_OPERATOR_HELMFILE_ROLE": role,
            "SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR": f"kubernetes.io/hostname={node}",
        }
    )
    agent = HelmfileJobAgent(
        k8s_api_client,
        node=node,
        workdir=tmp_path / "agent",
        toolchain_bin=dev_toolchain.bin_dir,
        charts_dir=support.REPO / "charts",
        kubeconfig=kubeconfig_path,
    )
    batch_api = client.BatchV1Api(k8s_api_client)
    statuses: dict[str, dict[str, Any]] = {}
    helm_pods: dict[str, dict[str, str]] = {}

    def sample() -> None:
        for env in cluster.items("simenvironments"):
            statuses[env["metadata"]["name"]] = env.get("status") or {}
        for pod in cluster.pods():
            annotations = pod.metadata.annotations or {}
            if "meta.helm.sh/release-name" in annotations:
                helm_pods[pod.metadata.name] = {
                    "release": annotations["meta.helm.sh/release-name"],
                    "managedBy": (pod.metadata.labels or {}).get(
                        "app.kubernetes.io/managed-by", ""
                    ),
                    "campaign": (pod.metadata.labels or {}).get("simtest.dev/campaign", ""),
                    "owner": (pod.metadata.owner_references or [None])[0].kind
                    if pod.metadata.owner_references
                    else "",
                }

    agent.start()
    try:
        with support.running(operator):
            body = support.campaign("hf", template=TEMPLATE, execution={"maxParallel": 2})
            body["spec"]["environment"]["provisioner"] = "Helmfile"
            cluster.create(body)
            status = cluster.wait_complete("hf", timeout=240, alive=operator.alive, during=sample)

            def leftovers() -> dict[str, list[str]]:
                jobs = batch_api.list_namespaced_job(
                    namespace, label_selector="simtest.dev/campaign"
                )
                maps = cluster.core.list_namespaced_config_map(namespace).items
                secrets = cluster.core.list_namespaced_secret(
                    namespace, label_selector="owner=helm"
                )
                return {
                    "jobs": [j.metadata.name for j in jobs.items],
                    "releases": [
                        m.metadata.name
                        for m in maps
                        if (m.metadata.labels or {}).get("owner") == "helm"
                    ]
                    + [s.metadata.name for s in secrets.items],
                    "helmfiles": [m.metadata.name for m in maps if "-hf-" in m.metadata.name],
                    "pods": [p.metadata.name for p in cluster.pods()],
                    "environments": [
                        e["metadata"]["name"] for e in cluster.items("simenvironments")
                    ],
                }

            deadline = time.monotonic() + 120
            remaining = leftovers()
            while any(remaining.values()) and time.monotonic() < deadline:
                sample()
                time.sleep(1)
                remaining = leftovers()
    finally:
        agent.stop()
    log = operator.log_text()
    results = cluster.results("hf")
    helmfile_logs = "\n".join(
        f"--- {p.parent.name}\n{p.read_text(errors='replace')[-1500:]}"
        for p in sorted((tmp_path / "agent").rglob("helmfile.log"))
    )
    assert (status["total"], status["passed"], status["failed"], status["errored"]) == (
        2,
        1,
        1,
        0,
    ), f"{results}\n{helmfile_logs}"
    assert results["pass-0.xosc"]["verdict"] == "Passed"
    assert "collided" in results["fail-0.xosc"]["reason"]
    # helmfile sync (run by the agent with the real binary) installed both simulator pods.
    assert len(helm_pods) == 2, helm_pods
    for name, pod in helm_pods.items():
        assert pod["managedBy"] == "Helm" and pod["campaign"] == "hf", pod
        assert pod["owner"] == "SimEnvironment" and pod["release"].startswith(name[:40]), pod
    actions = sorted(r.args[r.args.index("--no-color") + 1] for r in agent.ran)
    assert actions == ["destroy", "destroy", "sync", "sync"], agent.ran
    assert sorted(r.pod.rsplit("-", 1)[0] for r in agent.ran) == sorted(
        f"{name}-hf-{action}" for name in helm_pods for action in ("destroy", "sync")
    )
    # Status recorded which provisioner ran, the sync Job and the rendered hash (the destroy Job
    # is recorded just before the environment is deleted: tests/operator covers that write).
    assert set(statuses) == set(helm_pods)
    for name, seen in statuses.items():
        assert seen.get("provisioner") == "Helmfile", seen
        assert (seen.get("jobs") or {}).get("sync") == f"{name}-hf-sync", seen
        assert len(seen.get("renderedHash", "")) == 64
    # helmfile destroy really uninstalled everything; Jobs and their ConfigMaps are gone.
    assert remaining == {
        "jobs": [],
        "releases": [],
        "helmfiles": [],
        "pods": [],
        "environments": [],
    }, remaining
    assert "Forbidden" not in log and " 403 " not in log, log[-3000:]
