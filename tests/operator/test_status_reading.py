"""Reading watched statuses as the api's typed models: what the operator writes reads back
typed; an absent, unknown or malformed field reads as the model's default and is not marked set;
a condition keeps its reason and message even without a time; batch and environment results (and
an environment's conditions) are left out; an environment's phase, verdict, provisioner, Jobs and
timings read back typed, and its empty or unknown fields as absent."""

from __future__ import annotations

import datetime

from simtest_operator.api.v1alpha1 import EnvironmentPhase, Phase, Provisioner
from simtest_operator.api.v1alpha1.common import ConditionStatus
from simtest_operator.operator.status import reading
from simtest_operator.verdicts import Verdict

T0 = datetime.datetime(2030, 1, 1, tzinfo=datetime.UTC)
WRITTEN = {
    "phase": "Running",
    "observedGeneration": 2,
    "total": 3,
    "queued": 1,
    "running": 1,
    "passed": 1,
    "progress": "1/3",
    "startTime": "2030-01-01T00:00:00.000Z",
    "scenarioList": "camp-scenarios",
    "batches": 1,
    "throughput": 1.5,
    "conditions": [
        {
            "type": "Running",
            "status": "True",
            "reason": "Running",
            "message": "1/3 finished",
            "lastTransitionTime": "2030-01-01T00:00:00.000Z",
            "observedGeneration": 2,
        }
    ],
}


def test_what_the_operator_writes_reads_back_typed() -> None:
    status = reading.campaign(WRITTEN)
    assert status.phase is Phase.RUNNING
    assert (status.total, status.queued, status.running, status.passed) == (3, 1, 1, 1)
    assert status.start_time == T0 and status.completion_time is None
    assert (status.scenario_list, status.batches, status.throughput) == ("camp-scenarios", 1, 1.5)
    running = reading.condition(status, "Running")
    assert running is not None and running.status is ConditionStatus.TRUE
    assert (running.reason, running.message, running.last_transition_time) == (
        "Running",
        "1/3 finished",
        T0,
    )
    assert reading.counts(status) == {"total": 3, "queued": 1, "running": 1, "passed": 1}


def test_absent_unknown_and_malformed_fields_read_as_defaults() -> None:
    status = reading.campaign(
        {"phase": "Bogus", "total": "3", "startTime": "yesterday", "conditions": ["x"]}
    )
    assert status.phase is Phase.PENDING and status.total == 0 and status.start_time is None
    assert status.conditions == [] and status.model_fields_set == set()
    assert reading.counts(status) == {}
    assert reading.campaign({}).model_fields_set == set()


def test_a_condition_without_a_time_keeps_its_reason() -> None:
    status = reading.campaign(
        {"phase": "Cancelled", "conditions": [{"type": "Running", "reason": "DeadlineExceeded"}]}
    )
    running = reading.condition(status, "Running")
    assert running is not None and running.reason == "DeadlineExceeded" and running.message == ""
    assert running.status is ConditionStatus.UNKNOWN


def test_batch_results_are_left_to_the_view() -> None:
    status = reading.batch(
        {"phase": "Succeeded", "total": 1, "results": [{"id": "a", "verdict": "Passed"}]}
    )
    assert status.phase is Phase.SUCCEEDED and status.results == []
    assert "results" not in status.model_fields_set


def test_an_environment_status_reads_back_typed() -> None:
    status = reading.environment(
        {
            "phase": "Finished",
            "scenario": "b.xosc",
            "pod": "env-pod",
            "node": "n0",
            "verdict": "Failed",
            "reason": "collision",
            "renderedHash": "ab" * 32,
            "provisioner": "Helmfile",
            "jobs": {"sync": "env-sync"},
            "timings": {"queued": "2030-01-01T00:00:00Z", "finished": "soon"},
            "results": [{"id": "b.xosc", "verdict": "Failed"}],
            "conditions": [{"type": "Provisioned", "status": "True"}],
        }
    )
    assert status.phase is EnvironmentPhase.FINISHED and status.verdict is Verdict.FAILED
    assert (status.scenario, status.pod, status.node, status.reason) == (
        "b.xosc",
        "env-pod",
        "n0",
        "collision",
    )
    assert status.provisioner is Provisioner.HELMFILE and status.rendered_hash == "ab" * 32
    assert status.jobs is not None and (status.jobs.sync, status.jobs.destroy) == ("env-sync", None)
    assert status.timings.queued == T0 and status.timings.finished is None
    assert status.results == [] and status.conditions == []
    assert not {"results", "conditions"} & status.model_fields_set


def test_an_environment_status_reads_empty_and_unknown_fields_as_absent() -> None:
    status = reading.environment(
        {"phase": "Bogus", "pod": "", "verdict": "Maybe", "provisioner": "Ansible", "jobs": "x"}
    )
    assert status.phase is EnvironmentPhase.PENDING and status.pod is None
    assert status.verdict is None and status.provisioner is None and status.jobs is None
    assert status.model_fields_set == set()
