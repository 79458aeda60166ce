"""Bodies of the objects a campaign creates: batches, environments, the ServiceAccount, events."""

from __future__ import annotations

import datetime
import hashlib
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.api.v1alpha1 import API_VERSION
from simtest_operator.operator import names
from simtest_operator.operator.status import conditions
from simtest_operator.render.inputs import ScenarioRef
from simtest_operator.scenarios import PinnedScenario


def owner(kind: str, name: str, uid: str, *, controller: bool = True) -> dict[str, Any]:
    """An ownerReference to one of our custom resources."""
    return {
        "apiVersion": API_VERSION,
        "kind": kind,
        "name": name,
        "uid": uid,
        "controller": controller,
        "blockOwnerDeletion": True,
    }


def _frozen(entry: PinnedScenario | ScenarioRef) -> dict[str, Any]:
    return entry.to_json()


def batch(
    *,
    campaign: str,
    namespace: str,
    campaign_uid: str,
    index: int,
    scenarios: Sequence[PinnedScenario],
) -> dict[str, Any]:
    """A ScenarioBatch: one slice of the frozen list."""
    return {
        "apiVersion": API_VERSION,
        "kind": "ScenarioBatch",
        "metadata": {
            "name": names.batch(campaign, index),
            "namespace": namespace,
            "labels": names.campaign_labels(campaign),
            "ownerReferences": [owner("TestCampaign", campaign, campaign_uid)],
        },
        "spec": {
            "campaign": campaign,
            "index": index,
            "scenarios": [_frozen(s) for s in scenarios],
        },
    }


def environment(
    *,
    campaign: str,
    namespace: str,
    batch_name: str,
    batch_uid: str,
    name: str,
    attempt: int,
    isolation: str,
    scenarios: Sequence[PinnedScenario],
) -> dict[str, Any]:
    """A SimEnvironment running one unit of work."""
    return {
        "apiVersion": API_VERSION,
        "kind": "SimEnvironment",
        "metadata": {
            "name": name,
            "namespace": namespace,
            "labels": names.environment_labels(campaign, batch_name, attempt),
            "ownerReferences": [owner("ScenarioBatch", batch_name, batch_uid)],
        },
        "spec": {
            "campaign": campaign,
            "batch": batch_name,
            "scenarios": [_frozen(s) for s in scenarios],
            "isolation": isolation,
            "attempt": attempt,
        },
    }


def service_account(*, campaign: str, namespace: str, campaign_uid: str) -> dict[str, Any]:
    """The simulator pods' identity: no token mounted, no RBAC bindings."""
    return {
        "apiVersion": "v1",
        "kind": "ServiceAccount",
        "metadata": {
            "name": names.service_account(campaign),
            "namespace": namespace,
            "labels": names.campaign_labels(campaign),
            "ownerReferences": [owner("TestCampaign", campaign, campaign_uid)],
        },
        "automountServiceAccountToken": False,
    }


def event(
    *,
    involved: Mapping[str, str],
    reason: str,
    message: str,
    warning: bool,
    now: datetime.datetime,
    component: str = names.MANAGED_BY,
) -> dict[str, Any]:
    """A core/v1 Event about ``involved`` (apiVersion, kind, name, namespace, uid)."""
    stamp = conditions.rfc3339(now)
    # Two events about one object in one step (a batch's phase and a warning) differ in reason or
    # message: a digest of both keeps their names apart.
    digest = hashlib.sha256(f"{reason}\n{message}".encode()).hexdigest()[:6]
    moment = now.strftime("%Y%m%d%H%M%S%f") + digest
    return {
        "apiVersion": "v1",
        "kind": "Event",
        "metadata": {
            "name": f"{involved['name']}.{moment}"[:253],
            "namespace": involved["namespace"],
        },
        "involvedObject": dict(involved),
        "reason": reason,
        "message": message[:1024],
        "type": "Warning" if warning else "Normal",
        "source": {"component": component},
        "reportingComponent": component,
        "reportingInstance": component,
        "firstTimestamp": stamp,
        "lastTimestamp": stamp,
        "count": 1,
    }
