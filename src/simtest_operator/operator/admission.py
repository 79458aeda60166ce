"""Admission through Kueue (``spec.execution.queueName``): one Workload per campaign, its window.

The operator does not let Kueue gate its pods (that needs Kueue's pod webhook, and a gated pod
still counts against ``pendingTimeoutSeconds``). It asks for the window instead: one Workload,
``<campaign>-simulators``, whose single pod set is ``count`` = the window's simulator pods (each
with the campaign's cpu, memory, ``nvidia.com/gpu`` and one ``simtest.dev/simulator``, plus the
SUT sidecar's cpu and memory when the SUT runs as one) and ``minCount`` 1 (a batch with
``batchBarrier``), in the LocalQueue ``queueName``. Kueue admits it by its ClusterQueue's rules
(quotas, cohorts, fair sharing, partial admission down to what fits) and writes the admitted
count; the campaign then keeps at most that many environments in flight. Nothing starts before
admission, so a campaign over quota creates no pods at all; it waits with condition
``Admitted=False`` carrying Kueue's own reason and message. The Workload is deleted (its quota
released) once every scenario has its verdict, and while the campaign is suspended with nothing
in flight; it is owned by the campaign, so deleting the campaign removes it too.

Pure: the step's views in, the gate (window, condition, actions) out.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from simtest_operator.api.v1alpha1 import TestCampaignSpec
from simtest_operator.operator import bodies, names
from simtest_operator.operator.actions import Action, Create, Delete, Kind
from simtest_operator.operator.status import conditions
from simtest_operator.render.inputs import GPU_RESOURCE, SIMULATOR_RESOURCE

GROUP = "kueue.x-k8s.io"
VERSION = "v1beta2"
QUEUE_LABEL = f"{GROUP}/queue-name"
"""Kueue's convention for naming the LocalQueue of a job."""
POD_SET = "simulators"
CONDITION = "Admitted"

Raw = Mapping[str, Any]


def workload_name(campaign: str) -> str:
    """The campaign's one Workload."""
    return f"{campaign}-simulators"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class WorkloadView:
    """What the operator reads from a Workload: whether, where and how many were admitted."""

    name: str
    uid: str
    resource_version: str
    campaign: str
    deleting: bool
    admitted: bool
    """Condition ``Admitted=True`` (quota reserved and every admission check passed)."""
    count: int
    """Pods of the pod set Kueue admitted (less than requested after partial admission)."""
    cluster_queue: str
    reason: str
    """Why it is not admitted: ``QuotaReserved=False``'s (or ``Evicted``'s) reason."""
    message: str


def _condition(status: Raw, kind: str) -> Raw:
    for condition in status.get("conditions") or ():
        if isinstance(condition, Mapping) and condition.get("type") == kind:
            return condition
    return {}


def workload_view(body: Raw) -> WorkloadView:
    """Parse a Workload body (total: odd fields become empty, never an exception)."""
    meta = body.get("metadata") if isinstance(body.get("metadata"), Mapping) else {}
    status = body.get("status") if isinstance(body.get("status"), Mapping) else {}
    assert isinstance(meta, Mapping) and isinstance(status, Mapping)
    admission = status.get("admission") if isinstance(status.get("admission"), Mapping) else {}
    assert isinstance(admission, Mapping)
    count = 0
    for assignment in admission.get("podSetAssignments") or ():
        if isinstance(assignment, Mapping) and assignment.get("name") == POD_SET:
            try:
                count = int(assignment.get("count") or 0)
            except (TypeError, ValueError):
                count = 0
    admitted = _condition(status, "Admitted").get("status") == "True"
    evicted = _condition(status, "Evicted")
    waiting = evicted if evicted.get("status") == "True" else _condition(status, "QuotaReserved")
    labels = meta.get("labels") if isinstance(meta.get("labels"), Mapping) else {}
    assert isinstance(labels, Mapping)
    return WorkloadView(
        name=str(meta.get("name", "")),
        uid=str(meta.get("uid", "")),
        resource_version=str(meta.get("resourceVersion", "")),
        campaign=str(labels.get(names.LABEL_CAMPAIGN, "")),
        deleting=meta.get("deletionTimestamp") is not None,
        admitted=admitted and count > 0,
        count=count if admitted else 0,
        cluster_queue=str(admission.get("clusterQueue", "")),
        reason=str(waiting.get("reason", "")),
        message=str(waiting.get("message", "")),
    )


def pod_requests(spec: TestCampaignSpec) -> dict[str, str]:
    """What the simulator container asks for, in Kueue's terms."""
    requests = spec.execution.resources.requests
    amounts = {"cpu": requests.cpu, "memory": requests.memory, SIMULATOR_RESOURCE: "1"}
    if requests.gpu:
        amounts[GPU_RESOURCE] = str(requests.gpu)
    return amounts


def workload_body(
    spec: TestCampaignSpec, *, campaign: str, namespace: str, campaign_uid: str, count: int
) -> dict[str, Any]:
    """The campaign's Workload asking for ``count`` simulator pods (at least one)."""
    queue = spec.execution.queue_name or ""
    containers = [{"name": "simulator", "resources": {"requests": pod_requests(spec)}}]
    sut = spec.environment.sut.external
    if sut is not None and sut.image:
        # The SUT sidecar's requests count towards the pod's (and so towards the quota).
        sidecar = {"cpu": sut.resources.requests.cpu, "memory": sut.resources.requests.memory}
        containers.append({"name": "sut", "resources": {"requests": sidecar}})
    template: dict[str, Any] = {"restartPolicy": "Never", "containers": containers}
    if spec.execution.node_selector:
        template["nodeSelector"] = dict(spec.execution.node_selector)
    if spec.execution.tolerations:
        template["tolerations"] = [t.to_wire() for t in spec.execution.tolerations]
    # Not the controller: Kueue looks up a Workload's controller as the job it belongs to.
    owner = bodies.owner("TestCampaign", campaign, campaign_uid, controller=False)
    return {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "Workload",
        "metadata": {
            "name": workload_name(campaign),
            "namespace": namespace,
            "labels": {**names.campaign_labels(campaign), QUEUE_LABEL: queue},
            "ownerReferences": [owner],
        },
        "spec": {
            "queueName": queue,
            "podSets": [
                {
                    "name": POD_SET,
                    "count": max(count, 1),
                    "minCount": min_count(spec, count),
                    "template": {"spec": template},
                }
            ],
        },
    }


def min_count(spec: TestCampaignSpec, count: int) -> int:
    """The fewest simulators worth admitting: one, or with ``batchBarrier`` a whole batch (a
    barrier batch is submitted whole)."""
    execution = spec.execution
    return max(min(execution.batch_size if execution.batch_barrier else 1, count), 1)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Gate:
    """What admission allows this step."""

    window: int
    """Environments that may be in flight (the unclamped window without a queue)."""
    actions: tuple[Action, ...] = ()
    condition: conditions.Desired | None = None
    """The campaign's ``Admitted`` condition (None without a queue)."""
    waiting: str = ""
    """Kueue's words while nothing is admitted (the campaign is then Pending)."""


def gate(
    spec: TestCampaignSpec,
    *,
    campaign: str,
    namespace: str,
    campaign_uid: str,
    window: int,
    scenarios: int,
    workload: WorkloadView | None,
    complete: bool,
    in_flight: int = 0,
    refused: str | None = None,
) -> Gate:
    """The window admission allows, the Workload to create or delete, and the condition.

    The Workload goes when the campaign is done, and while it is suspended with nothing in
    flight (a paused campaign holds no quota; resuming asks the queue again, as Kueue does with
    a suspended Job)."""
    queue = spec.execution.queue_name
    if queue is None:
        return Gate(window=window)
    name = workload_name(campaign)
    release: tuple[Action, ...] = ()
    if workload is not None and not workload.deleting:
        release = (Delete(kind=Kind.WORKLOAD, name=name, uid=workload.uid or None),)
    if complete:
        return Gate(
            window=0,
            actions=release,
            condition=conditions.Desired(
                type=CONDITION,
                status=False,
                reason="Released",
                message=f"every scenario has its verdict; Workload {name} deleted, its quota "
                "released",
            ),
        )
    if spec.suspend and in_flight == 0:
        return Gate(
            window=0,
            actions=release,
            condition=conditions.Desired(
                type=CONDITION,
                status=False,
                reason="Suspended",
                message=f"spec.suspend is true: Workload {name} deleted, its quota released; "
                "resuming asks the queue again",
            ),
        )
    if workload is None or workload.deleting:
        if refused is not None:
            message = (
                f"the API server refused to create Workload {name}: {refused} (is Kueue "
                "installed, and may the operator create kueue.x-k8s.io workloads?)"
            )
            return Gate(
                window=0,
                condition=conditions.Desired(
                    type=CONDITION, status=False, reason="WorkloadRefused", message=message
                ),
                waiting=message,
            )
        count = max(min(window, scenarios), 1)
        message = f"Workload {name} asks LocalQueue {queue} for {count} simulators"
        create = Create(
            kind=Kind.WORKLOAD,
            body=workload_body(
                spec, campaign=campaign, namespace=namespace, campaign_uid=campaign_uid, count=count
            ),
        )
        return Gate(
            window=0,
            actions=() if workload is not None else (create,),
            condition=conditions.Desired(
                type=CONDITION, status=False, reason="Queued", message=message
            ),
            waiting=message,
        )
    if workload.admitted:
        return Gate(
            window=min(window, workload.count),
            condition=conditions.Desired(
                type=CONDITION,
                status=True,
                reason="Admitted",
                message=f"ClusterQueue {workload.cluster_queue} admitted {workload.count} "
                f"simulators at once (Workload {name})",
            ),
        )
    # Before Kueue first looks at it the Workload has no conditions: still just queued.
    reason = workload.reason or "Queued"
    message = workload.message or f"Workload {name} waits in LocalQueue {queue}"
    return Gate(
        window=0,
        condition=conditions.Desired(type=CONDITION, status=False, reason=reason, message=message),
        waiting=f"Kueue: {message}",
    )


def now_waiting(gate_: Gate, *, in_flight: int) -> str | None:
    """Kueue's words when the campaign waits with nothing in flight (its phase is then
    Pending), else None."""
    return gate_.waiting if gate_.waiting and in_flight == 0 else None
