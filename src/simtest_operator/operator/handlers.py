"""All kopf handlers of the operator (and nothing else): caches, wake-ups, startup, login.

Importing this module registers the handlers in kopf's default registry, so import it only from
the entry points: ``simtest operator`` or ``kopf run -m simtest_operator.operator.handlers``.

* ``@kopf.index`` handlers keep small views of campaigns, batches, environments, simulator pods
  and nodes, grouped by campaign — the cache every campaign loop plans from;
* ``@kopf.on.event`` handlers only wake the owning campaign's loop (they run in the event loop,
  never block, never write);
* startup builds the runtime (client, loops, metrics server), login hands kopf the same
  credentials as our client, cleanup stops everything.
"""

from __future__ import annotations

import logging
from typing import Any

import kopf

from simtest_operator.api.v1alpha1 import GROUP, VERSION
from simtest_operator.operator import admission, jobviews, names, observed, runtime
from simtest_operator.operator.caching import ALL_NODES, Cache
from simtest_operator.operator.client import Credentials, load_credentials
from simtest_operator.settings import Settings

log = logging.getLogger(__name__)
CAMPAIGN_LABEL = {names.LABEL_CAMPAIGN: kopf.PRESENT}


# --- caches ------------------------------------------------------------------------------------


@kopf.index(GROUP, VERSION, "testcampaigns")
def campaign_index(namespace: str | None, name: str, body: kopf.Body, **_: Any) -> dict[Any, Any]:
    """Campaign views by (namespace, name)."""
    return {(namespace or "", name): observed.campaign_view(body)}


@kopf.index(GROUP, VERSION, "scenariobatches")
def batch_index(namespace: str | None, body: kopf.Body, **_: Any) -> dict[Any, Any]:
    """Batch views by (namespace, campaign)."""
    view = observed.batch_view(body)
    return {(namespace or "", view.campaign): view}


@kopf.index(GROUP, VERSION, "simenvironments")
def environment_index(namespace: str | None, body: kopf.Body, **_: Any) -> dict[Any, Any]:
    """Environment views by (namespace, campaign)."""
    view = observed.environment_view(body)
    return {(namespace or "", view.campaign): view}


@kopf.index("v1", "pods", labels=CAMPAIGN_LABEL)
def pod_index(
    namespace: str | None, labels: kopf.Labels, body: kopf.Body, **_: Any
) -> dict[Any, Any]:
    """Simulator pod views by (namespace, campaign)."""
    return {(namespace or "", labels[names.LABEL_CAMPAIGN]): observed.pod_view(body)}


@kopf.index("batch", "v1", "jobs", labels=CAMPAIGN_LABEL)
def job_index(
    namespace: str | None, labels: kopf.Labels, body: kopf.Body, **_: Any
) -> dict[Any, Any]:
    """helmfile Job views by (namespace, campaign) (``provisioner: Helmfile``)."""
    return {(namespace or "", labels[names.LABEL_CAMPAIGN]): jobviews.job_view(body)}


@kopf.index(admission.GROUP, admission.VERSION, "workloads", labels=CAMPAIGN_LABEL)
def workload_index(
    namespace: str | None, labels: kopf.Labels, body: kopf.Body, **_: Any
) -> dict[Any, Any]:
    """Kueue Workload views by (namespace, campaign) (``spec.execution.queueName``; without
    Kueue's CRDs kopf serves nothing here and says so once)."""
    return {(namespace or "", labels[names.LABEL_CAMPAIGN]): admission.workload_view(body)}


@kopf.index("v1", "nodes")
def node_index(body: kopf.Body, **_: Any) -> dict[Any, Any]:
    """Node views, all under one key."""
    return {ALL_NODES: observed.node_view(body)}


# --- wake-ups ----------------------------------------------------------------------------------


@kopf.on.event(GROUP, VERSION, "testcampaigns")
async def campaign_event(type: str, namespace: str | None, name: str, memo: Any, **_: Any) -> None:
    """A campaign appeared, changed or went away: start (only while leading), wake or stop its
    loop."""
    if type == "DELETED":
        memo.runtime.loops.stop((namespace or "", name))
    else:
        memo.runtime.ensure((namespace or "", name))


@kopf.on.event(GROUP, VERSION, "scenariobatches")
@kopf.on.event(GROUP, VERSION, "simenvironments")
async def child_event(namespace: str | None, spec: kopf.Spec, memo: Any, **_: Any) -> None:
    """A batch or environment changed: wake its campaign."""
    memo.runtime.loops.wake((namespace or "", str(spec.get("campaign", ""))))


@kopf.on.event(admission.GROUP, admission.VERSION, "workloads", labels=CAMPAIGN_LABEL)
@kopf.on.event("batch", "v1", "jobs", labels=CAMPAIGN_LABEL)
async def job_event(namespace: str | None, labels: kopf.Labels, memo: Any, **_: Any) -> None:
    """A helmfile Job or Kueue Workload changed: wake its campaign."""
    memo.runtime.loops.wake((namespace or "", labels[names.LABEL_CAMPAIGN]))


@kopf.on.event("v1", "pods", labels=CAMPAIGN_LABEL)
async def pod_event(
    namespace: str | None, name: str, type: str, labels: kopf.Labels, memo: Any, **_: Any
) -> None:
    """A simulator pod changed: wake its campaign (told a deleted pod's name — its environment
    may not have recorded the pod yet, and the loop must not mistake it for a lagging watch)."""
    key = (namespace or "", labels[names.LABEL_CAMPAIGN])
    if type == "DELETED":
        memo.runtime.loops.pod_deleted(key, name)
    else:
        memo.runtime.loops.wake(key)


@kopf.on.event("v1", "nodes")
async def node_event(memo: Any, **_: Any) -> None:
    """Capacity or readiness changed: every window may change."""
    memo.runtime.loops.wake_all()


# --- lifecycle ---------------------------------------------------------------------------------


def _credentials(memo: Any) -> Credentials:
    credentials = memo.get("credentials")
    if credentials is None:
        credentials = load_credentials()
        memo["credentials"] = credentials
    assert isinstance(credentials, Credentials)
    return credentials


@kopf.on.login()
def login(memo: Any, **_: Any) -> kopf.ConnectionInfo:
    """kopf talks to the API as the same user as our client."""
    credentials = _credentials(memo)
    token = credentials.refresh() if credentials.refresh else credentials.token
    return kopf.ConnectionInfo(
        server=credentials.server,
        ca_path=credentials.ca_file,
        insecure=credentials.insecure,
        token=token,
        certificate_path=credentials.cert_file,
        private_key_path=credentials.key_file,
    )


@kopf.on.startup()
async def startup(settings: kopf.OperatorSettings, memo: Any, **kwargs: Any) -> None:
    """Tune kopf for a watch-heavy, write-light operator and start the runtime."""
    settings.posting.enabled = False  # our own, rate-limited events only
    settings.batching.batch_window = 0.01  # wake loops within ~10 ms of a change
    # No kopf peering: same-priority peers all freeze; replicas elect a leader over a Lease
    # instead (leadership.py), and only the leader's campaign loops write.
    settings.peering.standalone = True
    settings.watching.server_timeout = 600
    config = memo.get("config")
    if config is None:
        config = Settings.from_env().operator  # `kopf run -m`: no CLI read it
    cache = Cache(
        campaigns=kwargs["campaign_index"],
        batches=kwargs["batch_index"],
        environments=kwargs["environment_index"],
        pods=kwargs["pod_index"],
        nodes=kwargs["node_index"],
        jobs=kwargs["job_index"],
        workloads=kwargs["workload_index"],
    )
    memo.runtime = await runtime.start(config, _credentials(memo), cache)


@kopf.on.cleanup()
async def cleanup(memo: Any, **_: Any) -> None:
    """Stop loops, metrics server and client."""
    current = memo.get("runtime")
    if current is not None:
        await current.close()
