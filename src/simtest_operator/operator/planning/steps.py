"""One planning step: the order of its phases.

A step acts on observed state only. Results become durable in this order, each step after the
previous one is visible: pod terminated -> SimEnvironment status records the verdicts -> pod
deleted and the verdicts folded into the ScenarioBatch status -> SimEnvironment deleted. A crash
between any two steps leaves enough behind for the next operator to continue from.
"""

from __future__ import annotations

from collections.abc import Mapping

from simtest_operator.operator import admission, cancelling
from simtest_operator.operator.actions import Observation, Plan
from simtest_operator.operator.admission import Gate
from simtest_operator.operator.planning import (
    admitting,
    assessing,
    cleaning,
    evaluating,
    folding,
    inputs,
    starting,
    tending,
)
from simtest_operator.operator.planning.outcomes import Outcome
from simtest_operator.operator.status import campaignstatus, counting
from simtest_operator.operator.status.evaluationstatus import EvaluationState
from simtest_operator.settings import OperatorSettings


def plan(given: inputs.Inputs, *, config: OperatorSettings, render: inputs.Renderer) -> Plan:
    """One reconcile step."""
    campaign = given.campaign
    if campaign.deleting:
        return Plan(finished=True)
    if campaign.spec is None:
        return _halt(given, "Error", "InvalidSpec", campaign.spec_error or "invalid spec")
    if given.stored is None:
        if given.resolution_error is not None:
            return _halt(given, "Error", "ResolutionFailed", given.resolution_error)
        return _halt(given, "Resolving", "Resolving", "resolving scenario sources", final=False)
    if campaign.spec.search is not None and given.search is None:
        return _halt(given, "Resolving", "Resolving", "replaying the search", final=False)
    step = inputs.step(given, given.stored, campaign.spec, config=config, render=render)
    return _run(step)


def _halt(
    given: inputs.Inputs, phase: str, reason: str, message: str, *, final: bool = True
) -> Plan:
    actions = campaignstatus.halted(
        given.campaign, phase, reason, message, final=final, now=given.now
    )
    return Plan(actions=actions, finished=final)


def _run(step: inputs.Step) -> Plan:
    cancellation = cancelling.decide(step.spec, step.campaign.status, now=step.now)
    judged = assessing.assessments(step, cancellation)
    states = assessing.states(step, judged, cancellation)
    counts = counting.progress_counters(states)
    searching = step.inputs.search is not None and step.inputs.search.open
    complete = states.complete and not (searching and cancellation is None)
    in_flight = assessing.in_flight(step, judged)
    gate = admitting.admit(step, starting.window(step), complete=complete, in_flight=in_flight)
    window = gate.window
    outcome = (
        Outcome(actions=gate.actions)
        + tending.tend(step, judged)
        + cleaning.teardowns(step, states)
        + folding.fold(step, states)
        + cleaning.removals(step, judged, states)
    )
    if not complete and cancellation is None:
        outcome += starting.start(step, states, in_flight=in_flight, window=window)
        outcome += _deadline(step)
    due = complete and cancellation is None and counts["total"] > 0
    evaluated, evaluation = evaluating.evaluate(step, due=due)
    outcome += evaluated
    outcome += _campaign(
        step,
        counts,
        complete=complete,
        cancellation=cancellation,
        evaluation=evaluation,
        admitted=gate,
        in_flight=in_flight,
    )
    return Plan(
        actions=outcome.actions,
        wake_at=min(outcome.wakes) if outcome.wakes else None,
        observation=Observation(
            in_flight=in_flight,
            queued=counts["queued"],
            window=window,
            start_latencies=outcome.start_latencies,
            overheads=outcome.overheads,
        ),
        finished=complete and not step.envs and (evaluation is None or evaluation.stage.final),
    )


def _deadline(step: inputs.Step) -> Outcome:
    """Look again when ``activeDeadlineSeconds`` runs out."""
    limit = cancelling.deadline(step.spec, step.campaign.status)
    return Outcome(wakes=(limit,) if limit is not None else ())


def _campaign(
    step: inputs.Step,
    counts: Mapping[str, int],
    *,
    complete: bool,
    cancellation: cancelling.Cancellation | None,
    evaluation: EvaluationState | None,
    admitted: Gate,
    in_flight: int,
) -> Outcome:
    """The campaign's own status and event (a counters-only change may wait: a wake-up)."""
    update = campaignstatus.progressed(
        step.campaign,
        step.spec,
        counts,
        batches=len(step.batches),
        complete=complete,
        cancellation=cancellation,
        now=step.now,
        last_write=step.inputs.last_status_write,
        status_interval=step.config.pacing.status_interval,
        evaluation=evaluation,
        admission=admitted.condition,
        waiting=admission.now_waiting(admitted, in_flight=in_flight),
        search=step.inputs.search,
    )
    return Outcome(actions=update.actions, wakes=(update.due,) if update.due is not None else ())
