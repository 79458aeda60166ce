"""Actions: what a plan asks the API client to do. Plain data, applied by ``controlling``.

Every action is idempotent against the API (creates of deterministic names tolerate
``AlreadyExists``, deletes tolerate ``NotFound``), so applying a plan twice — after a crash, or from
a stale cache — changes nothing the second time.
"""

from __future__ import annotations

import dataclasses
import datetime
import enum
from collections.abc import Mapping
from typing import Any

from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.render import EnvironmentRequest


class Kind(enum.StrEnum):
    """Object kinds the operator writes."""

    CAMPAIGN = "testcampaigns"
    BATCH = "scenariobatches"
    ENVIRONMENT = "simenvironments"
    POD = "pods"
    CONFIG_MAP = "configmaps"
    SERVICE_ACCOUNT = "serviceaccounts"
    JOB = "jobs"
    ROLE_BINDING = "rolebindings"
    WORKLOAD = "workloads"
    """Kueue's (``spec.execution.queueName``; :mod:`~simtest_operator.operator.admission`)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Create:
    """Create an object (``AlreadyExists`` counts as done)."""

    kind: Kind
    body: Mapping[str, Any]
    provision: EnvironmentRequest | None = None
    """For a SimEnvironment: its pod's render request (owner uid still empty). The applier fills
    in the uid the create returns and provisions the pod at once, saving a watch round trip per
    scenario; if anything goes wrong the next planning step provisions it instead."""

    @property
    def name(self) -> str:
        """Name of the object to create."""
        return str(self.body["metadata"]["name"])


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Provision:
    """Create a SimEnvironment's pod, then record it in the environment's status."""

    environment: str
    pod: Mapping[str, Any]
    status: Mapping[str, Any]
    scenario_ids: tuple[str, ...] = ()
    attempt: int = 1


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunHelmfile:
    """Start a helmfile Job of an environment (``provisioner: Helmfile``): make sure the campaign's
    identities exist (``identities``, created once per operator run), create the ConfigMap with
    the rendered helmfile and the Job, then merge ``status`` into the environment's status.

    A ``sync`` ConfigMap is owned by the environment; a ``destroy`` Job is owned by the batch (it
    outlives the environment) and its ConfigMap by the Job itself (``config_map_owned_by_job``:
    the applier fills in the Job's uid), so deleting the finished Job removes both."""

    environment: str
    job: Mapping[str, Any]
    config_map: Mapping[str, Any]
    config_map_owned_by_job: bool = False
    identities: tuple[tuple[Kind, Mapping[str, Any]], ...] = ()
    status: Mapping[str, Any] | None = None
    scenario_ids: tuple[str, ...] = ()
    attempt: int = 1


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PatchStatus:
    """Merge-patch the status subresource; with ``resource_version`` the patch is conditional
    (``409 ConflictError`` when someone else wrote in between: re-plan from fresh state)."""

    kind: Kind
    name: str
    patch: Mapping[str, Any]
    resource_version: str | None = None
    folded: tuple[ResultRecord, ...] = ()
    """Results this patch records for the first time (counted in metrics once it succeeds)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Delete:
    """Delete an object (``NotFoundError`` counts as done)."""

    kind: Kind
    name: str
    uid: str | None = None
    """Precondition: delete only this incarnation."""
    grace_seconds: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Emit:
    """Post a Kubernetes Event about an object (rate limited by the applier)."""

    kind: Kind
    name: str
    uid: str
    reason: str
    message: str
    warning: bool = False
    terminal: bool = False
    """Terminal events bypass the rate limit."""


Action = Create | Provision | RunHelmfile | PatchStatus | Delete | Emit


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Observation:
    """Numbers a plan exposes for metrics (gauges, latencies)."""

    in_flight: int = 0
    queued: int = 0
    window: int = 0
    start_latencies: tuple[float, ...] = ()
    """Seconds from environment creation to container start, for environments that started."""
    overheads: tuple[float, ...] = ()
    """Seconds of orchestration per scenario folded (wall time of the attempt minus run time)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Plan:
    """The actions of one reconcile step, in the order they must be applied."""

    actions: tuple[Action, ...] = ()
    wake_at: datetime.datetime | None = None
    """When to plan again even if nothing changes (a time limit, a deferred status write)."""
    observation: Observation = dataclasses.field(default_factory=Observation)
    finished: bool = False
    """Every scenario has its recorded verdict and nothing is left to clean up."""
