"""Each environment after its assessment: record it, provision a missing pod, delete a done one.

The order that keeps results durable starts here: a pod is deleted only once its environment's
status holds the verdicts (``env.finished``), so a crash in between loses nothing.
"""

from __future__ import annotations

from collections.abc import Mapping

from simtest_operator.errors import RenderError
from simtest_operator.operator import environments, provisioning, requests
from simtest_operator.operator.actions import Action, Delete, Kind, PatchStatus, Provision
from simtest_operator.operator.environments import Assessment
from simtest_operator.operator.observed import EnvironmentView, PodView
from simtest_operator.operator.planning.inputs import Step
from simtest_operator.operator.planning.outcomes import Outcome
from simtest_operator.operator.status import environmentstatus, patches


def tend(step: Step, judged: Mapping[str, Assessment]) -> Outcome:
    """Every environment of the campaign, in order."""
    outcome = Outcome()
    for env in step.envs:
        outcome += _environment(step, env, judged[env.name])
    return outcome


def _environment(step: Step, env: EnvironmentView, assessment: Assessment) -> Outcome:
    if env.deleting:
        return Outcome()
    wakes = (assessment.wake_at,) if assessment.wake_at is not None else ()
    if assessment.needs_pod:
        return Outcome(actions=(_provision(step, env),), wakes=wakes)
    actions: list[Action] = []
    latencies: list[float] = []
    desired = environmentstatus.desired_status(env, assessment)
    patch = patches.changed_fields(desired, env.status_wire)
    if patch:
        actions.append(PatchStatus(kind=Kind.ENVIRONMENT, name=env.name, patch=patch))
        started = assessment.timings.started
        queued = assessment.timings.queued
        if started and queued and "started" not in (env.status_wire.get("timings") or {}):
            latencies.append(max((started - queued).total_seconds(), 0.0))
    pod = step.inputs.pods.get(env.status.pod or env.name)
    if env.finished and pod is not None:
        actions.extend(_release(step, pod))
    return Outcome(actions=tuple(actions), wakes=wakes, start_latencies=tuple(latencies))


def _release(step: Step, pod: PodView) -> tuple[Action, ...]:
    """Delete the pod of a finished environment, at once where nothing is left to stop.

    Without grace when its node is gone (a graceful delete there never completes) and when its
    simulator container has exited: the kubelet marks such a pod terminal only a PLEG relist
    (about 1 s) after the exit, and until then the scheduler counts its slot as taken, so the
    next pod would wait that second. Removing the object hands the slot over at once; the
    kubelet tears the sandbox down in the background. A pod still running is deleted
    gracefully, so its runner gets SIGTERM and keeps what it finished.
    """
    gone = environments.node_gone(pod, step.inputs.nodes)
    force = gone or (pod.container.state == "terminated" and step.config.pacing.release_exited)
    if pod.deleting and not force:
        return ()
    return (Delete(kind=Kind.POD, name=pod.name, uid=pod.uid, grace_seconds=0 if force else None),)


def _provision(step: Step, env: EnvironmentView) -> Action:
    """The pod (or helmfile sync Job) of an environment that has none, or its Error status
    when the pod cannot be rendered."""
    spec = step.spec
    request = requests.environment_request(spec, env, config=step.config, run_key=step.run_key)
    try:
        rendered = step.render(request)
    except RenderError as exc:
        status = environmentstatus.failed_status(
            env.scenario_ids,
            attempt=env.attempt,
            reason=f"cannot render the pod: {exc}",
            now=step.now,
        )
        return PatchStatus(kind=Kind.ENVIRONMENT, name=env.name, patch=status)
    if provisioning.uses_helmfile(spec):
        return provisioning.provision(
            spec, env, rendered, config=step.config, campaign_uid=step.campaign.uid, now=step.now
        )
    return Provision(
        environment=env.name,
        pod=rendered.pod,
        status=environmentstatus.provisioned_status(
            env, pod=env.name, rendered_hash=rendered.content_hash, now=step.now
        ),
        scenario_ids=env.scenario_ids,
        attempt=env.attempt,
    )
