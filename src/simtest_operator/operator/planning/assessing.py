"""What each environment and each scenario of the campaign is doing now.

Every later phase works on these judgements; under a cancellation they already say how each
attempt and each unstarted scenario ends (:mod:`simtest_operator.operator.cancelling`).
"""

from __future__ import annotations

from collections.abc import Mapping

from simtest_operator.operator import cancelling, provisioning
from simtest_operator.operator.batches import ScenarioState, scenario_states
from simtest_operator.operator.environments import Assessment, Limits
from simtest_operator.operator.observed import EnvironmentView
from simtest_operator.operator.planning.inputs import Step
from simtest_operator.render.inputs import STARTUP_ALLOWANCE_SECONDS


def limits(step: Step, env: EnvironmentView) -> Limits:
    """How long the environment may take in each stage."""
    execution = step.spec.execution
    config = step.config
    return Limits(
        timeout_seconds=execution.timeout_seconds,
        pending_seconds=execution.pending_timeout_seconds,
        deadline_seconds=execution.timeout_seconds * len(env.scenarios) + STARTUP_ALLOWANCE_SECONDS,
        backstop_grace=config.graces.backstop_grace,
        missing_grace=config.graces.missing_pod_grace,
        node_not_ready_grace=config.graces.node_not_ready_grace,
    )


def assessments(step: Step, cancellation: cancelling.Cancellation | None) -> dict[str, Assessment]:
    """Each environment's assessment by name (ended now under a cancellation)."""
    inputs = step.inputs
    judged = {
        env.name: provisioning.assess(
            env,
            inputs.pods.get(env.status.pod or env.name),
            jobs=inputs.jobs,
            pods=inputs.pods,
            nodes=inputs.nodes,
            now=step.now,
            limits=limits(step, env),
        )
        for env in step.envs
    }
    if cancellation is None:
        return judged
    return {
        env.name: cancelling.assessment(env, judged[env.name], cancellation, now=step.now)
        for env in step.envs
    }


def states(
    step: Step,
    judged: Mapping[str, Assessment],
    cancellation: cancelling.Cancellation | None,
) -> tuple[ScenarioState, ...]:
    """Every scenario's state, in frozen-list order."""
    current = scenario_states(
        step.layout,
        batches=step.batches.values(),
        envs=step.envs,
        assessments=judged,
        retries=step.spec.execution.retries,
    )
    if cancellation is None:
        return current
    return cancelling.states(current, step.layout, cancellation, batches=step.batches.keys())


def in_flight(step: Step, judged: Mapping[str, Assessment]) -> int:
    """Environments that still hold (or are about to hold) a simulator slot."""
    return sum(1 for env in step.envs if not env.deleting and not judged[env.name].ended)
