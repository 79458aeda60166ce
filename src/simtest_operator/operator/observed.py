"""Views: the few facts the operator needs from each watched object, parsed once.

The kopf indexes store these instead of whole bodies (a pod body is kilobytes; its view is a few
fields), and the planner works on them only. Parsing is pure and total: a malformed field becomes
``None``/empty rather than an exception, because one odd object must not stop a campaign.
"""

from __future__ import annotations

import dataclasses
import datetime
import sys
from collections.abc import Mapping
from typing import Any

from simtest_operator import provenance
from simtest_operator.api.v1alpha1 import (
    EnvironmentPhase,
    ManifestError,
    ScenarioBatchStatus,
    SimEnvironmentStatus,
    TestCampaignSpec,
    TestCampaignStatus,
    parse_campaign,
)
from simtest_operator.errors import SourceError
from simtest_operator.operator import names
from simtest_operator.operator.status import reading
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.render.inputs import SIMULATOR_RESOURCE, ScenarioRef
from simtest_operator.scenarios.pinned import PinnedScenario

Raw = Mapping[str, Any]
SUT_CONTAINER = "sut"
"""The container an external SUT image runs in (``default/pod.yaml.j2``: a native sidecar)."""


def _meta(body: Raw) -> Raw:
    meta = body.get("metadata")
    return meta if isinstance(meta, Mapping) else {}


def _status(body: Raw) -> Raw:
    status = body.get("status")
    return status if isinstance(status, Mapping) else {}


def _spec(body: Raw) -> Raw:
    spec = body.get("spec")
    return spec if isinstance(spec, Mapping) else {}


def _condition(status: Raw, kind: str) -> Raw | None:
    for condition in status.get("conditions") or ():
        if isinstance(condition, Mapping) and condition.get("type") == kind:
            return condition
    return None


def condition(status: Raw, kind: str) -> Raw | None:
    """The condition of type ``kind`` in a status, if any."""
    return _condition(status, kind)


def _results(items: Any) -> tuple[ResultRecord, ...]:
    records = []
    for item in items or ():
        try:
            records.append(ResultRecord.from_wire(item))
        except (KeyError, TypeError, ValueError):
            continue
    return tuple(records)


# --- pods --------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ContainerView:
    """The simulator container's current state."""

    state: str = ""
    """``waiting``, ``running``, ``terminated`` or empty (no status yet)."""
    reason: str = ""
    message: str = ""
    exit_code: int | None = None
    started_at: datetime.datetime | None = None
    finished_at: datetime.datetime | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PodView:
    """A simulator pod."""

    name: str
    namespace: str
    uid: str
    resource_version: str
    campaign: str
    created: datetime.datetime | None
    deleting: bool
    node_name: str | None
    phase: str
    reason: str
    message: str
    scheduled_at: datetime.datetime | None
    unschedulable: str
    """``PodScheduled=False`` reason and message while the scheduler cannot place the pod."""
    start_time: datetime.datetime | None
    container: ContainerView
    disruption: str
    """``DisruptionTarget`` reason and message (eviction, preemption, pod GC), if any."""
    job: str = ""
    """The Job that owns the pod (helmfile Jobs' pods carry the campaign label too)."""
    sut_image_id: str = ""
    """The image of the SUT container as the kubelet reports it (``repo@sha256:…`` or
    ``sha256:…``), empty without a SUT container or before its image is resolved."""

    @property
    def terminated(self) -> bool:
        """The pod ran to an end (phase or container state say so)."""
        return self.phase in ("Succeeded", "Failed") or self.container.state == "terminated"


def pod_view(body: Raw) -> PodView:
    """Parse a Pod body."""
    meta, status, spec = _meta(body), _status(body), _spec(body)
    scheduled = _condition(status, "PodScheduled")
    scheduled_at = None
    unschedulable = ""
    if scheduled is not None:
        if scheduled.get("status") == "True":
            scheduled_at = reading.timestamp(scheduled.get("lastTransitionTime"))
        else:
            unschedulable = " ".join(
                str(p) for p in (scheduled.get("reason"), scheduled.get("message")) if p
            )
    disruption = _condition(status, "DisruptionTarget")
    disruption_text = ""
    if disruption is not None and disruption.get("status") == "True":
        disruption_text = " ".join(
            str(p) for p in (disruption.get("reason"), disruption.get("message")) if p
        )
    return PodView(
        name=str(meta.get("name", "")),
        namespace=str(meta.get("namespace", "")),
        uid=str(meta.get("uid", "")),
        resource_version=str(meta.get("resourceVersion", "")),
        campaign=str((meta.get("labels") or {}).get(names.LABEL_CAMPAIGN, "")),
        created=reading.timestamp(meta.get("creationTimestamp")),
        deleting=meta.get("deletionTimestamp") is not None,
        node_name=spec.get("nodeName") or None,
        phase=str(status.get("phase", "Pending")),
        reason=str(status.get("reason", "")),
        message=str(status.get("message", "")),
        scheduled_at=scheduled_at,
        unschedulable=unschedulable,
        start_time=reading.timestamp(status.get("startTime")),
        container=_container(status),
        sut_image_id=_sut_image_id(status),
        disruption=disruption_text,
        job=next(
            (
                str(o.get("name", ""))
                for o in meta.get("ownerReferences") or ()
                if isinstance(o, Mapping) and o.get("kind") == "Job"
            ),
            "",
        ),
    )


def _container(status: Raw) -> ContainerView:
    statuses = status.get("containerStatuses") or ()
    chosen = next(
        (s for s in statuses if isinstance(s, Mapping) and s.get("name") == "simulator"),
        statuses[0] if statuses else None,
    )
    if not isinstance(chosen, Mapping):
        return ContainerView()
    state = chosen.get("state") or {}
    for kind in ("terminated", "running", "waiting"):
        detail = state.get(kind)
        if isinstance(detail, Mapping):
            exit_code = detail.get("exitCode")
            return ContainerView(
                state=kind,
                reason=str(detail.get("reason", "")),
                message=str(detail.get("message", "")),
                exit_code=int(exit_code) if isinstance(exit_code, int) else None,
                started_at=reading.timestamp(detail.get("startedAt")),
                finished_at=reading.timestamp(detail.get("finishedAt")),
            )
    return ContainerView()


def _sut_image_id(status: Raw) -> str:
    """The SUT container's ``imageID``: a native sidecar reports it among the init containers,
    a template that runs the SUT as a plain container among the containers."""
    for key in ("initContainerStatuses", "containerStatuses"):
        for entry in status.get(key) or ():
            if isinstance(entry, Mapping) and entry.get("name") == SUT_CONTAINER:
                return provenance.reported_image_id(str(entry.get("imageID") or ""))
    return ""


# --- nodes -------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class NodeView:
    """A node, as far as simulator placement goes."""

    name: str
    ready: bool
    unschedulable: bool
    slots: int
    """Allocatable ``simtest.dev/simulator`` units."""
    labels: tuple[tuple[str, str], ...]
    taints: tuple[tuple[str, str, str], ...]
    """(key, value, effect) of each taint."""
    not_ready_since: datetime.datetime | None = None
    """When its Ready condition last left True (None while Ready): a kubelet that stopped
    reporting, whose pods nobody will finish."""


def node_view(body: Raw) -> NodeView:
    """Parse a Node body."""
    meta, status, spec = _meta(body), _status(body), _spec(body)
    ready = _condition(status, "Ready")
    allocatable = status.get("allocatable") or {}
    try:
        slots = int(str(allocatable.get(SIMULATOR_RESOURCE, "0")))
    except ValueError:
        slots = 0
    taints = tuple(
        (str(t.get("key", "")), str(t.get("value", "")), str(t.get("effect", "")))
        for t in spec.get("taints") or ()
        if isinstance(t, Mapping)
    )
    is_ready = ready is not None and ready.get("status") == "True"
    return NodeView(
        name=str(meta.get("name", "")),
        ready=is_ready,
        not_ready_since=None
        if is_ready or ready is None
        else reading.timestamp(ready.get("lastTransitionTime")),
        unschedulable=bool(spec.get("unschedulable")),
        slots=slots,
        labels=tuple(sorted((str(k), str(v)) for k, v in (meta.get("labels") or {}).items())),
        taints=taints,
    )


# --- custom resources --------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EnvironmentView:
    """A SimEnvironment."""

    name: str
    namespace: str
    uid: str
    resource_version: str
    campaign: str
    batch: str
    attempt: int
    scenarios: tuple[ScenarioRef, ...]
    # What the cluster says; the defaults describe an environment not created yet.
    created: datetime.datetime | None = None
    deleting: bool = False
    status: SimEnvironmentStatus = dataclasses.field(default_factory=SimEnvironmentStatus)
    """The status, typed (:mod:`~simtest_operator.operator.status.reading`), without its
    results."""
    results: tuple[ResultRecord, ...] = ()
    """The recorded results (the typed ``status`` leaves them out: read once, here)."""
    provisioned_at: datetime.datetime | None = None
    """When the operator recorded creating the pod (condition ``Provisioned`` with its time)."""
    status_wire: Raw = dataclasses.field(default_factory=dict)
    """The status as stored, for merge patches."""

    @property
    def scenario_ids(self) -> tuple[str, ...]:
        """Ids of the scenarios this environment runs."""
        return tuple(s.id for s in self.scenarios)

    @property
    def finished(self) -> bool:
        """The environment's verdicts are recorded in its status (durable)."""
        return self.status.phase in _RECORDED


_RECORDED = frozenset({EnvironmentPhase.FINISHED, EnvironmentPhase.TORN_DOWN})


def environment_view(body: Raw) -> EnvironmentView:
    """Parse a SimEnvironment body."""
    meta, status, spec = _meta(body), _status(body), _spec(body)
    provisioned = _condition(status, "Provisioned")
    scenarios = tuple(
        ScenarioRef(
            id=str(s.get("id", "")),
            source=str(s.get("source", "")),
            sha256=str(s.get("sha256", "")),
            overrides={str(k): str(v) for k, v in (s.get("overrides") or {}).items()},
        )
        for s in spec.get("scenarios") or ()
        if isinstance(s, Mapping)
    )
    return EnvironmentView(
        name=str(meta.get("name", "")),
        namespace=str(meta.get("namespace", "")),
        uid=str(meta.get("uid", "")),
        resource_version=str(meta.get("resourceVersion", "")),
        campaign=str(spec.get("campaign", "")),
        batch=str(spec.get("batch", "")),
        attempt=int(spec.get("attempt", 1) or 1),
        scenarios=scenarios,
        created=reading.timestamp(meta.get("creationTimestamp")),
        deleting=meta.get("deletionTimestamp") is not None,
        status=reading.environment(status),
        results=_results(status.get("results")),
        provisioned_at=reading.timestamp((provisioned or {}).get("lastTransitionTime"))
        if provisioned is not None and provisioned.get("status") == "True"
        else None,
        status_wire=status,
    )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BatchView:
    """A ScenarioBatch.

    Batches are the only children that outlive the window (the durable record of the results),
    so the cache holds one view per batch for the whole campaign: 10,000 of them at 100,000
    scenarios. A view therefore keeps each verdict once, as its record; the wire form of the
    results and the typed status are rebuilt on demand, which only open batches need.
    """

    name: str
    namespace: str
    uid: str
    resource_version: str
    campaign: str
    index: int
    scenario_ids: tuple[str, ...]
    results: tuple[ResultRecord, ...]
    """The recorded results, parsed once."""
    proposals: tuple[PinnedScenario, ...] = ()
    """A search's wave: its concrete scenarios with their proposal records (empty otherwise)."""
    stored_fields: Raw
    """The status as stored, without ``results`` when :attr:`results` write back to exactly the
    stored list (else with it: the stored list is then kept as it is)."""

    @property
    def status(self) -> ScenarioBatchStatus:
        """The status, typed (:mod:`~simtest_operator.operator.status.reading`; no results)."""
        return reading.batch(self.stored_fields)

    @property
    def status_wire(self) -> Raw:
        """The status as stored, for merge patches."""
        if "results" in self.stored_fields or not self.results:
            return self.stored_fields
        return {**self.stored_fields, "results": [r.to_wire() for r in self.results]}


def batch_view(body: Raw) -> BatchView:
    """Parse a ScenarioBatch body."""
    meta, status, spec = _meta(body), _status(body), _spec(body)
    results = _results(status.get("results"))
    stored = status
    if results and [r.to_wire() for r in results] == status.get("results"):
        stored = {sys.intern(k): v for k, v in status.items() if k != "results"}
    ids = {r.id: r.id for r in results}  # one string per id, shared with the records
    return BatchView(
        name=str(meta.get("name", "")),
        namespace=str(meta.get("namespace", "")),
        uid=str(meta.get("uid", "")),
        resource_version=str(meta.get("resourceVersion", "")),
        campaign=str(spec.get("campaign", "")),
        index=int(spec.get("index", 0) or 0),
        scenario_ids=tuple(
            ids.get(i, i)
            for i in (
                str(s.get("id", "")) for s in spec.get("scenarios") or () if isinstance(s, Mapping)
            )
        ),
        results=results,
        proposals=_proposals(spec.get("scenarios"), where=f"ScenarioBatch {meta.get('name')}"),
        stored_fields=stored,
    )


def _proposals(entries: Any, *, where: str) -> tuple[PinnedScenario, ...]:
    """The entries of a batch that are search proposals (a malformed one is left out: the
    search then stops at the gap instead of the cache failing)."""
    found = []
    for entry in entries or ():
        if isinstance(entry, Mapping) and entry.get("proposal") is not None:
            try:
                found.append(PinnedScenario.from_json(entry, where=where))
            except SourceError:
                continue
    return tuple(found)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class CampaignView:
    """A TestCampaign with its validated spec."""

    name: str
    namespace: str
    uid: str
    resource_version: str
    generation: int
    created: datetime.datetime | None
    deleting: bool
    spec: TestCampaignSpec | None
    spec_error: str
    """Why the spec does not validate (only when ``spec`` is None)."""
    status: TestCampaignStatus
    """The status, typed (:mod:`~simtest_operator.operator.status.reading`)."""
    status_wire: Raw
    """The status as stored, for merge patches."""


def campaign_view(body: Raw) -> CampaignView:
    """Parse a TestCampaign body; an invalid spec is kept as an error, not raised."""
    meta, status = _meta(body), _status(body)
    spec: TestCampaignSpec | None = None
    error = ""
    document = {
        "apiVersion": body.get("apiVersion"),
        "kind": body.get("kind"),
        "metadata": {"name": meta.get("name"), "namespace": meta.get("namespace")},
        "spec": _spec(body),
    }
    try:
        spec = parse_campaign(document, source=f"testcampaign/{meta.get('name')}").spec
    except ManifestError as exc:
        error = "; ".join(f"{path}: {message}" for path, message in exc.problems)
    return CampaignView(
        name=str(meta.get("name", "")),
        namespace=str(meta.get("namespace", "")),
        uid=str(meta.get("uid", "")),
        resource_version=str(meta.get("resourceVersion", "")),
        generation=int(meta.get("generation", 1) or 1),
        created=reading.timestamp(meta.get("creationTimestamp")),
        deleting=meta.get("deletionTimestamp") is not None,
        spec=spec,
        spec_error=error,
        status=reading.campaign(status),
        status_wire=status,
    )
