"""Admission through Kueue end to end: a dev cluster started with ``--kueue`` (the manager built
from Go modules), kwok nodes, the operator as a process.

Covers: a campaign whose queue has no free ``simtest.dev/simulator`` quota creates no pod and
waits (phase Pending, ``Admitted=False`` with Kueue's reason and message) until quota frees,
then runs within the admitted count and releases its Workload when done; two campaigns in one
ClusterQueue share its quota (partial admission: together never more simulators than the quota,
both admitted while the first still runs) and both complete; with admission fair sharing the
team that has used less of the queue is admitted first, although its campaign came later.
"""

from __future__ import annotations

import collections
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from kubernetes import client
from kubernetes.client.exceptions import ApiException

from simtest_operator.devcluster import provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.state import ClusterInfo
from simtest_operator.devcluster.toolchain import BUILD_SCRIPT, Toolchain, build
from simtest_operator.errors import ToolchainError
from simtest_operator.settings import Settings
from tests.e2e import support
from tests.fixtures.cluster import REPO_ROOT, fresh_namespace

KUEUE = ("kueue.x-k8s.io", "v1beta2")
FLAVOR = "default-flavor"


@pytest.fixture(scope="module")
def kueue_cluster(
    dev_toolchain: Toolchain, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ClusterInfo]:
    """Its own dev cluster (2 kwok nodes x 3 slots), Kueue added once it runs; skipped only when
    the Kueue binary cannot be built on this machine."""
    settings = Settings.from_env()
    try:
        build(
            REPO_ROOT / BUILD_SCRIPT,
            cache_root=settings.cache.root,
            log_file=settings.cache.toolchain / "build.log",
            components=("kueue",),
        )
    except ToolchainError as exc:
        pytest.skip(f"the Kueue manager cannot be built on this machine: {exc}")
    cluster = DevCluster(
        tmp_path_factory.mktemp("kueue-cluster"), dev_toolchain, tied_to_this_process=True
    )
    cluster.up(nodes=2, slots=3, crds_dir=REPO_ROOT / "crds")
    info = cluster.up(with_kueue=True)  # Kueue added to the running cluster (`up`, `up --kueue`)
    assert "workloads.kueue.x-k8s.io" in info.crds
    assert any(c.name == "kueue" and c.alive for c in cluster.status().components)
    try:
        yield info
    finally:
        cluster.down()


@pytest.fixture
def api(kueue_cluster: ClusterInfo) -> Iterator[client.ApiClient]:
    api = provisioning.api_client(kueue_cluster.kubeconfig)
    try:
        yield api
    finally:
        api.close()  # type: ignore[no-untyped-call]


@pytest.fixture
def namespace(api: client.ApiClient) -> Iterator[str]:
    with fresh_namespace(api, "kq") as name:
        yield name


@pytest.fixture
def operator(
    kueue_cluster: ClusterInfo, namespace: str, tmp_path: Path
) -> Iterator[support.OperatorProcess]:
    sources = tmp_path / "sources"
    sources.mkdir()
    process = support.OperatorProcess(
        kubeconfig=kueue_cluster.kubeconfig,
        namespace=namespace,
        templates=support.templates_root(tmp_path),
        sources=sources,
        workdir=tmp_path,
    )
    try:
        yield process
    finally:
        process.stop()


class Queues:
    """The cluster admin's side: a flavor, ClusterQueues, LocalQueues (removed afterwards)."""

    def __init__(self, api: client.ApiClient, namespace: str) -> None:
        self.custom = client.CustomObjectsApi(api)
        self.namespace = namespace
        self.cluster_queues: list[str] = []

    def cluster_queue(self, name: str, *, simulators: int, fair: bool = False) -> None:
        resources = [
            {"name": "cpu", "nominalQuota": "16"},
            {"name": "memory", "nominalQuota": "32Gi"},
            {"name": "nvidia.com/gpu", "nominalQuota": "0"},
            {"name": "simtest.dev/simulator", "nominalQuota": str(simulators)},
        ]
        body = {
            "apiVersion": "/".join(KUEUE),
            "kind": "ClusterQueue",
            "metadata": {"name": name},
            "spec": {
                "namespaceSelector": {},
                **(
                    {"admissionScope": {"admissionMode": "UsageBasedAdmissionFairSharing"}}
                    if fair
                    else {}
                ),
                "resourceGroups": [
                    {
                        "coveredResources": [r["name"] for r in resources],
                        "flavors": [{"name": FLAVOR, "resources": resources}],
                    }
                ],
            },
        }
        self._create_cluster_object("resourceflavors", {"metadata": {"name": FLAVOR}})
        self._create_cluster_object("clusterqueues", body)
        self.cluster_queues.append(name)

    def local_queue(self, name: str, cluster_queue: str) -> None:
        self.custom.create_namespaced_custom_object(
            *KUEUE,
            self.namespace,
            "localqueues",
            {
                "apiVersion": "/".join(KUEUE),
                "kind": "LocalQueue",
                "metadata": {"name": name},
                "spec": {"clusterQueue": cluster_queue},
            },
        )

    def workloads(self) -> list[dict[str, Any]]:
        reply = self.custom.list_namespaced_custom_object(*KUEUE, self.namespace, "workloads")
        return list(reply.get("items", []))

    def create_workload(self, name: str, queue: str, *, simulators: int) -> None:
        """A workload of someone else that holds ``simulators`` of the quota."""
        self.custom.create_namespaced_custom_object(
            *KUEUE,
            self.namespace,
            "workloads",
            {
                "apiVersion": "/".join(KUEUE),
                "kind": "Workload",
                "metadata": {"name": name},
                "spec": {
                    "queueName": queue,
                    "podSets": [
                        {
                            "name": "main",
                            "count": simulators,
                            "template": {
                                "spec": {
                                    "restartPolicy": "Never",
                                    "containers": [
                                        {
                                            "name": "c",
                                            "resources": {
                                                "requests": {
                                                    "cpu": "100m",
                                                    "simtest.dev/simulator": "1",
                                                }
                                            },
                                        }
                                    ],
                                }
                            },
                        }
                    ],
                },
            },
        )

    def delete_workload(self, name: str) -> None:
        self.custom.delete_namespaced_custom_object(*KUEUE, self.namespace, "workloads", name)

    def close(self) -> None:
        for name in self.cluster_queues:
            try:
                self.custom.delete_cluster_custom_object(*KUEUE, "clusterqueues", name)
            except ApiException as exc:
                if exc.status != 404:
                    raise

    def _create_cluster_object(self, plural: str, body: dict[str, Any]) -> None:
        kind = {"resourceflavors": "ResourceFlavor", "clusterqueues": "ClusterQueue"}[plural]
        try:
            self.custom.create_cluster_custom_object(
                *KUEUE, plural, {"apiVersion": "/".join(KUEUE), "kind": kind, **body}
            )
        except ApiException as exc:
            if exc.status != 409:
                raise


@pytest.fixture
def queues(api: client.ApiClient, namespace: str) -> Iterator[Queues]:
    admin = Queues(api, namespace)
    try:
        yield admin
    finally:
        admin.close()


def _wait(predicate: Callable[[], bool], *, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.25)
    raise AssertionError(f"not reached within {timeout}s: {what}")


def _condition(status: dict[str, Any], kind: str) -> dict[str, Any]:
    return next((c for c in status.get("conditions", []) if c["type"] == kind), {})


def _live_simulators(cluster: support.Cluster) -> collections.Counter[str]:
    """Simulator pods per campaign that hold a slot now (not finished, not deleted)."""
    return collections.Counter(
        p.metadata.labels["simtest.dev/campaign"]
        for p in cluster.pods()
        if p.status.phase not in ("Succeeded", "Failed") and not p.metadata.deletion_timestamp
    )


def test_campaign_over_quota_waits_with_the_reason_then_runs(
    api: client.ApiClient,
    namespace: str,
    queues: Queues,
    operator: support.OperatorProcess,
) -> None:
    cq = f"sims-{namespace}"
    queues.cluster_queue(cq, simulators=2)
    queues.local_queue("team-a", cq)
    queues.create_workload("other-team", "team-a", simulators=2)  # all of the quota
    _wait(
        lambda: any(
            _condition(w.get("status") or {}, "Admitted").get("status") == "True"
            for w in queues.workloads()
        ),
        timeout=30,
        what="the other team's workload admitted",
    )
    support.scenario_files(operator.sources / "scenarios", [f"pass-{i:02d}.xosc" for i in range(5)])
    cluster = support.Cluster(api, namespace)
    peak = 0
    with support.running(operator):
        cluster.create(
            support.campaign("waits", execution={"queueName": "team-a", "maxParallel": 4})
        )
        _wait(
            lambda: _condition(cluster.status("waits"), "Admitted").get("reason") == "Pending",
            timeout=60,
            what="campaign condition Admitted=False with Kueue's reason",
        )
        status = cluster.status("waits")
        admitted = _condition(status, "Admitted")
        assert admitted["status"] == "False"
        assert "insufficient quota for simtest.dev/simulator" in admitted["message"]
        assert status["phase"] == "Pending"
        assert _condition(status, "Running")["reason"] == "Queued"
        time.sleep(3)  # it stays that way: no pod, no environment while the quota is taken
        assert cluster.pods() == [] and cluster.items("simenvironments") == []
        mine = next(w for w in queues.workloads() if w["metadata"]["name"] == "waits-simulators")
        assert mine["spec"]["queueName"] == "team-a"
        assert mine["metadata"]["labels"]["kueue.x-k8s.io/queue-name"] == "team-a"
        assert mine["spec"]["podSets"][0]["count"] == 4

        queues.delete_workload("other-team")

        def sample() -> None:
            nonlocal peak
            peak = max(peak, sum(_live_simulators(cluster).values()))

        final = cluster.wait_complete("waits", timeout=120, alive=operator.alive, during=sample)
        _wait(
            lambda: (
                not any(w["metadata"]["name"] == "waits-simulators" for w in queues.workloads())
            ),
            timeout=30,
            what="the campaign's Workload deleted (quota released)",
        )
    assert final["phase"] == "Succeeded" and final["passed"] == 5
    assert 1 <= peak <= 2, f"{peak} simulators at once; the ClusterQueue admits 2"
    released = _condition(cluster.status("waits"), "Admitted")
    assert (released["status"], released["reason"]) == ("False", "Released")


def test_two_campaigns_share_one_cluster_queue(
    api: client.ApiClient,
    namespace: str,
    queues: Queues,
    operator: support.OperatorProcess,
) -> None:
    cq = f"shared-{namespace}"
    queues.cluster_queue(cq, simulators=4)
    queues.local_queue("team-a", cq)
    queues.local_queue("team-b", cq)
    scenarios = operator.sources / "scenarios"
    support.scenario_files(scenarios / "a", [f"slow-{i:02d}.xosc" for i in range(6)])
    support.scenario_files(scenarios / "b", [f"slow-{i:02d}.xosc" for i in range(6)])
    cluster = support.Cluster(api, namespace)
    peak: collections.Counter[str] = collections.Counter()
    peak_total = 0
    admitted_counts: dict[str, int] = {}

    def sample() -> None:
        nonlocal peak_total
        live = _live_simulators(cluster)
        peak_total = max(peak_total, sum(live.values()))
        for campaign, count in live.items():
            peak[campaign] = max(peak[campaign], count)
        for workload in queues.workloads():
            for assignment in (
                (workload.get("status") or {}).get("admission", {}).get("podSetAssignments", [])
            ):
                admitted_counts[workload["metadata"]["name"]] = int(assignment["count"])

    with support.running(operator):
        cluster.create(
            support.campaign(
                "alpha",
                path="scenarios/a",
                execution={"queueName": "team-a", "maxParallel": 3},
            )
        )
        _wait(
            lambda: _condition(cluster.status("alpha"), "Admitted").get("status") == "True",
            timeout=60,
            what="alpha admitted",
        )
        cluster.create(
            support.campaign(
                "beta",
                path="scenarios/b",
                execution={"queueName": "team-b", "maxParallel": 3},
            )
        )

        def beta_admitted() -> bool:
            sample()
            return _condition(cluster.status("beta"), "Admitted").get("status") == "True"

        _wait(
            beta_admitted,
            timeout=60,
            what="beta admitted beside alpha (partial admission: what is left of the quota)",
        )
        assert _condition(cluster.status("alpha"), "Complete").get("status") != "True"
        beta_admitted = _condition(cluster.status("beta"), "Admitted")["message"]
        assert "admitted 1 simulators" in beta_admitted, beta_admitted
        for name in ("alpha", "beta"):
            final = cluster.wait_complete(name, timeout=180, alive=operator.alive, during=sample)
            assert final["phase"] == "Succeeded" and final["passed"] == 6, final
    assert admitted_counts == {"alpha-simulators": 3, "beta-simulators": 1}
    assert peak_total <= 4, f"{peak_total} simulators at once; the ClusterQueue admits 4"
    assert peak["alpha"] <= 3 and peak["beta"] <= 1, peak


def test_fair_sharing_admits_the_team_that_used_less_first(
    api: client.ApiClient,
    namespace: str,
    queues: Queues,
    operator: support.OperatorProcess,
) -> None:
    cq = f"fair-{namespace}"
    queues.cluster_queue(cq, simulators=2, fair=True)
    queues.local_queue("team-a", cq)
    queues.local_queue("team-b", cq)
    scenarios = operator.sources / "scenarios"
    for folder in ("a1", "a2", "b1"):
        support.scenario_files(scenarios / folder, [f"slow-{i:02d}.xosc" for i in range(4)])
    cluster = support.Cluster(api, namespace)

    def campaign(name: str, queue: str) -> None:
        cluster.create(
            support.campaign(
                name, path=f"scenarios/{name}", execution={"queueName": queue, "maxParallel": 2}
            )
        )

    def admitted(name: str) -> bool:
        return _condition(cluster.status(name), "Admitted").get("status") == "True"

    def waiting(name: str) -> bool:
        return _condition(cluster.status(name), "Admitted").get("reason") == "Pending"

    with support.running(operator):
        campaign("a1", "team-a")  # team a uses the whole quota for a while (4 x 6 s, 2 at once)
        _wait(lambda: admitted("a1"), timeout=60, what="a1 admitted")
        campaign("a2", "team-a")  # team a asks again first (FIFO would admit it next) ...
        _wait(lambda: waiting("a2"), timeout=60, what="a2 waiting in Kueue")
        time.sleep(1)
        campaign("b1", "team-b")  # ... team b, which used nothing, asks later
        _wait(lambda: waiting("b1"), timeout=60, what="b1 waiting in Kueue")
        assert _condition(cluster.status("a1"), "Complete").get("status") != "True"
        _wait(
            lambda: admitted("b1") or admitted("a2"),
            timeout=120,
            what="the next campaign admitted once a1 releases the quota",
        )
        assert admitted("b1") and not admitted("a2"), (
            _condition(cluster.status("a2"), "Admitted"),
            _condition(cluster.status("b1"), "Admitted"),
        )
        for name in ("a1", "b1", "a2"):
            final = cluster.wait_complete(name, timeout=180, alive=operator.alive)
            assert final["phase"] == "Succeeded" and final["passed"] == 4, final
