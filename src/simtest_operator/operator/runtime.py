"""The operator's runtime: everything built once at startup and torn down at cleanup.

kopf handlers reach it through the operator memo (``memo.runtime``); nothing lives in module
globals. Building it checks the API connection, so a wrong kubeconfig fails at startup with a
clear message instead of at the first campaign.

With leader election (:mod:`leadership`) every replica builds the same runtime and keeps its
caches warm, but campaign loops run only while it leads: :meth:`Runtime.ensure` is a no-op on a
follower, and becoming the leader starts a loop for every campaign in the cache.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
from typing import Any

import aiohttp.web

from simtest_operator.operator import leadership
from simtest_operator.operator import metrics as metrics_module
from simtest_operator.operator.caching import Cache, CampaignKey
from simtest_operator.operator.client import Client, Credentials
from simtest_operator.operator.loops import Loops, Shared
from simtest_operator.operator.metrics import Metrics
from simtest_operator.render import TemplateLibrary, render_environment
from simtest_operator.settings import OperatorSettings

log = logging.getLogger(__name__)


@dataclasses.dataclass(slots=True)
class Runtime:
    """Client, loops, metrics and the probe server of one operator process."""

    config: OperatorSettings
    client: Client
    metrics: Metrics
    loops: Loops
    cache: Cache | None = None
    server: aiohttp.web.AppRunner | None = None
    ready: bool = False
    """Connected and serving (leaders and followers alike: a follower is healthy)."""
    elector: leadership.Elector | None = None
    election: asyncio.Task[None] | None = None

    @property
    def leading(self) -> bool:
        """Whether this process runs campaign loops (always, without leader election)."""
        return self.elector is None or self.elector.leading

    def ensure(self, key: CampaignKey) -> None:
        """Start or wake a campaign's loop — only while leading."""
        if self.leading:
            self.loops.ensure(key)

    def started_leading(self) -> None:
        """Became the leader: a loop for every campaign the cache knows."""
        self.metrics.leader.set(1)
        if self.cache is None:
            return
        for key in list(self.cache.campaigns.keys()):
            campaign = self.cache.campaign(key)
            if campaign is not None and not campaign.deleting:
                self.loops.ensure(key)

    async def stopped_leading(self) -> None:
        """Lost the Lease: stop every loop (the next leader re-derives everything)."""
        self.metrics.leader.set(0)
        keys = list(self.loops.loops)
        await self.loops.close()
        for namespace, name in keys:
            self.metrics.forget(namespace, name)

    async def close(self) -> None:
        """Stop the election, loops, the server and the client (releasing a held Lease)."""
        if self.election is not None:
            self.election.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.election
        await self.loops.close()
        if self.elector is not None:
            await self.elector.release()
        if self.server is not None:
            await self.server.cleanup()
        await self.client.close()


async def start(config: OperatorSettings, credentials: Credentials, cache: Cache) -> Runtime:
    """Build and start the runtime."""
    metrics = Metrics()
    client = Client(credentials, on_request=metrics.count_request)
    version: dict[str, Any] = await client.request("GET", "/version", kind="version")
    log.info("connected to %s (Kubernetes %s)", credentials.server, version.get("gitVersion", "?"))
    library = TemplateLibrary(config.inputs.templates_dir)
    if "default" not in library.names():
        log.warning(
            "no 'default' environment template under %s", config.inputs.templates_dir.absolute()
        )
    shared = Shared(
        client=client,
        cache=cache,
        config=config,
        metrics=metrics,
        render=lambda request: render_environment(request, library),
    )
    runtime = Runtime(
        config=config, client=client, metrics=metrics, loops=Loops(shared), cache=cache
    )
    if config.leadership.enabled:
        settings = leadership.LeaseSettings(
            name=config.leadership.lease_name,
            namespace=config.leadership.lease_namespace or "default",
            identity=config.leadership.identity or leadership.default_identity(),
            lease_duration=config.leadership.lease_duration,
            renew_deadline=config.leadership.renew_deadline,
            retry_period=config.leadership.retry_period,
        )
        runtime.elector = leadership.Elector(
            client,
            settings,
            on_started=runtime.started_leading,
            on_stopped=runtime.stopped_leading,
        )
        metrics.leader.set(0)
        log.info(
            "leader election on: lease %s/%s as %s (duration %.0fs, renew deadline %.0fs, "
            "retry %.0fs)",
            settings.namespace,
            settings.name,
            settings.identity,
            settings.lease_duration,
            settings.renew_deadline,
            settings.retry_period,
        )
        runtime.election = asyncio.get_running_loop().create_task(
            runtime.elector.run(), name="leader election"
        )
    else:
        metrics.leader.set(1)
    if config.metrics_port:
        runtime.server = await metrics_module.serve(
            metrics, port=config.metrics_port, ready=lambda: runtime.ready
        )
    runtime.ready = True
    return runtime
