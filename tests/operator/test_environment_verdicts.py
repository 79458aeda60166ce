"""How a simulator pod's state maps to SimEnvironment phases and verdicts.

Covers: termination message -> runner verdicts (single and Reuse, missing scenarioId);
DeadlineExceeded -> Timeout; operator backstop -> Timeout; OOMKilled, eviction, deletion (with
the disruption reason), lost node (force delete), image errors, crash without result, empty
message, Pending past pendingTimeoutSeconds -> Error; an unprovisioned environment needs a pod;
a pod missing beyond the grace period -> Error; timings; wake-up times.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
from typing import Any

import pytest

from simtest_operator.api.v1alpha1 import EnvironmentPhase
from simtest_operator.operator import environments, observed
from simtest_operator.operator.environments import Limits
from simtest_operator.operator.status import environmentstatus
from simtest_operator.verdicts import Verdict

T0 = datetime.datetime(2030, 1, 1, tzinfo=datetime.UTC)
LIMITS = Limits(
    timeout_seconds=60,
    pending_seconds=300,
    deadline_seconds=90,
    backstop_grace=30,
    missing_grace=10,
)
NODES = {
    "n0": observed.NodeView(
        name="n0", ready=True, unschedulable=False, slots=3, labels=(), taints=()
    )
}


def at(seconds: float) -> datetime.datetime:
    return T0 + datetime.timedelta(seconds=seconds)


def iso(seconds: float) -> str:
    return at(seconds).strftime("%Y-%m-%dT%H:%M:%SZ")


def env(
    *ids: str, status: dict[str, Any] | None = None, attempt: int = 1, deleting: bool = False
) -> observed.EnvironmentView:
    meta: dict[str, Any] = {
        "name": "c-b00000-e000-a1",
        "namespace": "ns",
        "uid": "u",
        "creationTimestamp": iso(0),
    }
    if deleting:
        meta["deletionTimestamp"] = iso(1)
    return observed.environment_view(
        {
            "metadata": meta,
            "spec": {
                "campaign": "c",
                "batch": "c-b00000",
                "attempt": attempt,
                "scenarios": [
                    {"id": i, "source": f"file:///{i}", "sha256": "0" * 64}
                    for i in (ids or ("a.xosc",))
                ],
            },
            "status": status
            if status is not None
            else {
                "pod": "c-b00000-e000-a1",
                "conditions": [
                    {"type": "Provisioned", "status": "True", "lastTransitionTime": iso(0)}
                ],
            },
        }
    )


def pod(
    *,
    phase: str = "Running",
    node: str | None = "n0",
    state: dict[str, Any] | None = None,
    reason: str = "",
    deleting: bool = False,
    conditions: list[dict[str, Any]] | None = None,
) -> observed.PodView:
    meta: dict[str, Any] = {
        "name": "c-b00000-e000-a1",
        "namespace": "ns",
        "uid": "p",
        "creationTimestamp": iso(0),
    }
    if deleting:
        meta["deletionTimestamp"] = iso(5)
    status: dict[str, Any] = {
        "phase": phase,
        "reason": reason,
        "message": "details",
        "conditions": conditions
        if conditions is not None
        else (
            [{"type": "PodScheduled", "status": "True", "lastTransitionTime": iso(1)}]
            if node
            else []
        ),
    }
    if state is not None:
        status["containerStatuses"] = [{"name": "simulator", "state": state}]
    return observed.pod_view({"metadata": meta, "spec": {"nodeName": node}, "status": status})


def terminated(message: str, *, code: int = 0, reason: str = "Completed") -> dict[str, Any]:
    return {
        "terminated": {
            "exitCode": code,
            "reason": reason,
            "message": message,
            "startedAt": iso(2),
            "finishedAt": iso(12),
        }
    }


def assess(
    e: observed.EnvironmentView,
    p: observed.PodView | None,
    now: float = 20,
    nodes: Any = NODES,
    *,
    seen: bool = False,
) -> environments.Assessment:
    return environments.assess(e, p, nodes=nodes, now=at(now), limits=LIMITS, seen=seen)


def test_termination_message_gives_the_runner_verdict() -> None:
    message = json.dumps(
        {
            "scenarioId": "a.xosc",
            "verdict": "Failed",
            "reason": "minTTC 0.8 < 1.5",
            "metrics": {"minTTC": 0.8},
            "wallSeconds": 9.5,
        }
    )
    result = assess(env(), pod(phase="Succeeded", state=terminated(message)))
    assert result.phase is EnvironmentPhase.FINISHED
    assert result.results is not None
    (record,) = result.results
    assert (record.verdict, record.reason, record.duration_seconds) == (
        Verdict.FAILED,
        "minTTC 0.8 < 1.5",
        9.5,
    )
    assert dict(record.metrics) == {"minTTC": 0.8}
    assert result.timings.started == at(2) and result.timings.finished == at(12)
    assert result.timings.scheduled == at(1)


def test_message_without_scenario_id_is_accepted_for_a_single_scenario() -> None:
    result = assess(
        env(), pod(phase="Succeeded", state=terminated('{"verdict": "Passed", "wallSeconds": 3}'))
    )
    assert result.results is not None and result.results[0].verdict is Verdict.PASSED


def test_reuse_worker_reports_each_scenario_and_errors_for_those_it_did_not_reach() -> None:
    message = json.dumps(
        {
            "results": [
                {"scenarioId": "a.xosc", "verdict": "Passed"},
                {"scenarioId": "b.xosc", "verdict": "Failed"},
            ]
        }
    )
    result = assess(
        env("a.xosc", "b.xosc", "c.xosc"), pod(phase="Failed", state=terminated(message, code=1))
    )
    assert result.results is not None
    assert [r.verdict for r in result.results] == [Verdict.PASSED, Verdict.FAILED, Verdict.ERROR]
    assert "before running" in result.results[2].reason


@pytest.mark.parametrize(
    ("pod_reason", "container_reason", "cut", "words"),
    [
        ("DeadlineExceeded", "Error", Verdict.TIMEOUT, "deadline"),
        ("", "OOMKilled", Verdict.ERROR, "OOMKilled"),
        ("Evicted", "Error", Verdict.ERROR, "evicted"),
    ],
)
def test_a_warm_pod_killed_mid_queue_keeps_what_finished(
    pod_reason: str, container_reason: str, cut: Verdict, words: str
) -> None:
    # The runner rewrites its message after each scenario; SIGTERM (the kubelet's deadline kill)
    # adds the interrupted and unstarted ones flagged "stopped": they take the pod's verdict.
    message = json.dumps(
        {
            "results": [
                {"scenarioId": "a.xosc", "verdict": "Passed", "wallSeconds": 4.0},
                {"scenarioId": "b.xosc", "verdict": "Error", "stopped": True, "reason": "SIGTERM"},
                {"scenarioId": "c.xosc", "verdict": "Error", "stopped": True, "reason": "SIGTERM"},
            ]
        }
    )
    container = terminated(message, code=137, reason=container_reason)
    result = assess(
        env("a.xosc", "b.xosc", "c.xosc"), pod(phase="Failed", state=container, reason=pod_reason)
    )
    assert result.results is not None
    assert [r.verdict for r in result.results] == [Verdict.PASSED, cut, Verdict.ERROR]
    assert result.results[0].duration_seconds == 4.0
    assert words in result.results[1].reason
    assert result.results[2].reason.startswith("not run:") and words in result.results[2].reason


def test_a_killed_runner_keeps_what_it_finished_and_names_the_exit() -> None:
    message = json.dumps({"results": [{"scenarioId": "a.xosc", "verdict": "Passed"}]})
    result = assess(
        env("a.xosc", "b.xosc"),
        pod(phase="Failed", state=terminated(message, code=137, reason="Error")),
    )
    assert result.results is not None
    assert [r.verdict for r in result.results] == [Verdict.PASSED, Verdict.ERROR]
    assert "exit code 137" in result.results[1].reason


@pytest.mark.parametrize(
    ("pod_reason", "container", "verdict", "words"),
    [
        ("DeadlineExceeded", terminated("", code=137, reason="Error"), Verdict.TIMEOUT, "deadline"),
        ("Evicted", terminated("", code=137, reason="Error"), Verdict.ERROR, "evicted"),
        ("", terminated("", code=137, reason="OOMKilled"), Verdict.ERROR, "OOMKilled"),
        (
            "",
            terminated("Traceback...\nRuntimeError: boom", code=1, reason="Error"),
            Verdict.ERROR,
            "exit code 1",
        ),
        ("", terminated("", code=0), Verdict.ERROR, "without writing a result"),
    ],
)
def test_pod_endings_without_a_result(
    pod_reason: str, container: dict[str, Any], verdict: Verdict, words: str
) -> None:
    result = assess(env(), pod(phase="Failed", state=container, reason=pod_reason))
    assert result.results is not None
    assert result.results[0].verdict is verdict
    assert words in result.reason


def test_crash_reason_names_the_last_log_line() -> None:
    result = assess(
        env(),
        pod(
            phase="Failed", state=terminated("line one\nRuntimeError: boom", code=1, reason="Error")
        ),
    )
    assert result.reason.endswith("RuntimeError: boom")


def test_deleted_pod_is_an_error_with_the_disruption_reason() -> None:
    conditions = [
        {"type": "PodScheduled", "status": "True", "lastTransitionTime": iso(1)},
        {
            "type": "DisruptionTarget",
            "status": "True",
            "reason": "EvictionByEvictionAPI",
            "message": "drain",
        },
    ]
    result = assess(
        env(), pod(state={"running": {"startedAt": iso(2)}}, deleting=True, conditions=conditions)
    )
    assert result.results is not None and result.results[0].verdict is Verdict.ERROR
    assert "deleted" in result.reason and "EvictionByEvictionAPI" in result.reason


def test_lost_node_is_an_error_and_forces_the_delete() -> None:
    result = assess(env(), pod(state={"running": {"startedAt": iso(2)}}), nodes={})
    assert result.results is not None and result.results[0].verdict is Verdict.ERROR
    assert "node n0" in result.reason
    assert result.force_delete


def test_a_node_that_stops_reporting_ends_the_run_after_its_grace() -> None:
    # The kubelet stopped at t=5: nobody will finish or report this pod.
    silent = {
        "n0": observed.node_view(
            {
                "metadata": {"name": "n0"},
                "status": {
                    "conditions": [
                        {"type": "Ready", "status": "Unknown", "lastTransitionTime": iso(5)}
                    ],
                    "allocatable": {"simtest.dev/simulator": "3"},
                },
            }
        )
    }
    running = pod(state={"running": {"startedAt": iso(2)}})
    waiting = assess(env(), running, now=30, nodes=silent)
    assert waiting.results is None
    assert waiting.wake_at == at(5 + LIMITS.node_not_ready_grace)
    ended = assess(env(), running, now=5 + LIMITS.node_not_ready_grace, nodes=silent)
    assert ended.results is not None and ended.results[0].verdict is Verdict.ERROR
    assert "node n0 stopped reporting" in ended.reason
    assert ended.force_delete


def test_pods_on_deleted_or_silent_nodes_are_deleted_without_grace() -> None:
    running = pod(state={"running": {"startedAt": iso(2)}})
    silent = {"n0": dataclasses.replace(NODES["n0"], ready=False, not_ready_since=at(5))}
    assert not environments.node_gone(running, NODES)
    assert environments.node_gone(running, {})
    assert environments.node_gone(running, silent)
    assert not environments.node_gone(running, None)  # nodes not watched: nothing known


def test_image_errors_end_at_once() -> None:
    result = assess(
        env(),
        pod(phase="Pending", state={"waiting": {"reason": "ErrImagePull", "message": "not found"}}),
        now=3,
    )
    assert result.results is not None and "ErrImagePull" in result.reason


def test_pending_past_its_deadline_is_an_error_naming_the_scheduler_message() -> None:
    unschedulable = [
        {
            "type": "PodScheduled",
            "status": "False",
            "reason": "Unschedulable",
            "message": "0/3 nodes are available: 3 Insufficient simtest.dev/simulator.",
        }
    ]
    waiting = assess(env(), pod(phase="Pending", node=None, conditions=unschedulable), now=100)
    assert waiting.results is None and waiting.phase is EnvironmentPhase.PROVISIONING
    assert waiting.wake_at == at(300)
    late = assess(env(), pod(phase="Pending", node=None, conditions=unschedulable), now=301)
    assert late.results is not None and late.results[0].verdict is Verdict.ERROR
    assert "Pending after 301s" in late.reason and "Insufficient" in late.reason


def test_operator_backstop_ends_a_run_nobody_stops() -> None:
    running = pod(state={"running": {"startedAt": iso(2)}})
    assert assess(env(), running, now=100).results is None
    result = assess(env(), running, now=2 + 90 + 30)
    assert result.results is not None and result.results[0].verdict is Verdict.TIMEOUT


def test_environment_without_pod() -> None:
    fresh = env(status={})
    assert assess(fresh, None).needs_pod
    provisioned = env()
    seen = env(status={**provisioned.status_wire, "node": "n0"})
    assert assess(seen, None, now=5).results is None
    gone = assess(seen, None, now=11)
    assert gone.results is not None and "disappeared" in gone.reason


def test_a_pod_the_cache_never_showed_gets_the_pending_time_not_the_missing_grace() -> None:
    provisioned = env()  # created and recorded, never seen scheduled: the watch may lag
    lagging = assess(provisioned, None, now=11)
    assert lagging.results is None and lagging.wake_at == at(300)
    never = assess(provisioned, None, now=301)
    assert never.results is not None and never.results[0].verdict is Verdict.ERROR
    assert "never appeared in 300s" in never.reason


def test_a_watched_pod_that_is_gone_was_deleted_after_the_missing_grace() -> None:
    provisioned = env()  # the pod ran and was deleted before any status write recorded it
    assert assess(provisioned, None, now=5, seen=True).results is None
    gone = assess(provisioned, None, now=11, seen=True)
    assert gone.results is not None and gone.results[0].verdict is Verdict.ERROR
    assert "disappeared before it finished (deleted)" in gone.reason


def test_deleted_environment_is_an_error() -> None:
    result = assess(env(deleting=True), None)
    assert result.results is not None and "SimEnvironment" in result.reason


def test_running_phases() -> None:
    assert assess(env(), pod(phase="Pending", node="n0")).phase is EnvironmentPhase.SCHEDULED
    started = assess(env(), pod(state={"running": {"startedAt": iso(2)}}))
    assert started.phase is EnvironmentPhase.RUNNING and started.timings.started == at(2)
    status = environmentstatus.desired_status(env(), started)
    assert status["phase"] == "Running" and status["node"] == "n0"
    assert status["timings"]["started"] == "2030-01-01T00:00:02.000Z"
    assert "verdict" not in status


def test_finished_status_is_kept_and_pod_deleted() -> None:
    finished = env(
        status={
            "phase": "Finished",
            "verdict": "Passed",
            "results": [{"id": "a.xosc", "verdict": "Passed", "attempts": 1}],
        }
    )
    result = assess(finished, pod(phase="Succeeded", state=terminated("{}")))
    assert (
        result.delete_pod
        and result.results is not None
        and result.results[0].verdict is Verdict.PASSED
    )
