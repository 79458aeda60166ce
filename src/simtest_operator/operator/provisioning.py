"""``provisioner: Helmfile``: how an environment is provisioned and torn down through helmfile Jobs.

Pure, like :mod:`environments`: views and the clock in, actions and assessments out; the applier
does the I/O. The Pod provisioner (the default fast path) creates the rendered simulator pod
directly; the Helmfile provisioner instead runs the real ``helmfile`` binary in a Job on the
rendered, run-specific helmfile, whose simulator release installs exactly that pod (same name,
labels, ownerReferences — ``render.helmfiles`` checks it). From the moment the pod exists both
paths are judged by the same :func:`environments.assess`.

Lifecycle of a Helmfile environment (names from ``packaging.helmfilejobs``)::

    Pending       campaign identities (the simulator ServiceAccount, the helmfile Jobs'
                  ServiceAccount and its RoleBinding to the provisioner ClusterRole, all owned by
                  the campaign); ConfigMap <env>-hf-sync and Job <env>-hf-sync (owned by the
                  environment); status: provisioner, jobs.sync, renderedHash
    Provisioning  the sync Job runs; a failed Job ends the attempt as Error with the Job's
                  reason and its pod's termination message (helmfile's output)
    ...           the simulator pod, exactly as with the Pod provisioner
    Finished      Job <env>-hf-destroy (owned by the ScenarioBatch, so it outlives the
                  environment) and its ConfigMap (owned by that Job); status: jobs.destroy.
                  Only then may the environment be deleted. A finished destroy Job is deleted
                  (with its pod and ConfigMap); a failed one is reported as a Warning event
                  (the teardown half lives in :mod:`helmfileteardown`).
"""

from __future__ import annotations

import datetime
from collections.abc import Callable, Mapping
from typing import Any

from simtest_operator.api.v1alpha1 import (
    API_VERSION,
    EnvironmentPhase,
    Provisioner,
    TestCampaignSpec,
    Timings,
)
from simtest_operator.api.v1alpha1.kinds import HelmfileJobs
from simtest_operator.errors import RenderError
from simtest_operator.operator import bodies, environments, jobviews, names
from simtest_operator.operator.actions import Action, Kind, PatchStatus, RunHelmfile
from simtest_operator.operator.environments import Assessment, Limits
from simtest_operator.operator.observed import (
    EnvironmentView,
    NodeView,
    PodView,
)
from simtest_operator.operator.status import environmentstatus
from simtest_operator.operator.status.records import clip
from simtest_operator.packaging import helmfilejobs
from simtest_operator.packaging.helmfilejobs import Action as JobAction
from simtest_operator.packaging.helmfilejobs import HelmfileJobRequest, Owner
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment
from simtest_operator.settings import OperatorSettings
from simtest_operator.verdicts import Verdict

HELMFILE = Provisioner.HELMFILE.value
Renderer = Callable[[EnvironmentRequest], RenderedEnvironment]


def uses_helmfile(spec: TestCampaignSpec) -> bool:
    """The campaign's environments are provisioned by helmfile Jobs."""
    return spec.environment.provisioner is Provisioner.HELMFILE


_NO_JOBS = HelmfileJobs()


def recorded_jobs(env: EnvironmentView) -> HelmfileJobs:
    """The helmfile Jobs the environment's status records (none before provisioning)."""
    return env.status.jobs or _NO_JOBS


def sync_job(env: EnvironmentView) -> str:
    """Name of the environment's ``helmfile sync`` Job."""
    return recorded_jobs(env).sync or helmfilejobs.job_name(env.name, JobAction.SYNC)


def destroy_job(env: EnvironmentView) -> str:
    """Name of the environment's ``helmfile destroy`` Job."""
    return recorded_jobs(env).destroy or helmfilejobs.job_name(env.name, JobAction.DESTROY)


# --- judging -----------------------------------------------------------------------------------


def assess(
    env: EnvironmentView,
    pod: PodView | None,
    *,
    jobs: Mapping[str, jobviews.JobView],
    pods: Mapping[str, PodView],
    nodes: Mapping[str, NodeView] | None,
    now: datetime.datetime,
    limits: Limits,
    seen: bool = False,
) -> Assessment:
    """Judge one environment: its pod as :func:`environments.assess` does, and before the pod
    exists (or if provisioning breaks) its helmfile sync Job."""
    if env.status.provisioner != HELMFILE or env.finished or env.deleting:
        return environments.assess(env, pod, nodes=nodes, now=now, limits=limits, seen=seen)
    job = jobs.get(sync_job(env))
    if pod is not None:
        judged = environments.assess(env, pod, nodes=nodes, now=now, limits=limits, seen=seen)
        if judged.ended or job is None or not job.failed:
            return judged
        # The simulator started but the rest of the stack did not install: not a usable run.
        return _error(env, job_failure(job, pods), now=now, delete_pod=True, node=pod.node_name)
    queued = env.status.timings.queued or env.created
    timings = env.status.timings.model_copy(update={"queued": queued})
    if job is None:
        since = env.provisioned_at or queued or now
        grace_end = since + datetime.timedelta(seconds=limits.missing_grace)
        if now < grace_end:
            return _provisioning(timings, until=grace_end)
        return _error(
            env,
            f"helmfile sync Job {sync_job(env)} disappeared before the simulator pod appeared",
            now=now,
        )
    if job.failed:
        return _error(env, job_failure(job, pods), now=now)
    if job.succeeded:
        since = job.finished_at or now
        grace_end = since + datetime.timedelta(seconds=limits.missing_grace)
        if now < grace_end:
            return _provisioning(timings, until=grace_end)
        return _error(
            env,
            f"helmfile sync Job {job.name} succeeded but installed no simulator pod "
            f"{env.status.pod or env.name} (the template's helmfile must install the rendered pod "
            "with the simtest-simulator chart)",
            now=now,
        )
    # Running: the Job's activeDeadlineSeconds (pendingTimeoutSeconds) ends it; the backstop
    # covers a cluster whose Job controller does not.
    started = job.created or env.provisioned_at or now
    backstop = started + datetime.timedelta(seconds=limits.pending_seconds + limits.backstop_grace)
    if now >= backstop:
        return _error(
            env,
            f"helmfile sync Job {job.name} still running after "
            f"{(now - started).total_seconds():.0f}s (pendingTimeoutSeconds "
            f"{limits.pending_seconds:.0f})",
            now=now,
        )
    return Assessment(
        phase=EnvironmentPhase.PROVISIONING,
        node=None,
        timings=timings,
        results=None,
        wake_at=backstop,
    )


def job_failure(job: jobviews.JobView, pods: Mapping[str, PodView]) -> str:
    """Why a Job failed: its condition and the termination message of its last pod (helmfile's
    output tail, through ``FallbackToLogsOnError``)."""
    last = jobviews.last_run(job, pods)
    detail = ""
    if last is not None:
        container = last.container
        lines = [line.strip() for line in container.message.strip().splitlines() if line.strip()]
        tail = " | ".join(lines[-3:])
        exit_text = f"exit code {container.exit_code}" if container.exit_code is not None else ""
        detail = ": " + "; ".join(p for p in (exit_text, tail) if p) if (exit_text or tail) else ""
    cause = f" ({job.reason})" if job.reason else ""
    action = job.action or "sync"
    return clip(f"helmfile {action} Job {job.name} failed{cause}{detail}")


def _provisioning(timings: Timings, *, until: datetime.datetime) -> Assessment:
    """Still provisioning: look again at ``until`` (the end of a grace period)."""
    return Assessment(
        phase=EnvironmentPhase.PROVISIONING, node=None, timings=timings, results=None, wake_at=until
    )


def _error(
    env: EnvironmentView,
    reason: str,
    *,
    now: datetime.datetime,
    delete_pod: bool = False,
    node: str | None = None,
) -> Assessment:
    timings = env.status.timings.model_copy(
        update={"queued": env.status.timings.queued or env.created, "finished": now}
    )
    records = environments.failed_records(
        env, Verdict.ERROR, reason, started=timings.started, end=now
    )
    return Assessment(
        phase=EnvironmentPhase.FINISHED,
        node=node or env.status.node,
        timings=timings,
        results=records,
        reason=reason,
        delete_pod=delete_pod,
    )


# --- provisioning ------------------------------------------------------------------------------


def _labels(env: EnvironmentView) -> dict[str, str]:
    """The campaign label (the operator watches Jobs and their pods by it), batch and attempt."""
    labels = names.environment_labels(env.campaign, env.batch, env.attempt)
    labels.pop(names.LABEL_COMPONENT, None)
    return labels


def identities(
    *, campaign: str, namespace: str, campaign_uid: str, role: str
) -> tuple[tuple[Kind, dict[str, Any]], ...]:
    """The campaign's ServiceAccounts (simulator pods, helmfile Jobs) and the RoleBinding of the
    Jobs' account to the provisioner ClusterRole, in creation order (owned by the campaign)."""
    owner = Owner(api_version=API_VERSION, kind="TestCampaign", name=campaign, uid=campaign_uid)
    labels = names.campaign_labels(campaign)
    return (
        (
            Kind.SERVICE_ACCOUNT,
            bodies.service_account(
                campaign=campaign, namespace=namespace, campaign_uid=campaign_uid
            ),
        ),
        (
            Kind.SERVICE_ACCOUNT,
            helmfilejobs.service_account(
                campaign=campaign, namespace=namespace, owner=owner, labels=labels
            ),
        ),
        (
            Kind.ROLE_BINDING,
            helmfilejobs.role_binding(
                campaign=campaign,
                namespace=namespace,
                cluster_role=role,
                owner=owner,
                labels=labels,
            ),
        ),
    )


def job_request(
    env: EnvironmentView,
    *,
    action: JobAction,
    helmfile: str,
    owner: Owner,
    spec: TestCampaignSpec,
    config: OperatorSettings,
) -> HelmfileJobRequest:
    return HelmfileJobRequest(
        environment=env.name,
        namespace=env.namespace,
        action=action,
        helmfile=helmfile,
        image=config.helmfile.image,
        service_account=helmfilejobs.service_account_name(env.campaign),
        owner=owner,
        labels=_labels(env),
        deadline_seconds=int(spec.execution.pending_timeout_seconds),
        node_selector=config.helmfile.node_selector,
    )


def provision(
    spec: TestCampaignSpec,
    env: EnvironmentView,
    rendered: RenderedEnvironment,
    *,
    config: OperatorSettings,
    campaign_uid: str,
    now: datetime.datetime,
) -> Action:
    """The action that provisions a Helmfile environment: its sync Job (or, when it cannot be
    made, the environment's Error status)."""
    problem = ""
    if not config.helmfile.image or not config.helmfile.role:
        problem = (
            "provisioner Helmfile is not enabled in this operator (no helmfile image or "
            "provisioner role: chart value helmfileProvisioner.enabled, or "
            "SIMTEST_OPERATOR_HELMFILE_IMAGE and SIMTEST_OPERATOR_HELMFILE_ROLE)"
        )
    elif rendered.helmfile is None:
        problem = f"environment template {spec.environment.template!r} has no helmfile.yaml.j2"
    if problem:
        return _failed(env, problem, now=now)
    assert rendered.helmfile is not None
    request = job_request(
        env,
        action=JobAction.SYNC,
        helmfile=rendered.helmfile,
        owner=Owner(api_version=API_VERSION, kind="SimEnvironment", name=env.name, uid=env.uid),
        spec=spec,
        config=config,
    )
    try:
        job = helmfilejobs.job(request)
        config_map = helmfilejobs.config_map(request)
    except RenderError as exc:
        return _failed(env, f"cannot make the helmfile sync Job: {exc}", now=now)
    return RunHelmfile(
        environment=env.name,
        job=job,
        config_map=config_map,
        identities=identities(
            campaign=env.campaign,
            namespace=env.namespace,
            campaign_uid=campaign_uid,
            role=config.helmfile.role,
        ),
        status=environmentstatus.provisioned_status(
            env,
            pod=env.name,
            rendered_hash=rendered.content_hash,
            now=now,
            provisioner=HELMFILE,
            sync_job=job["metadata"]["name"],
        ),
        scenario_ids=env.scenario_ids,
        attempt=env.attempt,
    )


def _failed(env: EnvironmentView, reason: str, *, now: datetime.datetime) -> PatchStatus:
    status = environmentstatus.failed_status(
        env.scenario_ids, attempt=env.attempt, reason=reason, now=now
    )
    return PatchStatus(kind=Kind.ENVIRONMENT, name=env.name, patch=status)
