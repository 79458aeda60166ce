"""The seed paper's Table 1, redone on kwok nodes with the real control plane.

For every combination of simulators per node ``s``, batch size ``b`` and start policy (the
paper's batch barrier, and our refilled window) a campaign of N scenarios runs on 3 fake nodes
that advertise ``s`` ``simtest.dev/simulator`` slots each. Scenario durations are the paper's
35 s cap scaled down (``--scale``) with a realistic spread (truncated normal, seeded), carried to
kwok through pod annotations by a bench-only environment template. The operator runs as a real
``simtest operator`` process.

Reported per run: makespan; slot efficiency = ideal makespan / actual, with the ideal
``max(sum(d) / slots, max(d))``; orchestration overhead per scenario (makespan x slots - sum(d))
/ N, and p50/p95 of each pod's lifetime minus its duration; API requests per scenario (the
operator's own client, from its /metrics); operator CPU seconds and peak RSS.

    python bench/operator_table1.py                # full matrix: 200 scenarios, 35 s -> 3.5 s
    python bench/operator_table1.py --scenarios 60 --s 1,2,3 --b 9,60 --name quick
    python bench/operator_table1.py --kubeconfig PATH     # an already running dev cluster

Results go to ``bench/results/operator_table1[-NAME].{json,md,png}``.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import re
import statistics
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from kubernetes import client

from kwokbench import (
    CAMPAIGN,
    CAP_SECONDS,
    GROUP,
    REPO,
    VERSION,
    PodClock,
    campaign_body,
    campaign_complete,
    dev_cluster,
    durations,
    fake_nodes,
    greedy_makespan,
    metric_total,
    new_namespace,
    operator_metrics,
    operator_process,
    prepare_templates,
    proc_usage,
    set_slots,
    write_scenarios,
)
from simtest_operator.devcluster import provisioning

NODES = 3


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Config:
    simulators: int
    batch: int
    barrier: bool

    @property
    def label(self) -> str:
        return f"s{self.simulators}-b{self.batch}-{'barrier' if self.barrier else 'window'}"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Result:
    config: Config
    scenarios: int
    makespan: float
    ideal: float
    """Makespan of the same policy with zero orchestration overhead (list order, greedy)."""
    bound: float
    """Lower bound of any schedule: max(sum(d) / slots, max(d))."""
    efficiency: float
    """ideal / makespan: how much of the achievable speed the orchestration keeps."""
    bound_efficiency: float
    overhead_per_scenario: float
    lifetime_overhead_p50: float
    lifetime_overhead_p95: float
    api_requests_per_scenario: float
    operator_cpu_seconds: float
    operator_peak_rss_mib: float
    passed: int
    refill_p50: float = float("nan")
    """Seconds from a pod's end to the next pod's creation (window mode: the refill latency)."""
    refill_p95: float = float("nan")
    first_pod_seconds: float = float("nan")
    """From campaign creation to the first simulator pod (resolution, batch, environment)."""


def run_one(
    api: client.ApiClient,
    kubeconfig: Path,
    nodes: Sequence[str],
    config: Config,
    *,
    seconds: Sequence[float],
    workdir: Path,
) -> Result:
    core = client.CoreV1Api(api)
    custom = client.CustomObjectsApi(api)
    namespace = new_namespace(api)
    set_slots(core, nodes, config.simulators)
    sources = workdir / namespace
    write_scenarios(sources, seconds)
    body = campaign_body(
        {
            "batchSize": config.batch,
            "batchBarrier": config.barrier,
            "maxSimulatorsPerNode": config.simulators,
            "timeoutSeconds": 600,
            "pendingTimeoutSeconds": 3600,
            "retries": 0,
        }
    )
    try:
        with (
            operator_process(
                namespace=namespace,
                kubeconfig=kubeconfig,
                templates=workdir / "templates",
                sources=sources,
                cache=workdir / "cache",
                log=workdir / f"{config.label}.log",
            ) as (operator, port),
            PodClock(core, namespace) as clock,
        ):
            custom.create_namespaced_custom_object(GROUP, VERSION, namespace, "testcampaigns", body)
            started = time.monotonic()
            status: dict[str, Any] = {}
            while True:
                reply: Any = custom.get_namespaced_custom_object(
                    GROUP, VERSION, namespace, "testcampaigns", CAMPAIGN
                )
                status = dict(reply.get("status") or {})
                if campaign_complete(status):
                    break
                if operator.poll() is not None:
                    raise RuntimeError(f"operator exited; see {workdir / config.label}.log")
                time.sleep(0.1)
            makespan = time.monotonic() - started
            metrics = operator_metrics(port)
            cpu, _, rss = proc_usage(operator.pid)
    finally:
        core.delete_namespace(namespace, grace_period_seconds=0)
    slots = NODES * config.simulators
    total = sum(seconds)
    ideal = greedy_makespan(
        seconds, slots=slots, barrier_batch=config.batch if config.barrier else None
    )
    bound = max(total / slots, max(seconds))
    by_name = {f"s{i:04d}": d for i, d in enumerate(seconds)}
    overheads = []
    for pod, created in clock.created.items():
        ended = clock.ended.get(pod)
        match = re.search(r"-b(\d{5})-e(\d{3})-a", pod)
        if ended is None or match is None:
            continue
        index = int(match.group(1)) * config.batch + int(match.group(2))
        overheads.append(ended - created - by_name[f"s{index:04d}"])
    overheads.sort()
    creations = sorted(clock.created.values())
    gaps = sorted(
        next((c for c in creations if c >= end), end) - end
        for end in sorted(clock.ended.values())[:-1]
    )
    requests = metric_total(metrics, "simtest_api_requests_total")
    return Result(
        config=config,
        scenarios=len(seconds),
        makespan=round(makespan, 2),
        ideal=round(ideal, 2),
        efficiency=round(ideal / makespan, 3),
        bound=round(bound, 2),
        bound_efficiency=round(bound / makespan, 3),
        overhead_per_scenario=round((makespan * slots - total) / len(seconds), 3),
        lifetime_overhead_p50=round(statistics.median(overheads), 3) if overheads else float("nan"),
        lifetime_overhead_p95=round(overheads[int(0.95 * (len(overheads) - 1))], 3)
        if overheads
        else float("nan"),
        api_requests_per_scenario=round(requests / len(seconds), 2),
        operator_cpu_seconds=round(cpu, 2),
        operator_peak_rss_mib=round(rss, 1),
        passed=int(status.get("passed", 0)),
        refill_p50=round(statistics.median(gaps), 3) if gaps else float("nan"),
        refill_p95=round(gaps[int(0.95 * (len(gaps) - 1))], 3) if gaps else float("nan"),
        first_pod_seconds=round(creations[0] - started, 3) if creations else float("nan"),
    )


@contextlib.contextmanager
def cluster(kubeconfig: Path | None, workdir: Path) -> Iterator[tuple[Path, list[str]]]:
    if kubeconfig is not None:
        yield kubeconfig, fake_nodes(kubeconfig)[:NODES]
        return
    with dev_cluster(workdir / "cluster", nodes=NODES, slots=3) as info:
        yield info.kubeconfig, list(info.nodes)


def table(results: Sequence[Result]) -> str:
    lines = [
        "| config | makespan s | ideal s (policy, 0 overhead) | efficiency | lower bound s "
        "| bound efficiency | overhead/scenario s | refill p50 / p95 s | API req/scenario "
        "| operator CPU s | peak RSS MiB |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        lines.append(
            f"| {r.config.label} | {r.makespan} | {r.ideal} | {r.efficiency} | {r.bound} | "
            f"{r.bound_efficiency} | {r.overhead_per_scenario} | "
            f"{r.refill_p50} / {r.refill_p95} | {r.api_requests_per_scenario} | "
            f"{r.operator_cpu_seconds} | {r.operator_peak_rss_mib} |"
        )
    return "\n".join(lines) + "\n"


def plot(results: Sequence[Result], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(8, 4))
    batches = sorted({r.config.batch for r in results})
    for barrier, style in ((True, "--"), (False, "-")):
        for s in sorted({r.config.simulators for r in results}):
            points = [
                (r.config.batch, r.bound_efficiency)
                for r in results
                if r.config.barrier == barrier and r.config.simulators == s
            ]
            if points:
                points.sort()
                axis.plot(
                    [batches.index(b) for b, _ in points],
                    [e for _, e in points],
                    style,
                    marker="o",
                    label=f"s={s} {'barrier' if barrier else 'window'}",
                )
    axis.set_xticks(range(len(batches)), [str(b) for b in batches])
    axis.set_xlabel("batch size b")
    axis.set_ylabel("slot efficiency (lower bound / actual makespan)")
    axis.set_ylim(0, 1.05)
    axis.axhline(0.9, color="grey", linewidth=0.5)
    axis.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=120)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", type=int, default=200)
    parser.add_argument("--scale", type=float, default=0.1, help="35 s cap x scale (default 3.5 s)")
    parser.add_argument("--s", default="1,2,3")
    parser.add_argument("--b", default="1,9,60,200")
    parser.add_argument("--modes", default="barrier,window")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--kubeconfig", type=Path)
    parser.add_argument("--name", default="", help="suffix of the result files")
    args = parser.parse_args(argv)
    configs = [
        Config(simulators=int(s), batch=int(b), barrier=mode == "barrier")
        for mode in args.modes.split(",")
        for s in args.s.split(",")
        for b in args.b.split(",")
    ]
    seconds = durations(args.scenarios, scale=args.scale, seed=args.seed)
    out = REPO / "bench" / "results"
    out.mkdir(parents=True, exist_ok=True)
    stem = out / ("operator_table1" + (f"-{args.name}" if args.name else ""))
    results: list[Result] = []
    with tempfile.TemporaryDirectory(prefix="simtest-bench-") as scratch:
        workdir = Path(scratch)
        prepare_templates(workdir)
        with cluster(args.kubeconfig, workdir) as (kubeconfig, nodes):
            api = provisioning.api_client(kubeconfig)
            try:
                for config in configs:
                    result = run_one(
                        api, kubeconfig, nodes, config, seconds=seconds, workdir=workdir
                    )
                    results.append(result)
                    print(json.dumps(dataclasses.asdict(result)), flush=True)
                    stem.with_suffix(".json").write_text(
                        json.dumps(
                            {
                                "scenarios": args.scenarios,
                                "scale": args.scale,
                                "seed": args.seed,
                                "results": [dataclasses.asdict(r) for r in results],
                            },
                            indent=2,
                        )
                    )
            finally:
                set_slots(client.CoreV1Api(api), nodes, 3)
                api.close()  # type: ignore[no-untyped-call]
    stem.with_suffix(".md").write_text(
        f"{args.scenarios} scenarios, durations {CAP_SECONDS} s x {args.scale} cap (mean 0.75 cap, "
        f"sd 0.2), {NODES} kwok nodes x s simulator slots.\n\n" + table(results)
    )
    plot(results, stem.with_suffix(".png"))
    print(table(results))


if __name__ == "__main__":
    main()
