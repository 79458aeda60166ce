"""The evaluation step's rules (``spec.evaluation.offline``): when it is due, what its Job renders
from, and what a finished Job says.

Pure, like :mod:`provisioning`: the planner (:mod:`.planning.evaluating`) decides with these, the
applier creates the Job. The Job's answer is the exit code and termination message of its last
pod: ``simtest evaluate`` exits 0 (every scenario passed), 1 (some did not) or 2 (bad input) and
writes its summary line and evaluation id to the termination message.
"""

from __future__ import annotations

from collections.abc import Mapping

from simtest_operator import results
from simtest_operator.api.v1alpha1 import API_VERSION, TestCampaignSpec
from simtest_operator.operator import jobviews, names, requests
from simtest_operator.operator.jobviews import JobView
from simtest_operator.operator.observed import CampaignView, PodView
from simtest_operator.operator.status.evaluationstatus import EvaluationState, Stage
from simtest_operator.operator.status.records import clip
from simtest_operator.render import OwnerRef, SecretKey
from simtest_operator.render.evaluationjobs import ConfigMapKey, EvaluationJobRequest

DEADLINE_SECONDS = 3600
"""``activeDeadlineSeconds`` of the Job: re-scoring takes seconds per hundred recordings (plus
their download); an hour bounds a hung database connection."""
_STAGE_BY_EXIT = {0: Stage.PASSED, 1: Stage.FAILED, 2: Stage.ERROR}


def wanted(spec: TestCampaignSpec) -> bool:
    """The campaign asks for an evaluation step and names the database it reads."""
    return spec.evaluation.offline is not None and spec.results.database_secret_ref is not None


def request(
    spec: TestCampaignSpec, campaign: CampaignView, *, run_key: str
) -> EvaluationJobRequest:
    """What the campaign's evaluation Job renders from."""
    offline = spec.evaluation.offline
    database = spec.results.database_secret_ref
    assert offline is not None and database is not None  # wanted()
    criteria = offline.criteria
    execution = spec.execution
    return EvaluationJobRequest(
        name=names.evaluation_job(campaign.name),
        namespace=campaign.namespace,
        labels=names.evaluation_labels(campaign.name),
        owner=OwnerRef(
            api_version=API_VERSION, kind="TestCampaign", name=campaign.name, uid=campaign.uid
        ),
        service_account=names.service_account(campaign.name),
        image=spec.environment.simulator.image,
        run_key=run_key,
        results_dsn=SecretKey(name=database.name, key=database.key),
        artifacts=requests.artifacts(spec, campaign.name),
        criteria=ConfigMapKey(name=criteria.config_map_ref.name, key=criteria.config_map_ref.key)
        if criteria is not None
        else None,
        backoff_limit=offline.backoff_limit,
        deadline_seconds=DEADLINE_SECONDS,
        node_selector=dict(execution.node_selector),
        tolerations=tuple(t.to_wire() for t in execution.tolerations),
    )


def outcome(job: JobView, pods: Mapping[str, PodView]) -> EvaluationState | None:
    """What a Job that ended says; None while it runs."""
    if not job.done:
        return None
    last = jobviews.last_run(job, pods)
    said = results.EvaluationMessage.from_text(last.container.message if last else "")
    code = last.container.exit_code if last is not None else None
    stage = _STAGE_BY_EXIT.get(code) if code is not None else None
    if stage is None:
        # No pod left to ask, or a crash (signal, OOM) after the retries: the Job's word.
        stage = Stage.PASSED if job.succeeded else Stage.ERROR
    message = said.summary
    if stage is Stage.ERROR and code not in _STAGE_BY_EXIT:
        detail = "; ".join(
            p
            for p in (
                job.reason,
                f"exit code {code}" if code is not None else "",
                last.container.reason if last is not None else "",
                message,
            )
            if p
        )
        message = f"evaluation Job {job.name} failed" + (f": {detail}" if detail else "")
    elif not message:
        message = f"evaluation Job {job.name} ended with exit code {code} (no summary)"
    return EvaluationState(
        job=job.name, stage=stage, message=clip(message), evaluation_id=said.evaluation_id
    )
