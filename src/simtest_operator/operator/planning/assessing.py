"""What each environment and each scenario of the campaign is doing now.

Every later phase works on these judgements; under a cancellation they already say how each
attempt and each unstarted scenario ends (:mod:`simtest_operator.operator.cancelling`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from simtest_operator.operator import cancelling, provisioning
from simtest_operator.operator.batches import Progress, progress
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
            seen=(env.status.pod or env.name) in inputs.seen_pods,
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
) -> Progress:
    """Every scenario's state (only the open batches' spelled out)."""
    current = progress(
        step.layout,
        batches=step.batches,
        closed=step.closed,
        envs=step.envs,
        assessments=judged,
        retries=step.spec.execution.retries,
    )
    if cancellation is None:
        return current
    ended = cancelling.states(
        tuple(current.explicit.values()), step.layout, cancellation, batches=step.batches.keys()
    )
    return dataclasses.replace(
        current, explicit={s.position: s for s in ended}, skipped_absent=True
    )


def in_flight(step: Step, judged: Mapping[str, Assessment]) -> int:
    """Environments that still hold (or are about to hold) a simulator slot."""
    return sum(1 for env in step.envs if not env.deleting and not judged[env.name].ended)
