"""``provisioner: Helmfile`` teardown: destroy Jobs for ended environments, and their clean-up.

Pure, like :mod:`provisioning` (which provisions): an ended or deleted environment whose releases
may exist gets a ``helmfile destroy`` Job owned by its ScenarioBatch, so the Job outlives the
environment object; the environment may go once that Job is recorded (:func:`torn_down`).
Finished destroy Jobs are deleted; a failed one is reported on its batch first.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from simtest_operator.api.v1alpha1 import API_VERSION, TestCampaignSpec
from simtest_operator.errors import RenderError
from simtest_operator.operator import provisioning, requests
from simtest_operator.operator.actions import Action, Delete, Emit, Kind, RunHelmfile
from simtest_operator.operator.jobviews import JobView
from simtest_operator.operator.observed import BatchView, EnvironmentView, PodView
from simtest_operator.operator.provisioning import Renderer
from simtest_operator.packaging import helmfilejobs
from simtest_operator.packaging.helmfilejobs import Action as JobAction
from simtest_operator.packaging.helmfilejobs import Owner
from simtest_operator.settings import OperatorSettings


def _applied(env: EnvironmentView, jobs: Mapping[str, JobView]) -> bool:
    """Whether a sync Job was (possibly) created, so there may be releases to destroy."""
    return provisioning.recorded_jobs(env).sync is not None or provisioning.sync_job(env) in jobs


def torn_down(env: EnvironmentView, jobs: Mapping[str, JobView]) -> bool:
    """Whether the environment object may go: nothing to destroy, or the destroy Job exists
    (it is owned by the batch and runs on without the environment)."""
    return provisioning.recorded_jobs(env).destroy is not None or not _applied(env, jobs)


def teardown(
    spec: TestCampaignSpec,
    env: EnvironmentView,
    *,
    jobs: Mapping[str, JobView],
    batch: BatchView | None,
    render: Renderer,
    config: OperatorSettings,
) -> tuple[Action, ...]:
    """Actions that destroy the releases of an ended (or deleted) Helmfile environment."""
    if not (env.finished or env.deleting) or not _applied(env, jobs):
        return ()
    if provisioning.recorded_jobs(env).destroy is not None or provisioning.destroy_job(env) in jobs:
        return ()
    sync = jobs.get(provisioning.sync_job(env))
    if sync is not None and not sync.done and not sync.deleting and not env.deleting:
        # helm must not install while it uninstalls: stop the sync first (its pod goes with it).
        return (Delete(kind=Kind.JOB, name=sync.name, uid=sync.uid),)
    if sync is not None and not sync.done:
        return ()
    if batch is None or not config.helmfile.image:
        return ()
    request = requests.environment_request(spec, env, config=config)
    try:
        rendered = render(request)
        if rendered.helmfile is None:
            return ()
        job_request = provisioning.job_request(
            env,
            action=JobAction.DESTROY,
            helmfile=rendered.helmfile,
            owner=Owner(
                api_version=API_VERSION, kind="ScenarioBatch", name=batch.name, uid=batch.uid
            ),
            spec=spec,
            config=config,
        )
        job = helmfilejobs.job(job_request)
        config_map = helmfilejobs.config_map(job_request)
    except RenderError:
        return ()
    return (
        RunHelmfile(
            environment=env.name,
            job=job,
            config_map=config_map,
            config_map_owned_by_job=True,
            status=None if env.deleting else {"jobs": {"destroy": job["metadata"]["name"]}},
            scenario_ids=env.scenario_ids,
            attempt=env.attempt,
        ),
    )


def teardowns(
    spec: TestCampaignSpec,
    envs: Iterable[EnvironmentView],
    *,
    jobs: Mapping[str, JobView],
    pods: Mapping[str, PodView],
    batches: Iterable[BatchView],
    render: Renderer,
    config: OperatorSettings,
) -> tuple[Action, ...]:
    """Every teardown action of one planning step: destroy Jobs for ended environments, and the
    clean-up of finished destroy Jobs."""
    by_name = {b.name: b for b in batches}
    actions: list[Action] = []
    for env in envs:
        actions.extend(
            teardown(
                spec, env, jobs=jobs, batch=by_name.get(env.batch), render=render, config=config
            )
        )
    actions.extend(collect(jobs.values(), pods=pods, batches=by_name.values()))
    return tuple(actions)


def collect(
    jobs: Iterable[JobView], *, pods: Mapping[str, PodView], batches: Iterable[BatchView]
) -> tuple[Action, ...]:
    """Delete finished destroy Jobs (their pods and ConfigMaps go with them); a failed one is
    reported on its batch first, with helmfile's output tail, since the Job's pod goes too."""
    by_name = {b.name: b for b in batches}
    actions: list[Action] = []
    for job in jobs:
        if job.action != JobAction.DESTROY.value or not job.done or job.deleting:
            continue
        if job.failed:
            batch = by_name.get(job.batch)
            if batch is not None:
                actions.append(
                    Emit(
                        kind=Kind.BATCH,
                        name=batch.name,
                        uid=batch.uid,
                        reason="HelmfileDestroyFailed",
                        message=provisioning.job_failure(job, pods)
                        + f"; releases of {job.environment} may remain (helm list -n "
                        f"{job.namespace})",
                        warning=True,
                        terminal=True,
                    )
                )
        actions.append(Delete(kind=Kind.JOB, name=job.name, uid=job.uid))
    return tuple(actions)
