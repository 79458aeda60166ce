"""Whole campaigns through the planner on the in-memory cluster (no API server).

Covers: window mode completes with correct counters and one result per scenario; the window and
node slots are never exceeded; live SimEnvironments stay bounded; prefetch only beyond
a derived window with pending headroom; batches are created lazily;
barrier mode starts a batch only after the previous one has final verdicts; infrastructure
errors are retried as new attempts and Failed never is; retries run out into Error; suspend
pauses; Reuse runs queues on warm workers; a crash after any prefix of a plan's actions (an
operator restart) loses and duplicates nothing; a finished pod is deleted without grace (its slot
free at once); prefetched pods are created a step after the pods that fill the free slots.
"""

from __future__ import annotations

import json
import random

from simtest_operator.operator.actions import Create, Kind
from simtest_operator.settings import InputSettings, OperatorSettings, PacingSettings
from tests.operator.fakecluster import REPO, FakeCluster, Script, campaign_body, frozen_list


def test_window_mode_completes_with_correct_counters() -> None:
    cluster = FakeCluster(nodes={"n0": 2, "n1": 2, "n2": 2})
    cluster.start_campaign(
        campaign_body(batchSize=9, maxSimulatorsPerNode=2), frozen_list(50), batch_size=9
    )
    cluster.run()
    status = cluster.status()
    assert status["phase"] == "Succeeded"
    assert (status["total"], status["passed"], status["queued"], status["running"]) == (
        50,
        50,
        0,
        0,
    )
    assert status["progress"] == "50/50"
    assert status["batches"] == 6
    assert len(cluster.results()) == 50
    assert max(cluster.max_per_node.values()) <= 2
    assert cluster.max_in_flight <= 6 + 3  # the slots plus one prefetched pod per node
    assert cluster.max_live_envs <= 2 * 9  # in flight + finished awaiting their fold
    complete = next(c for c in status["conditions"] if c["type"] == "Complete")
    assert complete["status"] == "True"
    assert not cluster.of(Kind.POD)


def test_window_is_refilled_without_waiting_for_the_batch() -> None:
    durations = {f"s{i:03d}.xosc": 2.0 if i % 2 else 10.0 for i in range(12)}
    cluster = FakeCluster(nodes={"n0": 3}, script=lambda s, a: Script(seconds=durations[s]))
    cluster.start_campaign(
        campaign_body(batchSize=3, maxSimulatorsPerNode=3), frozen_list(12), batch_size=3
    )
    steps = cluster.run()
    # 3 slots, 6 long (10 s) and 6 short (2 s): a barrier would need >= 4 x 10 s.
    assert steps < 35


def test_barrier_mode_waits_for_each_batch() -> None:
    cluster = FakeCluster(nodes={"n0": 3, "n1": 3})
    cluster.start_campaign(
        campaign_body(batchSize=4, batchBarrier=True), frozen_list(12), batch_size=4
    )
    seen_overlap = False
    for _ in range(200):
        cluster.step()
        envs = cluster.of(Kind.ENVIRONMENT)
        if len({e["spec"]["batch"] for e in envs}) > 1:
            seen_overlap = any(e["status"].get("phase") != "Finished" for e in envs)
        if cluster.status().get("phase") == "Succeeded":
            break
    assert cluster.status()["phase"] == "Succeeded"
    assert not seen_overlap
    assert len(cluster.results()) == 12


def test_errors_are_retried_as_new_attempts_and_failures_are_not() -> None:
    def script(scenario: str, attempt: int) -> Script:
        if scenario == "s001.xosc" and attempt == 1:
            return Script(seconds=2, message="", exit_code=137, reason="OOMKilled")
        if scenario == "s002.xosc":
            return Script(
                seconds=2,
                message=json.dumps(
                    {"scenarioId": scenario, "verdict": "Failed", "reason": "collision with car1"}
                ),
            )
        return Script(seconds=2)

    cluster = FakeCluster(script=script)
    cluster.start_campaign(campaign_body(batchSize=5), frozen_list(5), batch_size=5)
    cluster.run()
    results = cluster.results()
    assert results["s001.xosc"]["verdict"] == "Passed"
    assert results["s001.xosc"]["attempts"] == 2
    assert results["s002.xosc"]["verdict"] == "Failed"
    assert results["s002.xosc"]["attempts"] == 1
    assert "collision" in results["s002.xosc"]["reason"]
    status = cluster.status()
    assert (status["passed"], status["failed"], status["errored"]) == (4, 1, 0)
    assert status["phase"] == "Failed"


def test_retries_run_out_into_error() -> None:
    cluster = FakeCluster(script=lambda s, a: Script(seconds=1, message="segfault", exit_code=139))
    cluster.start_campaign(campaign_body(batchSize=2, retries=1), frozen_list(2), batch_size=2)
    cluster.run()
    results = cluster.results()
    assert {r["verdict"] for r in results.values()} == {"Error"}
    assert {r["attempts"] for r in results.values()} == {2}
    assert "exit code 139" in results["s000.xosc"]["reason"]
    assert cluster.status()["phase"] == "Error"
    degraded = next(c for c in cluster.status()["conditions"] if c["type"] == "Degraded")
    assert degraded["status"] == "True"


def test_suspend_starts_nothing_new() -> None:
    cluster = FakeCluster()
    cluster.start_campaign(campaign_body(batchSize=5, maxParallel=2), frozen_list(6), batch_size=5)
    cluster.step()
    cluster.get(Kind.CAMPAIGN, "camp")["spec"]["suspend"] = True  # type: ignore[index]
    for _ in range(30):
        cluster.step()
    status = cluster.status()
    assert status["phase"] == "Suspended"
    assert status["passed"] == 2
    assert status["queued"] == 4
    cluster.get(Kind.CAMPAIGN, "camp")["spec"]["suspend"] = False  # type: ignore[index]
    cluster.run()
    assert cluster.status()["passed"] == 6


def test_reuse_runs_queues_on_warm_workers() -> None:
    config = OperatorSettings(
        inputs=InputSettings(templates_dir=REPO / "helm-templates"),
        pacing=PacingSettings(reuse_queue=4),
    )
    cluster = FakeCluster(config=config, nodes={"n0": 2})
    body = campaign_body(batchSize=10, isolation="Reuse")
    cluster.start_campaign(body, frozen_list(10), batch_size=10)
    created: set[str] = set()
    for _ in range(100):
        cluster.step()
        created |= {e["metadata"]["name"] for e in cluster.of(Kind.ENVIRONMENT)}
        if cluster.status().get("phase") == "Succeeded" and not cluster.of(Kind.ENVIRONMENT):
            break
    assert cluster.status()["passed"] == 10
    # Queues of at most 4, the batch split evenly: 4 + 3 + 3.
    assert created == {"camp-b00000-e000-a1", "camp-b00000-e004-a1", "camp-b00000-e007-a1"}


def test_crash_after_any_prefix_of_a_plan_loses_and_duplicates_nothing() -> None:
    rng = random.Random(7)

    def script(scenario: str, attempt: int) -> Script:
        if scenario.endswith(("3.xosc", "7.xosc")) and attempt == 1:
            return Script(seconds=1, message="", exit_code=1)
        return Script(seconds=rng.choice((1.0, 2.0, 3.0)))

    cluster = FakeCluster(nodes={"n0": 2, "n1": 2}, script=script)
    cluster.start_campaign(campaign_body(batchSize=4), frozen_list(20), batch_size=4)
    cluster.run(limit=lambda step: rng.randint(0, 3))
    results = cluster.results()
    assert sorted(results) == [f"s{i:03d}.xosc" for i in range(20)]
    assert all(r["verdict"] == "Passed" for r in results.values())
    retried = {k for k, r in results.items() if r["attempts"] > 1}
    assert retried == {"s003.xosc", "s007.xosc", "s013.xosc", "s017.xosc"}
    assert cluster.status()["passed"] == 20


def test_explicit_max_parallel_is_never_exceeded_and_prefetch_needs_pending_headroom() -> None:
    cluster = FakeCluster(nodes={"n0": 3, "n1": 3})
    cluster.start_campaign(campaign_body(batchSize=5, maxParallel=4), frozen_list(12), batch_size=5)
    cluster.run()
    assert cluster.max_in_flight <= 4
    tight = FakeCluster(nodes={"n0": 2, "n1": 2})
    body = campaign_body(
        batchSize=5, maxSimulatorsPerNode=2, timeoutSeconds=60, pendingTimeoutSeconds=90
    )
    tight.start_campaign(body, frozen_list(12), batch_size=5)
    tight.run()
    assert tight.max_in_flight <= 4  # a Pending wait could trip pendingTimeoutSeconds: no prefetch


def test_a_large_window_opens_over_several_short_steps() -> None:
    config = OperatorSettings(
        inputs=InputSettings(templates_dir=REPO / "helm-templates"),
        pacing=PacingSettings(max_starts_per_step=5),
    )
    cluster = FakeCluster(nodes={f"n{i}": 3 for i in range(8)}, config=config)
    cluster.start_campaign(campaign_body(batchSize=30), frozen_list(60), batch_size=30)
    created = []
    for _ in range(8):
        plan = cluster.plan()
        starts = [a for a in plan.actions if isinstance(a, Create) and a.kind is Kind.ENVIRONMENT]
        assert len(starts) <= 5
        if len(starts) == 5:
            assert plan.wake_at == cluster.now  # the rest right after, not at the next event
        created.append(len(starts))
        cluster.apply(plan)
    # Batches first, then the 16-pod window (8 slots + 8 prefetched) in 4 steps; the prefetched
    # pods only once the slots' pods exist, so the scheduler meets them after those.
    assert created[:5] == [0, 5, 3, 5, 3]
    assert plan.observation.window == 16
    cluster.run()
    assert cluster.status()["passed"] == 60


def test_exited_pods_hand_their_slot_over_at_once() -> None:
    """A finished environment's pod whose container exited is deleted without grace (the
    scheduler frees its slot now, not after the kubelet's relist); the baseline setting keeps
    the graceful delete."""
    for release, grace in ((True, 0), (False, None)):
        config = OperatorSettings(
            inputs=InputSettings(templates_dir=REPO / "helm-templates"),
            pacing=PacingSettings(release_exited=release),
        )
        cluster = FakeCluster(nodes={"n0": 1}, config=config)
        cluster.start_campaign(campaign_body(batchSize=3), frozen_list(3), batch_size=3)
        cluster.run()
        assert cluster.status()["phase"] == "Succeeded"
        assert len(cluster.pod_deletes) == 3
        assert {g for _, g in cluster.pod_deletes} == {grace}
