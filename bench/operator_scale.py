"""Scale on the real control plane: 2,000 scenarios on 50 kwok nodes against 200 on 5.

Both runs have the same per-node shape (3 simulator slots per node) and the same scenarios per
slot, so their lower-bound makespans are nearly equal and every other figure can be compared as
a ratio: 10x the scenarios and nodes should cost far less than 10x in live objects, operator
memory and API-server latency. Each run gets a fresh dev control plane (etcd, kube-apiserver,
controller-manager, scheduler, kwok), a real ``simtest operator`` process and a window-mode
campaign (the derived window: slots plus one prefetched pod per node).

Sampled every ~1.5 s until the campaign is Complete: live objects by kind in the namespace
(counted with ``limit=1`` lists: ``remainingItemCount``), operator RSS and CPU (/proc), the
latency of a cheap client-side GET (every ~0.25 s), etcd's DB size, the load average, the
operator's in-flight gauge and reconcile-step histogram; every ~5 s the API server's
``apiserver_request_duration_seconds`` (p50/p99 per verb of that window, and over the run).

    python bench/operator_scale.py                          # 200 on 5 nodes, then 2,000 on 50
    python bench/operator_scale.py --runs 20x2,100x10 --name quick

Results: ``bench/results/operator_scale[-NAME].{json,md,png}``.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import ssl
import statistics
import tempfile
import time
import urllib.request
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from kubernetes import client

import scalereport
from kwokbench import (
    CAMPAIGN,
    CAP_SECONDS,
    GROUP,
    REPO,
    VERSION,
    Buckets,
    bucket_delta,
    bucket_quantile,
    campaign_body,
    campaign_complete,
    dev_cluster,
    durations,
    greedy_makespan,
    histogram_buckets,
    lower_bound,
    metric_total,
    new_namespace,
    operator_metrics,
    operator_process,
    percentile,
    prepare_templates,
    proc_usage,
    write_scenarios,
)
from simtest_operator.devcluster import provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.state import ClusterInfo
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.settings import Settings

SLOTS_PER_NODE = 3
BATCH_SIZE = 10
"""The CRD's default batchSize: what a user who tunes nothing gets."""
VERBS = ("GET", "LIST", "POST", "PUT", "PATCH", "DELETE")
CUSTOM_KINDS = ("scenariobatches", "simenvironments")
PROBE_SECONDS = 0.25
SAMPLE_EVERY = 6
"""Probes per full sample (~1.5 s)."""
APISERVER_EVERY = 3
"""Full samples per API-server scrape (~4.5 s)."""
COMPONENTS = ("etcd", "kube-apiserver", "kube-scheduler", "kwok", "kube-controller-manager")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunConfig:
    scenarios: int
    nodes: int

    @property
    def label(self) -> str:
        return f"{self.scenarios}x{self.nodes}"

    @classmethod
    def parse(cls, text: str) -> RunConfig:
        scenarios, nodes = text.split("x")
        return cls(scenarios=int(scenarios), nodes=int(nodes))


class Scraper:
    """HTTP GETs of the cluster's metrics endpoints (API server with the admin token)."""

    def __init__(self, info: ClusterInfo) -> None:
        self.info = info
        self.tls = ssl.create_default_context(cafile=str(info.ca_file))

    def apiserver(self) -> str:
        request = urllib.request.Request(
            f"{self.info.server}/metrics", headers={"Authorization": f"Bearer {self.info.token}"}
        )
        with urllib.request.urlopen(request, timeout=30, context=self.tls) as reply:
            return str(reply.read().decode())

    def etcd(self) -> str:
        url = f"http://127.0.0.1:{self.info.ports.etcd_client}/metrics"
        with urllib.request.urlopen(url, timeout=10) as reply:
            return str(reply.read().decode())


def latency_buckets(text: str) -> dict[str, Buckets]:
    """apiserver_request_duration_seconds per verb, plus ``ALL`` (every non-long-running verb)."""
    by_verb = histogram_buckets(text, "apiserver_request_duration_seconds", "verb")
    out = {verb: by_verb[verb] for verb in VERBS if verb in by_verb}
    merged: Buckets = {}
    for buckets in out.values():
        for bound, count in buckets.items():
            merged[bound] = merged.get(bound, 0.0) + count
    out["ALL"] = merged
    return out


def count_objects(api: client.ApiClient, namespace: str) -> dict[str, int]:
    """Live objects per kind in the namespace, from ``limit=1`` lists (no bodies transferred)."""
    core = client.CoreV1Api(api)
    custom = client.CustomObjectsApi(api)
    counts: dict[str, int] = {}
    for kind in CUSTOM_KINDS:
        reply: Any = custom.list_namespaced_custom_object(GROUP, VERSION, namespace, kind, limit=1)
        meta = reply.get("metadata") or {}
        counts[kind] = len(reply.get("items") or []) + int(meta.get("remainingItemCount") or 0)
    for kind, lister in (
        ("pods", core.list_namespaced_pod),
        ("configmaps", core.list_namespaced_config_map),
        ("events", core.list_namespaced_event),
    ):
        typed: Any = lister(namespace, limit=1)
        counts[kind] = len(typed.items) + int(typed.metadata.remaining_item_count or 0)
    return counts


def object_sizes(api: client.ApiClient, namespace: str) -> dict[str, int]:
    """The largest object of each kind the campaign writes, in bytes of JSON (etcd refuses a
    request over 1.5 MiB; a ConfigMap's data may hold 1 MiB), and the frozen list's objects."""
    custom = client.CustomObjectsApi(api)
    maps = client.CoreV1Api(api).list_namespaced_config_map(namespace).items
    lists = [m for m in maps if (m.metadata.name or "").startswith(f"{CAMPAIGN}-scenarios")]
    campaign = custom.get_namespaced_custom_object(
        GROUP, VERSION, namespace, "testcampaigns", CAMPAIGN
    )
    largest_batch = 0
    token = None
    while True:
        page: Any = custom.list_namespaced_custom_object(
            GROUP, VERSION, namespace, "scenariobatches", limit=500, _continue=token
        )
        for item in page.get("items") or ():
            largest_batch = max(largest_batch, len(json.dumps(item)))
        token = (page.get("metadata") or {}).get("continue")
        if not token:
            break

    def size(obj: Any) -> int:
        return len(json.dumps(api.sanitize_for_serialization(obj)))

    return {
        "scenario_list_objects": len(lists),
        "scenario_list_max_bytes": max((size(m) for m in lists), default=0),
        "scenario_list_total_bytes": sum(size(m) for m in lists),
        "campaign_bytes": size(campaign),
        "batch_max_bytes": largest_batch,
    }


def event_sources(api: client.ApiClient, namespace: str) -> dict[str, int]:
    """Events in the namespace by reporting component, at the end of a run."""
    out: dict[str, int] = {}
    for event in client.CoreV1Api(api).list_namespaced_event(namespace).items:
        source = event.reporting_component or (event.source.component if event.source else "")
        out[source or "?"] = out.get(source or "?", 0) + 1
    return out


def component_pids(info: ClusterInfo) -> dict[str, int]:
    dev = DevCluster(info.root, Toolchain(root=Settings.from_env().cache.toolchain))
    return {c.name: c.pid for c in dev.status().components if c.alive}


def cpu_seconds(pids: dict[str, int]) -> dict[str, float]:
    out = {}
    for name, pid in pids.items():
        with contextlib.suppress(OSError):
            out[name] = proc_usage(pid)[0]
    return out


def run(
    config: RunConfig, *, seconds: Sequence[float], workdir: Path, budget: float
) -> dict[str, Any]:
    """One fresh cluster, one campaign; returns the run's summary with its samples."""
    cluster_started = time.monotonic()
    with dev_cluster(
        workdir / f"cluster-{config.label}", nodes=config.nodes, slots=SLOTS_PER_NODE
    ) as info:
        startup = time.monotonic() - cluster_started
        api = provisioning.api_client(info.kubeconfig)
        try:
            return _campaign(config, info, api, seconds=seconds, workdir=workdir, budget=budget) | {
                "cluster_startup_seconds": round(startup, 1)
            }
        finally:
            api.close()  # type: ignore[no-untyped-call]


def _campaign(
    config: RunConfig,
    info: ClusterInfo,
    api: client.ApiClient,
    *,
    seconds: Sequence[float],
    workdir: Path,
    budget: float,
) -> dict[str, Any]:
    custom = client.CustomObjectsApi(api)
    namespace = new_namespace(api)
    sources = workdir / f"sources-{config.label}"
    write_scenarios(sources, seconds)
    scraper = Scraper(info)
    pids = component_pids(info)
    body = campaign_body(
        {
            "batchSize": BATCH_SIZE,
            "maxSimulatorsPerNode": SLOTS_PER_NODE,
            "timeoutSeconds": 600,
            "pendingTimeoutSeconds": 3600,
            "retries": 0,
        }
    )
    samples: list[dict[str, Any]] = []
    probes: list[float] = []
    with operator_process(
        namespace=namespace,
        kubeconfig=info.kubeconfig,
        templates=workdir / "templates",
        sources=sources,
        cache=workdir / f"cache-{config.label}",
        log=workdir / f"operator-{config.label}.log",
    ) as (operator, port):
        idle_cpu, idle_rss, _ = proc_usage(operator.pid)
        api_before = latency_buckets(scraper.apiserver())
        api_previous = api_before
        ops_before = ops_previous = operator_metrics(port)
        components_before = cpu_seconds(pids)
        custom.create_namespaced_custom_object(GROUP, VERSION, namespace, "testcampaigns", body)
        started = time.monotonic()
        last_cpu, last_at = idle_cpu, started
        status: dict[str, Any] = {}
        tick = 1  # the first full sample after ~1.5 s (a CPU rate needs an interval)
        complete = False
        while time.monotonic() - started < budget:
            sent = time.perf_counter()
            reply: Any = custom.get_namespaced_custom_object(
                GROUP, VERSION, namespace, "testcampaigns", CAMPAIGN
            )
            probes.append(time.perf_counter() - sent)
            status = dict(reply.get("status") or {})
            complete = campaign_complete(status)
            if complete:
                break
            if operator.poll() is not None:
                raise RuntimeError(f"operator exited; see {workdir}/operator-{config.label}.log")
            if tick % SAMPLE_EVERY == 0:
                now = time.monotonic()
                cpu, rss, _ = proc_usage(operator.pid)
                etcd = scraper.etcd()
                ops = operator_metrics(port)
                sample: dict[str, Any] = {
                    "t": round(now - started, 2),
                    "finished": sum(
                        int(status.get(k, 0) or 0)
                        for k in ("passed", "failed", "errored", "timedOut", "invalid")
                    ),
                    "live": count_objects(api, namespace),
                    "operator_rss_mib": round(rss, 1),
                    "operator_cpu_percent": round(
                        100 * (cpu - last_cpu) / max(now - last_at, 1e-3), 1
                    ),
                    "probe_ms_p50": round(1000 * percentile(probes[-SAMPLE_EVERY:], 0.5), 2),
                    "etcd_db_mib": round(
                        metric_total(etcd, "etcd_mvcc_db_total_size_in_bytes") / 2**20, 2
                    ),
                    "etcd_in_use_mib": round(
                        metric_total(etcd, "etcd_mvcc_db_total_size_in_use_in_bytes") / 2**20, 2
                    ),
                    "in_flight": metric_total(ops, "simtest_scenarios_in_flight"),
                    "plan_ms_mean": _window_mean_ms(ops, ops_previous, "simtest_plan_seconds"),
                    "load1": round(os.getloadavg()[0], 2),
                }
                if (tick // SAMPLE_EVERY) % APISERVER_EVERY == 0:
                    current = latency_buckets(scraper.apiserver())
                    window = bucket_delta(current["ALL"], api_previous.get("ALL"))
                    sample["apiserver_p50_ms"] = round(1000 * bucket_quantile(window, 0.5), 2)
                    sample["apiserver_p99_ms"] = round(1000 * bucket_quantile(window, 0.99), 2)
                    api_previous = current
                samples.append(sample)
                last_cpu, last_at, ops_previous = cpu, now, ops
            tick += 1
            time.sleep(max(PROBE_SECONDS - (time.perf_counter() - sent), 0.0))
        makespan = time.monotonic() - started
        cpu, rss, peak_rss = proc_usage(operator.pid)
        api_after = latency_buckets(scraper.apiserver())
        ops_after = operator_metrics(port)
        components_after = cpu_seconds(pids)
        final_live = count_objects(api, namespace)
        sizes = object_sizes(api, namespace)
        sources_of_events = event_sources(api, namespace)
    return summarize(
        config,
        seconds=seconds,
        makespan=makespan,
        complete=complete,
        status=status,
        samples=samples,
        probes=probes,
        operator=(idle_cpu, idle_rss, cpu, rss, peak_rss),
        latency=(api_before, api_after),
        operator_metrics_text=(ops_before, ops_after),
        components={
            k: round(components_after.get(k, 0.0) - v, 1) for k, v in components_before.items()
        },
        final_live=final_live,
        sizes=sizes,
        event_sources=sources_of_events,
    )


def _window_mean_ms(after: str, before: str, name: str) -> float:
    """Mean of a Prometheus histogram between two scrapes, in ms (NaN without observations)."""
    count = metric_total(after, f"{name}_count") - metric_total(before, f"{name}_count")
    total = metric_total(after, f"{name}_sum") - metric_total(before, f"{name}_sum")
    return round(1000 * total / count, 3) if count else math.nan


def _histogram(after: str, before: str, name: str) -> dict[str, float]:
    """Mean, p50 and p99 in ms of a histogram between two scrapes."""
    window = bucket_delta(
        histogram_buckets(after, name, "").get("", {}),
        histogram_buckets(before, name, "").get("", {}),
    )
    return {
        "mean_ms": _window_mean_ms(after, before, name),
        "p50_ms": round(1000 * bucket_quantile(window, 0.5), 3),
        "p99_ms": round(1000 * bucket_quantile(window, 0.99), 3),
    }


def summarize(
    config: RunConfig,
    *,
    seconds: Sequence[float],
    makespan: float,
    complete: bool,
    status: dict[str, Any],
    samples: list[dict[str, Any]],
    probes: list[float],
    operator: tuple[float, float, float, float, float],
    latency: tuple[dict[str, Buckets], dict[str, Buckets]],
    operator_metrics_text: tuple[str, str],
    components: dict[str, float],
    final_live: dict[str, int],
    sizes: dict[str, int],
    event_sources: dict[str, int],
) -> dict[str, Any]:
    slots = config.nodes * SLOTS_PER_NODE
    bound = lower_bound(seconds, slots=slots)
    ideal = greedy_makespan(seconds, slots=slots, barrier_batch=None)
    idle_cpu, idle_rss, cpu, rss, peak_rss = operator
    before, after = latency
    apiserver = {}
    for verb, buckets in after.items():
        window = bucket_delta(buckets, before.get(verb))
        total = max(window.values(), default=0.0)
        apiserver[verb] = {
            "requests": int(total),
            "p50_ms": round(1000 * bucket_quantile(window, 0.5), 2),
            "p99_ms": round(1000 * bucket_quantile(window, 0.99), 2),
        }
    ops_before, ops_after = operator_metrics_text
    reconcile = _histogram(ops_after, ops_before, "simtest_reconcile_seconds")
    planning = _histogram(ops_after, ops_before, "simtest_plan_seconds")
    steps = metric_total(ops_after, "simtest_reconcile_seconds_count") - metric_total(
        ops_before, "simtest_reconcile_seconds_count"
    )
    overhead = histogram_buckets(ops_after, "simtest_orchestration_overhead_seconds", "").get(
        "", {}
    )
    requests = metric_total(ops_after, "simtest_api_requests_total") - metric_total(
        ops_before, "simtest_api_requests_total"
    )
    kinds = sorted({k for s in samples for k in s["live"]})
    loads = [s["load1"] for s in samples]
    return {
        "config": dataclasses.asdict(config),
        "label": config.label,
        "scenarios": config.scenarios,
        "nodes": config.nodes,
        "slots": slots,
        "complete": complete,
        "passed": int(status.get("passed", 0) or 0),
        "makespan": round(makespan, 1),
        "bound": round(bound, 1),
        "ideal": round(ideal, 1),
        "bound_efficiency": round(bound / makespan, 3),
        "live_peak": {k: max(s["live"].get(k, 0) for s in samples) for k in kinds}
        if samples
        else {},
        "live_median": {k: statistics.median(s["live"].get(k, 0) for s in samples) for k in kinds}
        if samples
        else {},
        "live_final": final_live,
        "object_sizes": sizes,
        "finished": sum(
            int(status.get(k, 0) or 0)
            for k in ("passed", "failed", "errored", "timedOut", "invalid")
        ),
        "event_sources": event_sources,
        "window": max((s["in_flight"] for s in samples), default=0),
        "operator_idle_rss_mib": round(idle_rss, 1),
        "operator_peak_rss_mib": round(peak_rss, 1),
        "operator_end_rss_mib": round(rss, 1),
        "operator_rss_growth_mib": round(peak_rss - idle_rss, 1),
        "operator_cpu_seconds": round(cpu - idle_cpu, 1),
        "operator_cpu_ms_per_scenario": round(1000 * (cpu - idle_cpu) / len(seconds), 1),
        "operator_cpu_percent_median": statistics.median(s["operator_cpu_percent"] for s in samples)
        if samples
        else math.nan,
        "api_requests_per_scenario": round(requests / len(seconds), 2),
        "reconcile_steps": int(steps),
        "reconcile_mean_ms": reconcile["mean_ms"],
        "reconcile_p50_ms": reconcile["p50_ms"],
        "reconcile_p99_ms": reconcile["p99_ms"],
        "plan_mean_ms": planning["mean_ms"],
        "plan_p50_ms": planning["p50_ms"],
        "plan_p99_ms": planning["p99_ms"],
        "plan_mean_ms_last_quarter": _late_mean(samples, "plan_ms_mean"),
        "overhead_p50_s": round(bucket_quantile(overhead, 0.5), 3),
        "overhead_p95_s": round(bucket_quantile(overhead, 0.95), 3),
        "apiserver": apiserver,
        "probe_p50_ms": round(1000 * percentile(probes, 0.5), 2),
        "probe_p99_ms": round(1000 * percentile(probes, 0.99), 2),
        "etcd_db_peak_mib": max((s["etcd_db_mib"] for s in samples), default=math.nan),
        "etcd_in_use_peak_mib": max((s["etcd_in_use_mib"] for s in samples), default=math.nan),
        "component_cpu_seconds": components,
        "load1_median": statistics.median(loads) if loads else math.nan,
        "load1_max": max(loads, default=math.nan),
        "samples": samples,
    }


def _late_mean(samples: Sequence[dict[str, Any]], key: str) -> float:
    """Median of a per-sample figure over the last quarter of the run (growth shows here)."""
    values = [s[key] for s in samples[3 * len(samples) // 4 :] if not math.isnan(s[key])]
    return round(statistics.median(values), 3) if values else math.nan


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", default="200x5,2000x50", help="SCENARIOSxNODES, baseline first")
    parser.add_argument("--scale", type=float, default=0.5, help="35 s cap x scale (17.5 s)")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--budget", type=float, default=420.0, help="max seconds per campaign")
    parser.add_argument("--name", default="", help="suffix of the result files")
    args = parser.parse_args(argv)
    configs = [RunConfig.parse(text) for text in args.runs.split(",")]
    out = REPO / "bench" / "results"
    out.mkdir(parents=True, exist_ok=True)
    stem = out / ("operator_scale" + (f"-{args.name}" if args.name else ""))
    results: list[dict[str, Any]] = []
    began = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="simtest-scale-") as scratch:
        workdir = Path(scratch)
        prepare_templates(workdir)
        for config in configs:
            seconds = durations(config.scenarios, scale=args.scale, seed=args.seed)
            result = run(config, seconds=seconds, workdir=workdir, budget=args.budget)
            results.append(result)
            print(json.dumps({k: v for k, v in result.items() if k != "samples"}), flush=True)
            document = {
                "scale": args.scale,
                "cap_seconds": CAP_SECONDS * args.scale,
                "seed": args.seed,
                "slots_per_node": SLOTS_PER_NODE,
                "batch_size": BATCH_SIZE,
                "cpus": os.cpu_count(),
                "wall_seconds": round(time.monotonic() - began, 1),
                "runs": results,
            }
            stem.with_suffix(".json").write_text(json.dumps(document, indent=1))
    markdown = scalereport.markdown(document)
    stem.with_suffix(".md").write_text(markdown)
    scalereport.plot(results, stem.with_suffix(".png"))
    scalereport.print_table(document)


if __name__ == "__main__":
    main()
