"""Verdicts into batch statuses: each ScenarioBatch's counters, phase and recorded results.

A result is folded once it is durable (its environment's status holds it, or a cancellation
re-derives it); only then may :mod:`.cleaning` delete the environment. A batch that reaches a
final phase gets one event; results the pods could not store in the database get one Warning
per environment.
"""

from __future__ import annotations

from collections.abc import Sequence

from simtest_operator.operator.actions import Action, Emit, Kind, PatchStatus
from simtest_operator.operator.batches import (
    Progress,
    ScenarioState,
    State,
    unstored_by_environment,
)
from simtest_operator.operator.observed import BatchView
from simtest_operator.operator.planning.inputs import Step
from simtest_operator.operator.planning.outcomes import Outcome
from simtest_operator.operator.status import batchstatus, patches

_FINAL_PHASES = ("Succeeded", "Failed", "Error")


def fold(step: Step, states: Progress) -> Outcome:
    """Status patches and events of every batch whose status changes, by index (only open
    batches can change: a closed one holds every result and nothing runs for it)."""
    busy = {env.batch for env in step.envs}
    actions: list[Action] = []
    for index in states.open:
        batch = step.batches.get(index)
        if batch is None:
            continue
        if batch.name not in busy and len(batch.results) == len(step.layout.positions(index)):
            continue  # every result recorded and nothing running: the status is final
        actions.extend(_batch(step, index, batch, states.of_batch(index)))
    return Outcome(actions=tuple(actions))


def _batch(
    step: Step, index: int, batch: BatchView, mine: Sequence[ScenarioState]
) -> tuple[Action, ...]:
    desired = batchstatus.batch_status(states=mine, current=batch.status_wire, now=step.now)
    patch = patches.changed_fields(desired, batch.status_wire)
    if not patch:
        return ()
    actions: list[Action] = []
    known = {r.id for r in batch.results}
    folding = [
        s
        for s in mine
        if s.result is not None
        and s.id not in known
        and (s.state is State.FOLDED or (s.state is State.DONE and s.durable))
    ]
    new = tuple(s.result for s in folding if s.result is not None)
    for env_name, ids in unstored_by_environment(folding, step.envs):
        actions.append(
            Emit(
                kind=Kind.BATCH,
                name=batch.name,
                uid=batch.uid,
                reason="ResultsNotStored",
                message=f"{env_name or 'a finished environment'}: the results database "
                f"did not take {', '.join(ids)} (verdicts kept in status; see the pod log)",
                warning=True,
                terminal=True,  # once per environment: not rate limited
            )
        )
    actions.append(
        PatchStatus(
            kind=Kind.BATCH,
            name=batch.name,
            patch=patch,
            resource_version=batch.resource_version if "results" in patch else None,
            folded=new,
        )
    )
    phase = desired["phase"]
    if batch.status.phase != phase and phase in _FINAL_PHASES:
        actions.append(
            Emit(
                kind=Kind.BATCH,
                name=batch.name,
                uid=batch.uid,
                reason=f"Batch{phase}",
                message=f"batch {index}: {desired['progress']} finished, "
                f"{desired['passed']} passed, {desired['failed']} failed, "
                f"{desired['errored']} errored",
                warning=phase == "Error",
            )
        )
    return tuple(actions)
