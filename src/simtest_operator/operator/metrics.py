"""Prometheus metrics and the HTTP endpoint that serves them with the health probes.

One registry per operator (not the global default), so tests can run operators side by side.
``/metrics`` is the Prometheus text format; ``/healthz`` answers while the event loop runs;
``/readyz`` once the operator has logged in and its caches are filled.
"""

from __future__ import annotations

from collections.abc import Callable

import aiohttp.web
import prometheus_client
from prometheus_client import CollectorRegistry, Counter, Gauge, Histogram

LATENCY_BUCKETS = (0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 30.0, 60.0, 300.0)


class Metrics:
    """The operator's metrics."""

    def __init__(self) -> None:
        self.registry = CollectorRegistry()
        self.scenarios = Counter(
            "simtest_scenarios_finished",
            "Scenarios that reached their final verdict (recorded in a ScenarioBatch).",
            ["namespace", "campaign", "verdict"],
            registry=self.registry,
        )
        self.in_flight = Gauge(
            "simtest_scenarios_in_flight",
            "Simulator environments running or waiting for a node.",
            ["namespace", "campaign"],
            registry=self.registry,
        )
        self.queued = Gauge(
            "simtest_scenarios_queued",
            "Scenarios not started yet (queue depth).",
            ["namespace", "campaign"],
            registry=self.registry,
        )
        self.window = Gauge(
            "simtest_window_size",
            "In-flight window (maxParallel, or the simulator slots of matching nodes).",
            ["namespace", "campaign"],
            registry=self.registry,
        )
        self.start_latency = Histogram(
            "simtest_pod_start_latency_seconds",
            "From SimEnvironment creation to simulator container start.",
            buckets=LATENCY_BUCKETS,
            registry=self.registry,
        )
        self.overhead = Histogram(
            "simtest_orchestration_overhead_seconds",
            "Per scenario: environment lifetime minus the runner's own run time.",
            buckets=LATENCY_BUCKETS,
            registry=self.registry,
        )
        self.reconcile = Histogram(
            "simtest_reconcile_seconds",
            "Duration of one campaign reconcile step (plan and apply).",
            buckets=(0.001, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 5.0),
            registry=self.registry,
        )
        self.plan = Histogram(
            "simtest_plan_seconds",
            "One campaign step without its API calls: reading the cache and planning.",
            buckets=(0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 1.0),
            registry=self.registry,
        )
        self.leader = Gauge(
            "simtest_operator_leader",
            "1 while this replica runs the campaign loops (holds the Lease, or no election).",
            registry=self.registry,
        )
        self.api_requests = Counter(
            "simtest_api_requests",
            "Kubernetes API requests sent by the operator's client (kopf's watches excluded).",
            ["verb", "kind", "code"],
            registry=self.registry,
        )

    def count_request(self, verb: str, kind: str, code: int) -> None:
        """Client hook: one API request."""
        self.api_requests.labels(verb=verb, kind=kind, code=str(code)).inc()

    def forget(self, namespace: str, campaign: str) -> None:
        """Drop a deleted campaign's gauges (bounded label cardinality)."""
        for gauge in (self.in_flight, self.queued, self.window):
            try:
                gauge.remove(namespace, campaign)
            except KeyError:
                continue

    def exposition(self) -> bytes:
        """The Prometheus text format."""
        return bytes(prometheus_client.generate_latest(self.registry))


async def serve(
    metrics: Metrics, *, port: int, ready: Callable[[], bool], host: str = "0.0.0.0"
) -> aiohttp.web.AppRunner:
    """Start ``/metrics``, ``/healthz`` and ``/readyz`` on ``port``; returns the runner to stop."""

    async def get_metrics(_: aiohttp.web.Request) -> aiohttp.web.Response:
        return aiohttp.web.Response(
            body=metrics.exposition(), content_type="text/plain", charset="utf-8"
        )

    async def get_health(_: aiohttp.web.Request) -> aiohttp.web.Response:
        return aiohttp.web.Response(text="ok\n")

    async def get_ready(_: aiohttp.web.Request) -> aiohttp.web.Response:
        if ready():
            return aiohttp.web.Response(text="ready\n")
        return aiohttp.web.Response(text="starting\n", status=503)

    app = aiohttp.web.Application()
    app.router.add_get("/metrics", get_metrics)
    app.router.add_get("/healthz", get_health)
    app.router.add_get("/readyz", get_ready)
    runner = aiohttp.web.AppRunner(app, access_log=None)
    await runner.setup()
    await aiohttp.web.TCPSite(runner, host, port).start()
    return runner
