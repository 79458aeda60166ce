"""The evaluation step after the runs (``spec.evaluation.offline``): its Job, once, and its answer.

Due when every scenario has its final verdict (the campaign is complete, not cancelled, and ran
something): then one Job ``<campaign>-evaluate`` re-scores the run in the results database. Its
name is fixed per campaign, so a restarted operator finds the Job instead of creating a second;
``status.evaluation.job`` records that it was created, so a Job deleted before it answered is
reported as ``Error`` rather than silently run again. A create the API server refuses for good
(missing RBAC, an invalid Job: ``Inputs.refused``) is ``Error`` too, with the server's words.
What the step says goes into the campaign's status through
:func:`~simtest_operator.operator.status.campaignstatus.progressed` (one writer of that status);
this phase adds the Job and the events.
"""

from __future__ import annotations

from simtest_operator.operator import evaluationjobs, names
from simtest_operator.operator.actions import Action, Create, Kind
from simtest_operator.operator.planning.inputs import Step
from simtest_operator.operator.planning.outcomes import Outcome
from simtest_operator.operator.status import campaignstatus, conditions
from simtest_operator.operator.status.evaluationstatus import (
    CONDITION,
    FINAL_REASONS,
    EvaluationState,
    Stage,
)
from simtest_operator.render import evaluationjobs as rendering


def evaluate(step: Step, *, due: bool) -> tuple[Outcome, EvaluationState | None]:
    """The step's actions, and what the campaign's status should say about it (None: nothing,
    or nothing new)."""
    spec = step.spec
    if not due or not evaluationjobs.wanted(spec):
        return Outcome(), None
    campaign = step.campaign
    name = names.evaluation_job(campaign.name)
    recorded = campaign.status.evaluation
    current = conditions.get(campaign.status_wire.get("conditions"), CONDITION)
    if recorded is not None and current is not None and current.get("reason") in FINAL_REASONS:
        return Outcome(), None  # answered: the status keeps it
    running = EvaluationState(
        job=name,
        stage=Stage.RUNNING,
        message=f"Job {name} re-scores run {step.run_key} (simtest evaluate)",
    )
    job = step.inputs.jobs.get(name)
    refusal = step.inputs.refused.get((Kind.JOB, name))
    if job is None and refusal is not None:
        refused = EvaluationState(
            job=name,
            stage=Stage.ERROR,
            message=f"the API server refused to create the evaluation Job {name}: {refusal} "
            "(not tried again)",
        )
        return Outcome(actions=(_answered(step, refused),)), refused
    if job is None and recorded is None:
        body = rendering.job(evaluationjobs.request(spec, campaign, run_key=step.run_key))
        started = _event(step, "EvaluationStarted", running.message, warning=False)
        return Outcome(actions=(Create(kind=Kind.JOB, body=body), started)), running
    if job is None:
        lost = EvaluationState(
            job=name,
            stage=Stage.ERROR,
            message=f"evaluation Job {name} disappeared before it answered (not run again)",
        )
        return Outcome(actions=(_answered(step, lost),)), lost
    answer = evaluationjobs.outcome(job, step.inputs.pods)
    if answer is None:
        return Outcome(), running
    return Outcome(actions=(_answered(step, answer),)), answer


def _answered(step: Step, state: EvaluationState) -> Action:
    return _event(
        step, f"Evaluation{state.stage.value}", state.message, warning=state.stage is Stage.ERROR
    )


def _event(step: Step, reason: str, message: str, *, warning: bool) -> Action:
    return campaignstatus.event(
        step.campaign, reason=reason, message=message, warning=warning, terminal=True
    )
