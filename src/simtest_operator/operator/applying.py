"""Applying a plan through the API client: concurrent, idempotent, with expectations.

Actions of one plan are independent of each other (the planner only creates environments in
batches it has seen, and only deletes pods of environments whose status it has seen), so they are
sent concurrently. Each successful write yields the expectation the next planning step waits
for. A ``ConflictError`` on a conditional status patch means our view was stale: nothing is written
and the loop plans again from fresh state. A create the API server refuses for good (400, 403,
422: an invalid body, missing RBAC, admission) ends what it served as ``Error`` with the server's
words: a pod or a helmfile Job in its environment's status, written here; any other object is
reported back (:attr:`Applied.refused`) for the planner to word in its owner's status. Events are
rate limited per object.
"""

from __future__ import annotations

import asyncio
import dataclasses
import datetime
import logging
from collections.abc import Callable, Mapping
from typing import Any

from simtest_operator.errors import ClusterError, RenderError
from simtest_operator.operator import bodies, names, observed
from simtest_operator.operator.actions import (
    Action,
    Create,
    Delete,
    Emit,
    Kind,
    PatchStatus,
    Plan,
    Provision,
    RunHelmfile,
)
from simtest_operator.operator.client import (
    AlreadyExistsError,
    ApiError,
    Client,
    ConflictError,
    NotFoundError,
)
from simtest_operator.operator.expectations import Expectation, Want
from simtest_operator.operator.metrics import Metrics
from simtest_operator.operator.status import environmentstatus
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment

log = logging.getLogger(__name__)

REFUSED_FOR_GOOD = frozenset({400, 403, 422})
"""API answers to a create that every retry would get the same way (malformed, forbidden,
invalid): the object it served ends ``Error`` instead of being retried."""

KIND_NAMES = {
    Kind.CAMPAIGN: "TestCampaign",
    Kind.BATCH: "ScenarioBatch",
    Kind.ENVIRONMENT: "SimEnvironment",
}

_EVENT_KEYS_KEPT = 256
"""Rate-limit entries kept at least before the expired ones are dropped."""


@dataclasses.dataclass(slots=True)
class Applied:
    """What applying one plan produced."""

    expectations: list[Expectation] = dataclasses.field(default_factory=list)
    conflict: bool = False
    failures: int = 0
    campaign_written: bool = False
    refused: dict[tuple[Kind, str], str] = dataclasses.field(default_factory=dict)
    """Creates the API server refused for good (:data:`REFUSED_FOR_GOOD`), by kind and name:
    its status code and message (also counted in ``failures``)."""


@dataclasses.dataclass(slots=True)
class Applier:
    """Applies plans of one campaign."""

    client: Client
    namespace: str
    campaign: str
    campaign_uid: Callable[[], str]
    metrics: Metrics
    event_interval: float
    parallel: int = 16
    render: Callable[[EnvironmentRequest], RenderedEnvironment] | None = None
    """Renders pods of environments created in the same step (see ``Create.provision``)."""
    _last_event: dict[tuple[Kind, str, str], datetime.datetime] = dataclasses.field(
        default_factory=dict
    )
    """Last event per (object, reason): repeats of one reason are limited, a new phase is not.
    Entries older than ``event_interval`` limit nothing and are dropped (one per batch and
    environment would otherwise stay for the whole campaign)."""
    _prune_at: int = _EVENT_KEYS_KEPT
    _identities_ready: bool = False
    """The campaign's helmfile identities were created (or found) by this applier: once per
    operator run, not once per environment."""

    async def apply(self, plan: Plan, *, now: datetime.datetime) -> Applied:
        """Send every action; never raises for API errors (they are counted and logged)."""
        applied = Applied()
        gate = asyncio.Semaphore(self.parallel)

        async def one(action: Action) -> None:
            async with gate:
                try:
                    await self._one(action, applied, now=now)
                except ConflictError as exc:
                    applied.conflict = True
                    log.info(
                        "%s/%s: %s; planning again from fresh state",
                        self.namespace,
                        self.campaign,
                        exc,
                    )
                except ClusterError as exc:
                    applied.failures += 1
                    log.warning(
                        "%s/%s: %s failed: %s",
                        self.namespace,
                        self.campaign,
                        type(action).__name__,
                        exc,
                    )

        await asyncio.gather(*(one(a) for a in plan.actions))
        return applied

    async def _one(self, action: Action, applied: Applied, *, now: datetime.datetime) -> None:
        if isinstance(action, Create):
            try:
                created: dict[str, Any] | None = await self.client.create(
                    action.kind, self.namespace, action.body
                )
            except AlreadyExistsError:
                created = None
            except ApiError as exc:
                # A Workload's 404: Kueue's CRDs are not installed (or the namespace is gone).
                if exc.status in REFUSED_FOR_GOOD or (
                    exc.status == 404 and action.kind is Kind.WORKLOAD
                ):
                    applied.refused[(action.kind, action.name)] = str(exc)
                raise
            applied.expectations.append(
                Expectation(kind=action.kind, name=action.name, want=Want.PRESENT)
            )
            if created is not None and action.provision is not None and self.render is not None:
                await self._provision_new(created, action.provision, applied, now=now)
        elif isinstance(action, Provision):
            await self._provision(action, applied, now=now)
        elif isinstance(action, RunHelmfile):
            await self._run_helmfile(action, applied, now=now)
        elif isinstance(action, PatchStatus):
            reply = await self.client.patch_status(
                action.kind,
                self.namespace,
                action.name,
                action.patch,
                resource_version=action.resource_version,
            )
            version = str((reply.get("metadata") or {}).get("resourceVersion", ""))
            applied.expectations.append(
                Expectation(kind=action.kind, name=action.name, want=Want.VERSION, version=version)
            )
            if action.kind is Kind.CAMPAIGN:
                applied.campaign_written = True
            for record in action.folded:
                self.metrics.scenarios.labels(
                    namespace=self.namespace, campaign=self.campaign, verdict=record.verdict.value
                ).inc()
        elif isinstance(action, Delete):
            await self.client.delete(
                action.kind,
                self.namespace,
                action.name,
                uid=action.uid,
                grace_seconds=action.grace_seconds,
            )
            applied.expectations.append(
                Expectation(kind=action.kind, name=action.name, want=Want.ABSENT)
            )
        else:
            await self._emit(action, now=now)

    async def _provision_new(
        self,
        created: Mapping[str, Any],
        request: EnvironmentRequest,
        applied: Applied,
        *,
        now: datetime.datetime,
    ) -> None:
        assert self.render is not None
        env = observed.environment_view(created)
        owner = dataclasses.replace(request.owner, uid=env.uid)
        try:
            rendered = self.render(dataclasses.replace(request, owner=owner))
        except RenderError:
            return  # the next planning step records the render failure
        provision = Provision(
            environment=env.name,
            pod=rendered.pod,
            status=environmentstatus.provisioned_status(
                env, pod=env.name, rendered_hash=rendered.content_hash, now=now
            ),
            scenario_ids=env.scenario_ids,
            attempt=env.attempt,
        )
        await self._provision(provision, applied, now=now)

    async def _provision(
        self, action: Provision, applied: Applied, *, now: datetime.datetime
    ) -> None:
        for attempt in range(2):
            try:
                await self.client.create(Kind.POD, self.namespace, action.pod)
                break
            except AlreadyExistsError:
                break
            except ApiError as exc:
                if attempt == 0 and exc.status == 403 and "serviceaccount" in str(exc).lower():
                    await self._ensure_service_account()
                    continue
                if exc.status in (400, 422):
                    await self._rejected(action, exc, now=now)
                    return
                raise
        reply = await self.client.patch_status(
            Kind.ENVIRONMENT, self.namespace, action.environment, action.status
        )
        applied.expectations.append(
            Expectation(kind=Kind.POD, name=action.environment, want=Want.PRESENT)
        )
        applied.expectations.append(_written(action.environment, reply))

    async def _create(self, kind: Kind, body: Mapping[str, Any]) -> dict[str, Any] | None:
        """Create; None when it exists already."""
        try:
            return await self.client.create(kind, self.namespace, body)
        except AlreadyExistsError:
            return None

    async def _run_helmfile(
        self, action: RunHelmfile, applied: Applied, *, now: datetime.datetime
    ) -> None:
        job_name = str(action.job["metadata"]["name"])
        try:
            if action.identities and not self._identities_ready:
                for kind, body in action.identities:
                    await self._create(kind, body)
                self._identities_ready = True
            if not action.config_map_owned_by_job:
                await self._create(Kind.CONFIG_MAP, action.config_map)
            job = await self._create(Kind.JOB, action.job)
            if action.config_map_owned_by_job:
                if job is None:
                    job = await self.client.get(Kind.JOB, self.namespace, job_name)
                await self._create(Kind.CONFIG_MAP, _owned_by_job(action.config_map, job))
        except ApiError as exc:
            if action.status is None or exc.status not in REFUSED_FOR_GOOD:
                raise
            # Refused for good (RBAC, admission, an invalid spec): every attempt would be refused
            # the same way, so the environment ends as Error with the server's words.
            status = environmentstatus.failed_status(
                action.scenario_ids,
                attempt=action.attempt,
                reason=f"the API server refused the helmfile Job {job_name}: {exc}",
                now=now,
            )
            await self.client.patch_status(
                Kind.ENVIRONMENT, self.namespace, action.environment, status
            )
            return
        applied.expectations.append(Expectation(kind=Kind.JOB, name=job_name, want=Want.PRESENT))
        if action.status is None:
            return
        try:
            reply = await self.client.patch_status(
                Kind.ENVIRONMENT, self.namespace, action.environment, action.status
            )
        except NotFoundError:
            return  # the environment went meanwhile; its destroy Job runs on regardless
        applied.expectations.append(_written(action.environment, reply))

    async def _rejected(self, action: Provision, exc: ApiError, *, now: datetime.datetime) -> None:
        """The API server refuses the pod (admission, invalid spec): every attempt would be
        refused the same way, so the environment ends as Error with the server's words."""
        status = environmentstatus.failed_status(
            action.scenario_ids,
            attempt=action.attempt,
            reason=f"the API server rejected the simulator pod: {exc}",
            now=now,
        )
        await self.client.patch_status(Kind.ENVIRONMENT, self.namespace, action.environment, status)

    async def _ensure_service_account(self) -> None:
        body = bodies.service_account(
            campaign=self.campaign, namespace=self.namespace, campaign_uid=self.campaign_uid()
        )
        try:
            await self.client.create(Kind.SERVICE_ACCOUNT, self.namespace, body)
        except AlreadyExistsError:
            return

    async def _emit(self, action: Emit, *, now: datetime.datetime) -> None:
        key = (action.kind, action.name, action.reason)
        last = self._last_event.get(key)
        if (
            not action.terminal
            and last is not None
            and (now - last).total_seconds() < self.event_interval
        ):
            return
        if len(self._last_event) >= self._prune_at:  # amortised: the bound doubles past it
            self._last_event = {
                k: t
                for k, t in self._last_event.items()
                if (now - t).total_seconds() < self.event_interval
            }
            self._prune_at = max(_EVENT_KEYS_KEPT, 2 * len(self._last_event))
        self._last_event[key] = now
        involved = {
            "apiVersion": "simtest.dev/v1alpha1",
            "kind": KIND_NAMES.get(action.kind, str(action.kind)),
            "name": action.name,
            "namespace": self.namespace,
            "uid": action.uid,
        }
        body = bodies.event(
            involved=involved,
            reason=action.reason,
            message=action.message,
            warning=action.warning,
            now=now,
            component=names.MANAGED_BY,
        )
        await self.client.create("events", self.namespace, body)


def _owned_by_job(config_map: Mapping[str, Any], job: Mapping[str, Any]) -> dict[str, Any]:
    """The destroy Job's ConfigMap, owned by that Job (deleting the Job removes it). Nothing
    needs to block the Job's deletion on it, so no ``blockOwnerDeletion`` (which would need
    ``update`` on ``jobs/finalizers`` where OwnerReferencesPermissionEnforcement is on)."""
    meta = job.get("metadata") or {}
    reference = {
        "apiVersion": "batch/v1",
        "kind": "Job",
        "name": str(meta.get("name", "")),
        "uid": str(meta.get("uid", "")),
        "controller": True,
    }
    body = dict(config_map)
    body["metadata"] = {**dict(config_map["metadata"]), "ownerReferences": [reference]}
    return body


def _written(environment: str, reply: Mapping[str, Any]) -> Expectation:
    """Expect the cache to catch up with the environment version a status write returned."""
    version = str((reply.get("metadata") or {}).get("resourceVersion", ""))
    return Expectation(kind=Kind.ENVIRONMENT, name=environment, want=Want.VERSION, version=version)
