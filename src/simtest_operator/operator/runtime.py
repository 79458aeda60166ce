"""The operator's runtime: everything built once at startup and torn down at cleanup.

kopf handlers reach it through the operator memo (``memo.runtime``); nothing lives in module
globals. Building it checks the API connection, so a wrong kubeconfig fails at startup with a
clear message instead of at the first campaign.
"""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

import aiohttp.web

from simtest_operator.operator import metrics as metrics_module
from simtest_operator.operator.caching import Cache
from simtest_operator.operator.client import Client, Credentials
from simtest_operator.operator.configuration import OperatorConfig
from simtest_operator.operator.loops import Loops, Shared
from simtest_operator.operator.metrics import Metrics
from simtest_operator.render import TemplateLibrary, render_environment

log = logging.getLogger(__name__)


@dataclasses.dataclass(slots=True)
class Runtime:
    """Client, loops, metrics and the probe server of one operator process."""

    config: OperatorConfig
    client: Client
    metrics: Metrics
    loops: Loops
    server: aiohttp.web.AppRunner | None = None
    ready: bool = False

    async def close(self) -> None:
        """Stop loops, the server and the client."""
        await self.loops.close()
        if self.server is not None:
            await self.server.cleanup()
        await self.client.close()


async def start(config: OperatorConfig, credentials: Credentials, cache: Cache) -> Runtime:
    """Build and start the runtime."""
    metrics = Metrics()
    client = Client(credentials, on_request=metrics.count_request)
    version: dict[str, Any] = await client.request("GET", "/version", kind="version")
    log.info("connected to %s (Kubernetes %s)", credentials.server, version.get("gitVersion", "?"))
    library = TemplateLibrary(config.templates_dir)
    if "default" not in library.names():
        log.warning("no 'default' environment template under %s", config.templates_dir.absolute())
    shared = Shared(
        client=client,
        cache=cache,
        config=config,
        metrics=metrics,
        render=lambda request: render_environment(request, library),
    )
    runtime = Runtime(config=config, client=client, metrics=metrics, loops=Loops(shared))
    if config.metrics_port:
        runtime.server = await metrics_module.serve(
            metrics, port=config.metrics_port, ready=lambda: runtime.ready
        )
    runtime.ready = True
    return runtime
