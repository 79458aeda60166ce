"""The evaluation step (``spec.evaluation.offline``) in the campaign planner, on the fake cluster.

Covers: no Job while scenarios run, exactly one ``<campaign>-evaluate`` Job (owned by the
campaign) once every verdict is in, however often the planner runs; ``Evaluated`` Unknown/Running
with ``status.evaluation.job`` meanwhile and the phase unchanged throughout; the Job's answer
(exit 0/1/2 with the summary and id from the termination message, a crash after the retries, a
Job gone before it answered, a create the API server refused: its code and words, not retried)
as the condition, ``status.evaluation.id`` and one event; a restart after the Job was created but
not recorded finds the Job instead of making a second; no ``offline`` field, or a cancelled
campaign: no Job, no condition; the simulator pods never see the field.
"""

from __future__ import annotations

import json
from typing import Any

import pytest

from simtest_operator.operator import observed, recording_results, requests
from simtest_operator.operator.actions import Create, Kind
from simtest_operator.settings import OperatorSettings
from tests.operator.fakecluster import FakeCluster, campaign_body, frozen_list, stamp

JOB = "camp-evaluate"
SUMMARY = "evaluation default-20300101T000000Z-0a1b2c3d of run tests-camp: 3 passed"


def _campaign(*, offline: bool = True, **spec: Any) -> dict[str, Any]:
    body = campaign_body(maxParallel=2)
    body["spec"]["results"] = {"databaseSecretRef": {"name": "results-db", "key": "dsn"}}
    if offline:
        body["spec"]["evaluation"] = {
            "offline": {"criteria": {"configMapRef": {"name": "crit", "key": "strict.yaml"}}}
        }
    body["spec"].update(spec)
    return body


def _cluster(**kwargs: Any) -> FakeCluster:
    cluster = FakeCluster()
    cluster.start_campaign(_campaign(**kwargs), frozen_list(3), batch_size=3)
    return cluster


def _condition(cluster: FakeCluster) -> dict[str, Any] | None:
    found = [c for c in cluster.status().get("conditions", []) if c["type"] == "Evaluated"]
    return found[0] if found else None


def _finish_job(cluster: FakeCluster, *, exit_code: int, message: str, failed: bool) -> None:
    """Play the Job controller and the kubelet: one pod that ended, the Job's end condition."""
    job = cluster.get(Kind.JOB, JOB)
    assert job is not None
    cluster.add(
        Kind.POD,
        {
            "metadata": {
                "name": f"{JOB}-abcde",
                "labels": job["spec"]["template"]["metadata"]["labels"],
                "ownerReferences": [
                    {"kind": "Job", "name": JOB, "uid": job["metadata"]["uid"], "controller": True}
                ],
            },
            "spec": {},
            "status": {
                "phase": "Failed" if exit_code else "Succeeded",
                "containerStatuses": [
                    {
                        "name": "evaluate",
                        "state": {
                            "terminated": {
                                "exitCode": exit_code,
                                "reason": "Error" if exit_code else "Completed",
                                "message": message,
                                "finishedAt": stamp(cluster.now),
                            }
                        },
                    }
                ],
            },
        },
    )
    end = {"type": "Failed" if failed else "Complete", "status": "True"}
    if failed:
        end |= {"reason": "PodFailurePolicy", "message": "Container evaluate exited"}
    job["status"] = {"conditions": [{**end, "lastTransitionTime": stamp(cluster.now)}]}


def _creates(cluster: FakeCluster) -> list[Create]:
    return [a for a in cluster.plan().actions if isinstance(a, Create) and a.kind is Kind.JOB]


def test_one_job_once_every_verdict_is_in_and_never_before() -> None:
    cluster = _cluster()
    for _ in range(200):
        cluster.step(1.0)
        phase = cluster.status().get("phase")
        if phase == "Succeeded":
            break
        assert cluster.get(Kind.JOB, JOB) is None, f"Job created while {phase}"
    assert cluster.status()["phase"] == "Succeeded"
    for _ in range(10):  # the planner runs on and on: still one Job, never a second create
        cluster.step(1.0)
        assert not _creates(cluster)
    (job,) = cluster.of(Kind.JOB)
    campaign = cluster.get(Kind.CAMPAIGN, "camp")
    assert campaign is not None
    (owner,) = job["metadata"]["ownerReferences"]
    assert (owner["kind"], owner["uid"]) == ("TestCampaign", campaign["metadata"]["uid"])
    status = cluster.status()
    assert status["evaluation"] == {"job": JOB}
    assert status["phase"] == "Succeeded"
    condition = _condition(cluster)
    assert condition is not None
    assert (condition["status"], condition["reason"]) == ("Unknown", "Running")
    assert [e.reason for e in cluster.events if e.reason.startswith("Evaluation")] == [
        "EvaluationStarted"
    ]
    args = job["spec"]["template"]["spec"]["containers"][0]["args"]
    run_key = args[args.index("--run") + 1]
    assert run_key == recording_results.run_key(observed.campaign_view(campaign))
    assert "--criteria" in args


@pytest.mark.parametrize(
    ("exit_code", "failed", "reason", "status"),
    [(0, False, "Passed", "True"), (1, True, "Failed", "True"), (2, True, "Error", "False")],
)
def test_the_jobs_answer_becomes_the_condition(
    exit_code: int, failed: bool, reason: str, status: str
) -> None:
    cluster = _cluster()
    cluster.run()
    cluster.step(1.0)
    message = json.dumps(
        {"evaluation": "default-20300101T000000Z-0a1b2c3d", "run": "k", "summary": SUMMARY}
    )
    _finish_job(cluster, exit_code=exit_code, message=message, failed=failed)
    for _ in range(5):
        cluster.step(1.0)
    condition = _condition(cluster)
    assert condition is not None
    assert (condition["status"], condition["reason"], condition["message"]) == (
        status,
        reason,
        SUMMARY,
    )
    assert cluster.status()["evaluation"] == {
        "job": JOB,
        "id": "default-20300101T000000Z-0a1b2c3d",
    }
    assert cluster.status()["phase"] == "Succeeded"  # evidence added, not a re-run
    answered = [e for e in cluster.events if e.reason == f"Evaluation{reason}"]
    assert len(answered) == 1 and answered[0].warning == (reason == "Error")
    assert len(cluster.of(Kind.JOB)) == 1


def test_a_crash_after_the_retries_is_an_error_with_the_jobs_words() -> None:
    cluster = _cluster()
    cluster.run()
    cluster.step(1.0)
    _finish_job(cluster, exit_code=137, message="Traceback ...\nMemoryError", failed=True)
    cluster.step(1.0)
    condition = _condition(cluster)
    assert condition is not None
    assert (condition["status"], condition["reason"]) == ("False", "Error")
    assert condition["message"].startswith(f"evaluation Job {JOB} failed: PodFailurePolicy")
    assert "exit code 137" in condition["message"] and "MemoryError" in condition["message"]
    assert "id" not in cluster.status()["evaluation"]


def test_a_restart_finds_the_job_instead_of_creating_a_second() -> None:
    cluster = _cluster()
    cluster.run()
    cluster.step(1.0)
    assert cluster.get(Kind.JOB, JOB) is not None
    # The operator crashed after creating the Job, before its status write was seen.
    status = cluster.status()
    status.pop("evaluation")
    status["conditions"] = [c for c in status["conditions"] if c["type"] != "Evaluated"]
    assert not _creates(cluster)
    cluster.step(1.0)
    assert cluster.status()["evaluation"] == {"job": JOB}
    assert len(cluster.of(Kind.JOB)) == 1


def test_a_job_gone_before_it_answered_is_an_error_not_a_rerun() -> None:
    cluster = _cluster()
    cluster.run()
    cluster.step(1.0)
    cluster.delete(Kind.JOB, JOB)
    for _ in range(3):
        cluster.step(1.0)
    assert cluster.get(Kind.JOB, JOB) is None
    condition = _condition(cluster)
    assert condition is not None
    assert (condition["status"], condition["reason"]) == ("False", "Error")
    assert "disappeared" in condition["message"]


FORBIDDEN = (
    '403 Forbidden: jobs.batch is forbidden: User "system:serviceaccount:ops:simtest-operator" '
    'cannot create resource "jobs" in API group "batch" in the namespace "tests"'
)


def test_a_refused_create_is_an_error_with_the_servers_words_not_a_retry() -> None:
    cluster = _cluster()
    cluster.refusing[(Kind.JOB, JOB)] = FORBIDDEN
    cluster.run()
    for _ in range(5):
        cluster.step(1.0)
        assert not _creates(cluster), "tried again"
    assert cluster.get(Kind.JOB, JOB) is None
    condition = _condition(cluster)
    assert condition is not None
    assert (condition["status"], condition["reason"]) == ("False", "Error")
    assert condition["message"] == (
        f"the API server refused to create the evaluation Job {JOB}: {FORBIDDEN} (not tried again)"
    )
    assert cluster.status()["evaluation"] == {"job": JOB}
    assert cluster.status()["phase"] == "Succeeded"
    errors = [e for e in cluster.events if e.reason == "EvaluationError"]
    assert len(errors) == 1 and errors[0].warning and FORBIDDEN in errors[0].message


@pytest.mark.parametrize("case", ["no offline field", "cancelled"])
def test_nothing_to_evaluate(case: str) -> None:
    cluster = _cluster(offline=case != "no offline field")
    if case == "cancelled":
        cluster.step(1.0)
        campaign = cluster.get(Kind.CAMPAIGN, "camp")
        assert campaign is not None
        campaign["spec"]["cancel"] = True
    cluster.run()
    for _ in range(3):
        cluster.step(1.0)
    assert not cluster.of(Kind.JOB)
    assert _condition(cluster) is None and "evaluation" not in cluster.status()


def test_simulator_pods_do_not_see_the_step() -> None:
    cluster = _cluster()
    campaign = cluster.get(Kind.CAMPAIGN, "camp")
    assert campaign is not None
    spec = observed.campaign_view(campaign).spec
    assert spec is not None and spec.evaluation.offline is not None
    view = observed.EnvironmentView(
        name="camp-b00000-e000-a1",
        namespace="tests",
        uid="u",
        resource_version="1",
        campaign="camp",
        batch="camp-b00000",
        attempt=1,
        scenarios=(),
    )
    request = requests.environment_request(spec, view, config=OperatorSettings())
    assert "offline" not in request.evaluation and "criteria" in request.evaluation
