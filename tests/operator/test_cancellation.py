"""Cancellation through the planner on the in-memory cluster, and its pure decisions.

Covers: ``spec.cancel`` mid-run deletes the running pods, ends them and every unstarted scenario
``Skipped`` ("cancelled"), starts nothing and creates no batch afterwards, phase ``Cancelled`` with
``Complete=True`` reason ``Cancelled`` and one event; verdicts known before stand; un-cancelling
does nothing; ``activeDeadlineSeconds`` cancels with ``DeadlineExceeded`` and the planner wakes at
the deadline; a campaign that ended on its own is never cancelled afterwards; a crash after any
prefix of a plan while cancelling loses and duplicates nothing; the pod deletion the cancellation
causes is never an ``Error`` (not even with retries 0); a runner verdict that arrived stands.
"""

from __future__ import annotations

import datetime
import random
from typing import Any

from simtest_operator.api.v1alpha1 import EnvironmentPhase, TestCampaignSpec, Timings
from simtest_operator.operator import cancelling
from simtest_operator.operator.actions import Kind
from simtest_operator.operator.environments import Assessment
from simtest_operator.operator.observed import environment_view
from simtest_operator.operator.status import reading
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.verdicts import Verdict
from tests.operator.fakecluster import T0, FakeCluster, Script, campaign_body, frozen_list


def _spec(cluster: FakeCluster) -> dict[str, Any]:
    campaign = cluster.get(Kind.CAMPAIGN, "camp")
    assert campaign is not None
    spec: dict[str, Any] = campaign["spec"]
    return spec


def _condition(status: dict[str, Any], kind: str) -> dict[str, Any]:
    return next(c for c in status["conditions"] if c["type"] == kind)


def _until(cluster: FakeCluster, predicate: Any, *, steps: int = 200) -> None:
    for _ in range(steps):
        if predicate(cluster.status()):
            return
        cluster.step()
    raise AssertionError(f"condition not reached: {cluster.status()}")


def _settle(cluster: FakeCluster) -> None:
    _until(
        cluster,
        lambda s: (
            _condition(s, "Complete")["status"] == "True" and not cluster.of(Kind.ENVIRONMENT)
        ),
    )


def test_cancel_mid_run_skips_the_rest_and_starts_nothing() -> None:
    cluster = FakeCluster(script=lambda s, a: Script(seconds=4))
    body = campaign_body(batchSize=5, maxParallel=3, retries=0)
    cluster.start_campaign(body, frozen_list(12), batch_size=5)
    _until(cluster, lambda s: s.get("passed", 0) >= 3 and s.get("running", 0) > 0)
    passed_before = cluster.status()["passed"]
    started_before = len(cluster.pods_started)
    batches_before = {b["metadata"]["name"] for b in cluster.of(Kind.BATCH)}
    running_pods = {p["metadata"]["name"] for p in cluster.of(Kind.POD)}
    assert running_pods
    _spec(cluster)["cancel"] = True
    _settle(cluster)

    status = cluster.status()
    assert status["phase"] == "Cancelled"
    assert (status["total"], status["queued"], status["running"]) == (12, 0, 0)
    assert status["passed"] >= passed_before
    assert status["passed"] + status["skipped"] == 12 and status["errored"] == 0
    complete = _condition(status, "Complete")
    assert (complete["status"], complete["reason"]) == ("True", "Cancelled")
    assert _condition(status, "Running")["status"] == "False"
    assert status["progress"] == "12/12" and "completionTime" in status
    assert len(cluster.pods_started) == started_before  # nothing new started
    assert {b["metadata"]["name"] for b in cluster.of(Kind.BATCH)} == batches_before
    assert not cluster.of(Kind.POD) and not cluster.of(Kind.ENVIRONMENT)
    results = cluster.results()
    skipped = {k: r for k, r in results.items() if r["verdict"] == "Skipped"}
    assert skipped and all(r["reason"] == "cancelled" for r in skipped.values())
    # every scenario of an existing batch has its one result; those whose pods ran were skipped
    assert len(results) == min(5 * len(batches_before), 12)
    for pod in running_pods:  # camp-b00000-e002-a1 -> batch 0, slot 2 -> s002.xosc
        batch, slot = int(pod.split("-")[1][1:]), int(pod.split("-")[2][1:])
        assert results[f"s{batch * 5 + slot:03d}.xosc"]["verdict"] == "Skipped"
    assert all(
        b["status"]["phase"] == "Cancelled"
        for b in cluster.of(Kind.BATCH)
        if b["status"].get("skipped")
    )
    events = [e for e in cluster.events if e.kind is Kind.CAMPAIGN and e.reason == "Cancelled"]
    assert len(events) == 1 and events[0].terminal and not events[0].warning


def test_uncancelling_does_nothing() -> None:
    cluster = FakeCluster()
    cluster.start_campaign(campaign_body(batchSize=5, maxParallel=2), frozen_list(6), batch_size=5)
    cluster.step()
    _spec(cluster)["cancel"] = True
    _settle(cluster)
    started = len(cluster.pods_started)
    _spec(cluster)["cancel"] = False
    for _ in range(10):
        cluster.step()
    status = cluster.status()
    assert status["phase"] == "Cancelled" and status["skipped"] + status["passed"] == 6
    assert len(cluster.pods_started) == started and not cluster.of(Kind.POD)


def test_deadline_cancels_with_deadline_exceeded_and_wakes_the_planner() -> None:
    cluster = FakeCluster(script=lambda s, a: Script(seconds=5))
    body = campaign_body(batchSize=4, maxParallel=2)
    body["spec"]["activeDeadlineSeconds"] = 12
    cluster.start_campaign(body, frozen_list(8), batch_size=4)
    cluster.step()
    started = datetime.datetime.fromisoformat(cluster.status()["startTime"].replace("Z", "+00:00"))
    plan = cluster.plan()
    assert plan.wake_at is not None and plan.wake_at <= started + datetime.timedelta(seconds=12)
    _settle(cluster)
    status = cluster.status()
    assert status["phase"] == "Cancelled"
    complete = _condition(status, "Complete")
    assert (
        complete["reason"] == "DeadlineExceeded"
        and "activeDeadlineSeconds" in (complete["message"])
    )
    assert 0 < status["passed"] < 8 and status["passed"] + status["skipped"] == 8
    skipped = [r for r in cluster.results().values() if r["verdict"] == "Skipped"]
    assert skipped and all(r["reason"].startswith("cancelled: ") for r in skipped)
    events = [e for e in cluster.events if e.reason == "DeadlineExceeded"]
    assert len(events) == 1 and events[0].warning


def test_a_finished_campaign_is_never_cancelled_afterwards() -> None:
    cluster = FakeCluster()
    cluster.start_campaign(campaign_body(batchSize=5), frozen_list(4), batch_size=5)
    cluster.run()
    _spec(cluster)["cancel"] = True
    _spec(cluster)["activeDeadlineSeconds"] = 1
    for _ in range(5):
        cluster.step(30)
    assert cluster.status()["phase"] == "Succeeded"
    assert not [e for e in cluster.events if e.reason in ("Cancelled", "DeadlineExceeded")]


def test_crash_after_any_prefix_while_cancelling_loses_and_duplicates_nothing() -> None:
    rng = random.Random(11)
    for _ in range(5):
        cluster = FakeCluster(
            nodes={"n0": 2, "n1": 2}, script=lambda s, a: Script(seconds=rng.choice((2.0, 4.0)))
        )
        cluster.start_campaign(campaign_body(batchSize=4, retries=0), frozen_list(14), batch_size=4)
        for _ in range(rng.randint(1, 8)):
            cluster.step(limit=rng.randint(0, 4))
        _spec(cluster)["cancel"] = True
        for _ in range(300):
            cluster.step(limit=rng.randint(0, 4))
            if cluster.status().get("phase") == "Cancelled" and not cluster.of(Kind.ENVIRONMENT):
                complete = _condition(cluster.status(), "Complete")
                if complete["status"] == "True":
                    break
        status = cluster.status()
        assert status["phase"] == "Cancelled" and status["total"] == 14
        assert status["passed"] + status["skipped"] == 14, status
        assert status["errored"] == 0
        results = cluster.results()  # asserts one result per scenario
        assert all(r["verdict"] in ("Passed", "Skipped") for r in results.values())
        assert not cluster.of(Kind.POD)


def _env_body(*, phase: str = "Running", results: list[dict[str, Any]] | None = None) -> Any:
    return environment_view(
        {
            "metadata": {"name": "camp-b00000-e000-a1", "namespace": "t", "uid": "u"},
            "spec": {
                "campaign": "camp",
                "batch": "camp-b00000",
                "attempt": 2,
                "scenarios": [
                    {"id": "a", "source": "file:///a", "sha256": "0" * 64},
                    {"id": "b", "source": "file:///b", "sha256": "1" * 64},
                ],
            },
            "status": {"phase": phase, "results": results or []},
        }
    )


def test_assessment_under_cancellation() -> None:
    cancel = cancelling.Cancellation(reason=cancelling.Reason.CANCELLED, message="spec.cancel")
    now = T0 + datetime.timedelta(seconds=30)
    running = Assessment(
        phase=EnvironmentPhase.RUNNING,
        node="n0",
        timings=Timings(started=T0),
        results=None,
        wake_at=now,
    )
    ended = cancelling.assessment(_env_body(), running, cancel, now=now)
    assert ended.ended and ended.phase is EnvironmentPhase.FINISHED and ended.wake_at is None
    assert ended.results is not None
    assert [(r.verdict, r.reason, r.attempts) for r in ended.results] == [
        (Verdict.SKIPPED, "cancelled", 2)
    ] * 2
    assert ended.results[0].duration_seconds == 30.0 and ended.timings.finished == now
    # the pod deletion a cancellation causes reads as Error: never kept as one
    deleted = Assessment(
        phase=EnvironmentPhase.FINISHED,
        node="n0",
        timings=Timings(started=T0, finished=now),
        results=(
            ResultRecord(id="a", verdict=Verdict.PASSED, attempts=2),
            ResultRecord(id="b", verdict=Verdict.ERROR, reason="pod deleted", attempts=2),
        ),
    )
    mixed = cancelling.assessment(_env_body(), deleted, cancel, now=now)
    assert mixed.results is not None
    assert [r.verdict for r in mixed.results] == [Verdict.PASSED, Verdict.SKIPPED]
    # a delivered verdict stands; recorded verdicts are never touched
    passed = Assessment(
        phase=EnvironmentPhase.FINISHED,
        node=None,
        timings=Timings(),
        results=(ResultRecord(id="a", verdict=Verdict.PASSED),),
    )
    assert cancelling.assessment(_env_body(), passed, cancel, now=now) is passed
    recorded = _env_body(phase="Finished", results=[{"id": "a", "verdict": "Error", "attempts": 2}])
    assert cancelling.assessment(recorded, deleted, cancel, now=now) is deleted


def test_decide() -> None:
    spec = TestCampaignSpec.model_validate(
        {"scenarios": {"sources": [{"path": "s"}]}, "activeDeadlineSeconds": 60}
    )
    start = reading.campaign({"phase": "Running", "startTime": "2030-01-01T00:00:00.000Z"})
    assert cancelling.decide(spec, start, now=T0 + datetime.timedelta(seconds=59)) is None
    late = cancelling.decide(spec, start, now=T0 + datetime.timedelta(seconds=60))
    assert late is not None and late.reason is cancelling.Reason.DEADLINE_EXCEEDED
    assert cancelling.deadline(spec, start) == T0 + datetime.timedelta(seconds=60)
    assert cancelling.deadline(spec, reading.campaign({})) is None  # not started: no clock yet
    kept = reading.campaign(
        {
            "phase": "Cancelled",
            "conditions": [
                {"type": "Running", "status": "False", "reason": "DeadlineExceeded", "message": "m"}
            ],
        }
    )
    again = cancelling.decide(spec, kept, now=T0)
    assert again == cancelling.Cancellation(reason=cancelling.Reason.DEADLINE_EXCEEDED, message="m")
