"""The end of an environment: its helmfile teardown, then its deletion once folded.

An environment is deleted only when every verdict it holds is in its batch's status and (with
``provisioner: Helmfile``) its releases are torn down; deleting it measures the orchestration
overhead its scenarios paid.
"""

from __future__ import annotations

from collections.abc import Mapping

from simtest_operator.operator import helmfileteardown, names
from simtest_operator.operator.actions import Action, Delete, Kind
from simtest_operator.operator.batches import Progress, State
from simtest_operator.operator.environments import Assessment
from simtest_operator.operator.observed import BatchView
from simtest_operator.operator.planning.inputs import Step
from simtest_operator.operator.planning.outcomes import Outcome


def teardowns(step: Step, states: Progress) -> Outcome:
    """helmfile destroy Jobs (and their bookkeeping) of finished Helmfile environments."""
    return Outcome(
        actions=tuple(
            helmfileteardown.teardowns(
                step.spec,
                step.envs,
                jobs=step.inputs.jobs,
                pods=step.inputs.pods,
                batches=_named(step, states),
                render=step.render,
                config=step.config,
            )
        )
    )


def removals(step: Step, judged: Mapping[str, Assessment], states: Progress) -> Outcome:
    """Deletes of finished environments whose verdicts are all folded into their batches,
    unless the configuration keeps them."""
    actions: list[Action] = []
    overheads: list[float] = []
    if step.config.keep_finished_environments:
        return Outcome()
    for env in step.envs:
        if env.deleting or not env.finished:
            continue
        if not all(_folded(step, states, scenario_id) for scenario_id in env.scenario_ids):
            continue
        if not helmfileteardown.torn_down(env, step.inputs.jobs):
            continue
        actions.append(Delete(kind=Kind.ENVIRONMENT, name=env.name, uid=env.uid))
        timings = judged[env.name].timings
        if timings.queued and timings.finished:
            wall = (timings.finished - timings.queued).total_seconds()
            ran = sum(r.duration_seconds for r in judged[env.name].results or ())
            overheads.append(max(wall - ran, 0.0) / max(len(env.scenarios), 1))
    return Outcome(actions=tuple(actions), overheads=tuple(overheads))


def _named(step: Step, states: Progress) -> list[BatchView]:
    """The batches a teardown may name: the open ones (every live environment's) and those of
    the helmfile Jobs -- a lookup each, not a pass over every batch of the campaign."""
    chosen = {i: step.batches[i] for i in states.open if i in step.batches}
    for job in step.inputs.jobs.values():
        parsed = names.parse_environment(job.environment)
        if parsed is not None and parsed.batch_index in step.batches:
            chosen[parsed.batch_index] = step.batches[parsed.batch_index]
    return list(chosen.values())


def _folded(step: Step, states: Progress, scenario_id: str) -> bool:
    position = step.layout.index.get(scenario_id)
    return position is not None and states.state(position).state is State.FOLDED
