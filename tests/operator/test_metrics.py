"""Metrics and probes endpoint.

Covers: /metrics serves the operator's own registry (counters, gauges, histograms with labels);
/readyz is 503 until ready; /healthz answers; a deleted campaign's gauges are dropped.
"""

from __future__ import annotations

import asyncio
import socket

import aiohttp

from simtest_operator.operator.metrics import Metrics, serve


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def test_metrics_and_probes() -> None:
    async def scenario() -> tuple[int, int, str, str]:
        metrics = Metrics()
        metrics.scenarios.labels(namespace="ns", campaign="c", verdict="Passed").inc(3)
        metrics.in_flight.labels(namespace="ns", campaign="c").set(4)
        metrics.start_latency.observe(0.3)
        metrics.count_request("POST", "pods", 201)
        ready = [False]
        port = _free_port()
        runner = await serve(metrics, port=port, ready=lambda: ready[0], host="127.0.0.1")
        try:
            async with aiohttp.ClientSession() as session:
                base = f"http://127.0.0.1:{port}"
                before = (await session.get(f"{base}/readyz")).status
                ready[0] = True
                after = (await session.get(f"{base}/readyz")).status
                health = await (await session.get(f"{base}/healthz")).text()
                text = await (await session.get(f"{base}/metrics")).text()
        finally:
            await runner.cleanup()
        metrics.forget("ns", "c")
        assert 'simtest_scenarios_in_flight{campaign="c"' not in metrics.exposition().decode()
        return before, after, health, text

    before, after, health, text = asyncio.run(scenario())
    assert (before, after, health) == (503, 200, "ok\n")
    assert (
        'simtest_scenarios_finished_total{campaign="c",namespace="ns",verdict="Passed"} 3.0' in text
    )
    assert 'simtest_scenarios_in_flight{campaign="c",namespace="ns"} 4.0' in text
    assert "simtest_pod_start_latency_seconds_bucket" in text
    assert 'simtest_api_requests_total{code="201",kind="pods",verb="POST"} 1.0' in text
