"""Admission through Kueue in the planner (``spec.execution.queueName``), Kueue played by hand.

Covers: the campaign's one Workload (queue name in spec and label, one pod set of the window's
simulators with cpu, memory, GPUs only when asked, one ``simtest.dev/simulator``, placement,
``minCount`` 1, owned by the campaign but not as its controller); nothing starts before
admission and the campaign says why (phase Pending, ``Admitted=False`` with Kueue's reason and
message, ``Queued`` before Kueue looked); in flight never beyond the admitted count; the
Workload deleted at the end (``Admitted=False``, ``Released``); an eviction stops new starts;
a refused Workload is named; without ``queueName`` nothing changes; Workload views parse
Kueue's status (partial admission, eviction first) and survive odd bodies.
"""

from __future__ import annotations

from typing import Any

from simtest_operator.api.v1alpha1 import parse_campaign
from simtest_operator.operator import admission
from simtest_operator.operator.actions import Kind
from tests.operator.fakecluster import FakeCluster, campaign_body, frozen_list

WORKLOAD = "camp-simulators"


def _condition(status: dict[str, Any], kind: str) -> dict[str, Any]:
    return next((c for c in status.get("conditions", []) if c["type"] == kind), {})


def _kueue(
    cluster: FakeCluster, *, admitted: int | None, reason: str = "", message: str = ""
) -> None:
    """What Kueue writes into the Workload's status: admitted with a count, or waiting."""
    workload = cluster.get(Kind.WORKLOAD, WORKLOAD)
    assert workload is not None
    if admitted is None:
        workload["status"] = {
            "conditions": [
                {"type": "QuotaReserved", "status": "False", "reason": reason, "message": message}
            ]
        }
        return
    workload["status"] = {
        "admission": {
            "clusterQueue": "simulators",
            "podSetAssignments": [{"name": "simulators", "count": admitted}],
        },
        "conditions": [
            {"type": "QuotaReserved", "status": "True", "reason": "QuotaReserved"},
            {"type": "Admitted", "status": "True", "reason": "Admitted"},
        ],
    }


def _queued_campaign(count: int = 6, **execution: Any) -> FakeCluster:
    cluster = FakeCluster(nodes={"n0": 3, "n1": 3})
    body = campaign_body(queueName="team-a", maxParallel=4, **execution)
    cluster.start_campaign(body, frozen_list(count), batch_size=3)
    return cluster


def test_nothing_starts_before_admission_and_the_campaign_says_why() -> None:
    cluster = _queued_campaign()
    cluster.step()
    workload = cluster.get(Kind.WORKLOAD, WORKLOAD)
    assert workload is not None
    assert workload["spec"]["queueName"] == "team-a"
    assert workload["metadata"]["labels"]["kueue.x-k8s.io/queue-name"] == "team-a"
    assert workload["spec"]["podSets"][0]["count"] == 4
    assert not cluster.of(Kind.ENVIRONMENT) and not cluster.of(Kind.POD)
    status = cluster.status()
    assert status["phase"] == "Pending"
    queued = _condition(status, "Admitted")
    assert (queued["status"], queued["reason"]) == ("False", "Queued")
    assert "LocalQueue team-a" in queued["message"]

    message = (
        "couldn't assign flavors to pod set simulators: "
        "insufficient quota for simtest.dev/simulator"
    )
    _kueue(cluster, admitted=None, reason="Pending", message=message)
    for _ in range(5):
        cluster.step()
    status = cluster.status()
    waiting = _condition(status, "Admitted")
    assert (waiting["status"], waiting["reason"], waiting["message"]) == (
        "False",
        "Pending",
        message,
    )
    assert status["phase"] == "Pending"
    assert "startTime" not in status  # the wait does not count against activeDeadlineSeconds
    assert _condition(status, "Running")["reason"] == "Queued"
    assert message in _condition(status, "Running")["message"]
    assert not cluster.of(Kind.ENVIRONMENT) and not cluster.of(Kind.POD)


def test_runs_within_the_admitted_count_and_releases_the_workload() -> None:
    cluster = _queued_campaign(count=7)
    cluster.step()
    _kueue(cluster, admitted=2)
    cluster.step()
    running = _condition(cluster.status(), "Admitted")
    assert (running["status"], running["reason"]) == ("True", "Admitted")
    assert "startTime" in cluster.status()
    assert "admitted 2 simulators" in running["message"]
    cluster.run()
    assert cluster.status()["phase"] == "Succeeded"
    assert len(cluster.results()) == 7
    assert cluster.max_in_flight <= 2
    assert cluster.get(Kind.WORKLOAD, WORKLOAD) is None
    released = _condition(cluster.status(), "Admitted")
    assert (released["status"], released["reason"]) == ("False", "Released")


def test_a_barrier_campaign_is_admitted_a_whole_batch_at_least() -> None:
    """minCount is the batch size, so Kueue never admits less than the barrier submits whole."""
    cluster = FakeCluster(nodes={"n0": 3, "n1": 3})
    body = campaign_body(queueName="team-a", maxParallel=6, batchSize=3, batchBarrier=True)
    cluster.start_campaign(body, frozen_list(9), batch_size=3)
    cluster.step()
    workload = cluster.get(Kind.WORKLOAD, WORKLOAD)
    assert workload is not None
    assert (
        workload["spec"]["podSets"][0]["count"],
        workload["spec"]["podSets"][0]["minCount"],
    ) == (6, 3)
    _kueue(cluster, admitted=3)
    cluster.run()
    assert cluster.status()["phase"] == "Succeeded" and len(cluster.results()) == 9
    assert cluster.max_in_flight <= 3


def test_an_evicted_workload_stops_new_starts() -> None:
    cluster = _queued_campaign(count=12)
    cluster.step()
    _kueue(cluster, admitted=3)
    cluster.step()
    started = len(cluster.pods_started)
    assert started > 0
    workload = cluster.get(Kind.WORKLOAD, WORKLOAD)
    assert workload is not None
    workload["status"]["conditions"] = [
        {"type": "Admitted", "status": "False", "reason": "Evicted"},
        {"type": "Evicted", "status": "True", "reason": "Preempted", "message": "preempted"},
    ]
    for _ in range(10):
        cluster.step(seconds=5)
    assert len(cluster.pods_started) == started
    evicted = _condition(cluster.status(), "Admitted")
    assert (evicted["status"], evicted["reason"], evicted["message"]) == (
        "False",
        "Preempted",
        "preempted",
    )


def test_a_suspended_campaign_releases_its_quota_and_asks_again_on_resume() -> None:
    cluster = _queued_campaign(count=12)
    cluster.step()
    _kueue(cluster, admitted=2)
    cluster.step()
    campaign = cluster.get(Kind.CAMPAIGN, "camp")
    assert campaign is not None
    campaign["spec"]["suspend"] = True
    cluster.step()
    assert cluster.get(Kind.WORKLOAD, WORKLOAD) is not None  # two still run: it keeps them
    for _ in range(10):
        cluster.step(seconds=5)
    assert cluster.get(Kind.WORKLOAD, WORKLOAD) is None
    suspended = _condition(cluster.status(), "Admitted")
    assert (suspended["status"], suspended["reason"]) == ("False", "Suspended")
    assert cluster.status()["phase"] == "Suspended"
    started = len(cluster.pods_started)
    campaign["spec"]["suspend"] = False
    cluster.step()
    assert cluster.get(Kind.WORKLOAD, WORKLOAD) is not None
    assert len(cluster.pods_started) == started  # not before Kueue admits again
    _kueue(cluster, admitted=2)
    cluster.run()
    assert cluster.status()["phase"] == "Succeeded" and len(cluster.results()) == 12


def test_a_refused_workload_is_named_in_the_condition() -> None:
    cluster = _queued_campaign()
    cluster.refusing[(Kind.WORKLOAD, WORKLOAD)] = "404 Not Found: the server could not find"
    cluster.step()
    refused = _condition(cluster.status(), "Admitted")
    assert (refused["status"], refused["reason"]) == ("False", "WorkloadRefused")
    assert "is Kueue installed" in refused["message"] and "404" in refused["message"]
    assert not cluster.of(Kind.ENVIRONMENT)


def test_without_a_queue_nothing_changes() -> None:
    cluster = FakeCluster(nodes={"n0": 3})
    cluster.start_campaign(campaign_body(maxParallel=2), frozen_list(3), batch_size=3)
    cluster.run()
    assert not cluster.of(Kind.WORKLOAD)
    assert _condition(cluster.status(), "Admitted") == {}


def test_workload_body_asks_for_the_pod_of_the_spec() -> None:
    spec = parse_campaign(
        campaign_body(
            queueName="team-b",
            nodeSelector={"pool": "sim"},
            tolerations=[{"key": "gpu", "operator": "Exists", "effect": "NoSchedule"}],
            resources={"requests": {"cpu": "2", "memory": "3Gi", "gpu": 1}},
        ),
        source="test",
    ).spec
    body = admission.workload_body(
        spec, campaign="camp", namespace="ns", campaign_uid="u-1", count=0
    )
    pod_set = body["spec"]["podSets"][0]
    assert (pod_set["name"], pod_set["count"], pod_set["minCount"]) == ("simulators", 1, 1)
    template = pod_set["template"]["spec"]
    assert template["containers"][0]["resources"]["requests"] == {
        "cpu": "2",
        "memory": "3Gi",
        "simtest.dev/simulator": "1",
        "nvidia.com/gpu": "1",
    }
    assert template["nodeSelector"] == {"pool": "sim"}
    assert template["tolerations"] == [{"key": "gpu", "operator": "Exists", "effect": "NoSchedule"}]
    owner = body["metadata"]["ownerReferences"][0]
    assert (owner["kind"], owner["uid"], owner["controller"]) == ("TestCampaign", "u-1", False)
    assert [c["name"] for c in template["containers"]] == ["simulator"]
    cpu_only = parse_campaign(campaign_body(queueName="q"), source="test").spec
    requests = admission.pod_requests(cpu_only)
    assert "nvidia.com/gpu" not in requests and requests["simtest.dev/simulator"] == "1"
    with_sut = parse_campaign(
        {
            **campaign_body(queueName="q"),
            "spec": {
                **campaign_body(queueName="q")["spec"],
                "environment": {"sut": {"external": {"image": "registry.example/sut:1"}}},
            },
        },
        source="test",
    ).spec
    sut_body = admission.workload_body(
        with_sut, campaign="camp", namespace="ns", campaign_uid="u", count=2
    )
    sidecar = sut_body["spec"]["podSets"][0]["template"]["spec"]["containers"][1]
    assert sidecar == {"name": "sut", "resources": {"requests": {"cpu": "500m", "memory": "256Mi"}}}


def test_workload_view_reads_kueue_status() -> None:
    partial = admission.workload_view(
        {
            "metadata": {"name": "w", "uid": "u", "labels": {"simtest.dev/campaign": "c"}},
            "status": {
                "admission": {
                    "clusterQueue": "cq",
                    "podSetAssignments": [{"name": "simulators", "count": 3}],
                },
                "conditions": [{"type": "Admitted", "status": "True", "reason": "Admitted"}],
            },
        }
    )
    assert (partial.admitted, partial.count, partial.cluster_queue, partial.campaign) == (
        True,
        3,
        "cq",
        "c",
    )
    evicted = admission.workload_view(
        {
            "metadata": {"name": "w"},
            "status": {
                "admission": {"podSetAssignments": [{"name": "simulators", "count": 3}]},
                "conditions": [
                    {"type": "QuotaReserved", "status": "False", "reason": "Pending"},
                    {"type": "Evicted", "status": "True", "reason": "ClusterQueueStopped"},
                ],
            },
        }
    )
    assert (evicted.admitted, evicted.count, evicted.reason) == (False, 0, "ClusterQueueStopped")
    odd = admission.workload_view(
        {
            "metadata": "x",
            "status": {
                "admission": {"podSetAssignments": [{"name": "simulators", "count": "many"}]}
            },
        }
    )
    assert (odd.name, odd.admitted, odd.count, odd.reason) == ("", False, 0, "")
