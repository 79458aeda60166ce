"""SimEnvironment status patches: what the operator writes about one environment.

Pure builders over an environment's view and its :class:`~environments.Assessment`: the phase,
timings, node and per-scenario results after an assessment; the record of a pod or helmfile Job
just created; and the Error status of an environment whose pod cannot be made.
"""

from __future__ import annotations

import datetime
from collections.abc import Sequence
from typing import Any

from simtest_operator.api.v1alpha1 import EnvironmentPhase
from simtest_operator.operator.environments import Assessment
from simtest_operator.operator.observed import EnvironmentView
from simtest_operator.operator.status import conditions
from simtest_operator.operator.status.records import ResultRecord, clip
from simtest_operator.verdicts import Verdict


def _stamp(moment: datetime.datetime | None) -> str | None:
    return conditions.rfc3339(moment) if moment is not None else None


def desired_status(env: EnvironmentView, assessment: Assessment) -> dict[str, Any]:
    """The status fields the assessment implies (a merge patch over the observed status)."""
    timings = {
        key: value
        for key, value in (
            ("queued", _stamp(assessment.timings.queued)),
            ("scheduled", _stamp(assessment.timings.scheduled)),
            ("started", _stamp(assessment.timings.started)),
            ("finished", _stamp(assessment.timings.finished)),
        )
        if value is not None
    }
    status: dict[str, Any] = {
        "phase": assessment.phase.value,
        "observedGeneration": 1,
        "scenario": env.scenarios[-1].id if assessment.results else env.scenarios[0].id,
        "timings": timings,
    }
    if assessment.node:
        status["node"] = assessment.node
    if assessment.results is not None:
        last = assessment.results[-1]
        status["verdict"] = last.verdict.value
        status["reason"] = clip(assessment.reason or last.reason)
        status["results"] = [r.to_wire() for r in assessment.results]
    return status


def provisioned_status(
    env: EnvironmentView,
    *,
    pod: str,
    rendered_hash: str,
    now: datetime.datetime,
    provisioner: str = "Pod",
    sync_job: str | None = None,
) -> dict[str, Any]:
    """Status recorded right after the pod (``Pod``) or its helmfile sync Job (``Helmfile``) was
    created."""
    queued = env.status.timings.queued or env.created or now
    if sync_job is not None:
        reason, message = "HelmfileJobCreated", f"helmfile sync Job {sync_job} created"
    else:
        reason, message = "PodCreated", f"pod {pod} created"
    extra: dict[str, Any] = {"jobs": {"sync": sync_job}} if sync_job is not None else {}
    return {
        "phase": EnvironmentPhase.PROVISIONING.value,
        "observedGeneration": 1,
        "scenario": env.scenarios[0].id,
        "pod": pod,
        "renderedHash": rendered_hash,
        "provisioner": provisioner,
        **extra,
        "timings": {"queued": conditions.rfc3339(queued)},
        "conditions": conditions.merge(
            env.status_wire.get("conditions"),
            [
                conditions.Desired(
                    type="Provisioned",
                    status=True,
                    reason=reason,
                    message=message,
                )
            ],
            now=now,
        ),
    }


def failed_status(
    scenario_ids: Sequence[str], *, attempt: int, reason: str, now: datetime.datetime
) -> dict[str, Any]:
    """Status of an environment whose pod cannot be made (render failure, pod refused by the
    API server): an Error for each of its scenarios."""
    records = [
        ResultRecord(id=i, verdict=Verdict.ERROR, reason=clip(reason), attempts=attempt)
        for i in scenario_ids
    ]
    return {
        "phase": EnvironmentPhase.FINISHED.value,
        "observedGeneration": 1,
        "scenario": scenario_ids[-1],
        "verdict": Verdict.ERROR.value,
        "reason": clip(reason),
        "results": [r.to_wire() for r in records],
        "timings": {"finished": conditions.rfc3339(now)},
    }
