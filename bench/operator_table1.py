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
import os
import random
import re
import secrets
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from kubernetes import client, watch

from simtest_operator.devcluster import provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.settings import Settings

REPO = Path(__file__).resolve().parents[1]
GROUP, VERSION = "simtest.dev", "v1alpha1"
CAP_SECONDS = 35.0
NODES = 3
SMOKE = REPO / "scenarios" / "smoke" / "cut-in_highway_v25_gap30_dv5.xosc"

BENCH_VALUES = """{#- Bench-only: kwok fake runs; the id holds the duration (d<ms>). -#}
{%- set ms = scenario.id.split("-d")[1].split(".")[0] | int %}
{%- set message = {"verdict": "Passed", "wallSeconds": ms / 1000} | json %}
{%- set extraPodAnnotations = {"simtest.dev/fake-duration": (ms / 1000) ~ "s",
    "simtest.dev/fake-termination-message": message} %}
{% include "default/values.yaml.j2" %}
"""
BENCH_POD = '{% include "default/pod.yaml.j2" %}\n'


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


def durations(count: int, *, scale: float, seed: int) -> list[float]:
    """Truncated-normal scenario durations: mean 0.75 of the cap, sd 0.2, within [0.2, 1] x cap."""
    rng = random.Random(seed)
    cap = CAP_SECONDS * scale
    out = []
    for _ in range(count):
        value = rng.gauss(0.75, 0.2)
        out.append(round(min(max(value, 0.2), 1.0) * cap, 3))
    return out


def greedy_makespan(seconds: Sequence[float], *, slots: int, barrier_batch: int | None) -> float:
    """Makespan of starting scenarios in list order on the first free slot, with no overhead;
    with a barrier, batch by batch (each batch starts when the previous one has ended)."""
    groups = (
        [list(seconds)]
        if barrier_batch is None
        else [list(seconds[i : i + barrier_batch]) for i in range(0, len(seconds), barrier_batch)]
    )
    clock = 0.0
    for group in groups:
        free = [clock] * slots
        end = clock
        for duration in group:
            start = min(free)
            free[free.index(start)] = start + duration
            end = max(end, start + duration)
        clock = end
    return clock


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class PodClock:
    """Watches simulator pods; records when each was created and when it terminated."""

    def __init__(self, core: client.CoreV1Api, namespace: str) -> None:
        self.core = core
        self.namespace = namespace
        self.created: dict[str, float] = {}
        self.ended: dict[str, float] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> PodClock:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join(timeout=10)

    def _run(self) -> None:
        while not self._stop.is_set():
            watcher: Any = watch.Watch()  # type: ignore[no-untyped-call]
            stream = watcher.stream(
                self.core.list_namespaced_pod, self.namespace, timeout_seconds=2
            )
            for event in stream:
                pod = event["object"]
                name = pod.metadata.name
                now = time.monotonic()
                self.created.setdefault(name, now)
                statuses = pod.status.container_statuses or []
                if any(s.state and s.state.terminated for s in statuses):
                    self.ended.setdefault(name, now)
                if self._stop.is_set():
                    break


def _metric_total(text: str, name: str) -> float:
    return sum(
        float(m.group(1)) for m in re.finditer(rf"^{name}(?:{{[^}}]*}})? ([0-9.e+-]+)$", text, re.M)
    )


def _proc_usage(pid: int) -> tuple[float, float]:
    with Path(f"/proc/{pid}/stat").open() as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    cpu = (int(fields[11]) + int(fields[12])) / ticks
    rss = 0.0
    with Path(f"/proc/{pid}/status").open() as handle:
        for line in handle:
            if line.startswith("VmHWM:"):
                rss = int(line.split()[1]) / 1024
    return cpu, rss


def _wait_ready(port: int, operator: subprocess.Popen[bytes], timeout: float = 60.0) -> None:
    """Until the operator answers /readyz (its start-up is not part of the makespan)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if operator.poll() is not None:
            raise RuntimeError("operator exited during start-up")
        with contextlib.suppress(OSError):
            if urllib.request.urlopen(f"http://127.0.0.1:{port}/readyz", timeout=2).status == 200:
                time.sleep(1.0)  # kopf's initial listings
                return
        time.sleep(0.2)
    raise RuntimeError("operator not ready")


def set_slots(core: client.CoreV1Api, nodes: Sequence[str], slots: int) -> None:
    for node in nodes:
        patch = {
            "status": {
                "capacity": {"simtest.dev/simulator": str(slots)},
                "allocatable": {"simtest.dev/simulator": str(slots)},
            }
        }
        core.patch_node_status(node, patch)


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
    namespace = f"bench-{secrets.token_hex(3)}"
    core.create_namespace({"metadata": {"name": namespace}})  # type: ignore[arg-type]
    while not provisioning.default_service_account_exists(api, namespace):
        time.sleep(0.1)
    set_slots(core, nodes, config.simulators)
    sources = workdir / namespace
    (sources / "scenarios").mkdir(parents=True)
    text = SMOKE.read_text()
    for i, duration in enumerate(seconds):
        name = f"s{i:04d}-d{int(duration * 1000)}.xosc"
        (sources / "scenarios" / name).write_text(text + f"<!-- {name} -->\n")
    templates = workdir / "templates"
    port = free_port()
    log = (workdir / f"{config.label}.log").open("wb")
    operator = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "from simtest_operator.cli.main import main; main()",
            "operator",
            "--namespace",
            namespace,
            "--kubeconfig",
            str(kubeconfig),
            "--templates",
            str(templates),
            "--sources",
            str(sources),
            "--cache",
            str(workdir / "cache"),
            "--metrics-port",
            str(port),
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
    )
    execution: dict[str, Any] = {
        "batchSize": config.batch,
        "batchBarrier": config.barrier,
        "maxSimulatorsPerNode": config.simulators,
        "timeoutSeconds": 600,
        "pendingTimeoutSeconds": 3600,
        "retries": 0,
    }
    body = {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "TestCampaign",
        "metadata": {"name": "bench"},
        "spec": {
            "scenarios": {"sources": [{"path": "scenarios"}], "include": ["*.xosc"]},
            "environment": {"template": "bench"},
            "execution": execution,
        },
    }
    try:
        _wait_ready(port, operator)
        with PodClock(core, namespace) as clock:
            custom.create_namespaced_custom_object(GROUP, VERSION, namespace, "testcampaigns", body)
            started = time.monotonic()
            status: dict[str, Any] = {}
            while True:
                reply: Any = custom.get_namespaced_custom_object(
                    GROUP, VERSION, namespace, "testcampaigns", "bench"
                )
                status = dict(reply.get("status") or {})
                if any(
                    c["type"] == "Complete" and c["status"] == "True"
                    for c in status.get("conditions", [])
                ):
                    break
                if operator.poll() is not None:
                    raise RuntimeError(f"operator exited; see {log.name}")
                time.sleep(0.1)
            makespan = time.monotonic() - started
        metrics = (
            urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=10).read().decode()
        )
        cpu, rss = _proc_usage(operator.pid)
    finally:
        operator.send_signal(signal.SIGTERM)
        with contextlib.suppress(subprocess.TimeoutExpired):
            operator.wait(timeout=20)
        if operator.poll() is None:
            operator.kill()
        log.close()
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
    requests = _metric_total(metrics, "simtest_api_requests_total")
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
        api = provisioning.api_client(kubeconfig)
        nodes = [
            str(n.metadata.name)
            for n in client.CoreV1Api(api).list_node().items
            if n.metadata and (n.metadata.annotations or {}).get("kwok.x-k8s.io/node") == "fake"
        ]
        api.close()  # type: ignore[no-untyped-call]
        yield kubeconfig, [str(n) for n in nodes[:NODES]]
        return
    dev = DevCluster(
        workdir / "cluster",
        Toolchain(root=Settings.from_env().cache.toolchain),
        tied_to_this_process=True,
    )
    info = dev.up(nodes=NODES, slots=3, crds_dir=REPO / "crds")
    try:
        yield info.kubeconfig, list(info.nodes)
    finally:
        dev.down()


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
        templates = workdir / "templates"
        shutil.copytree(REPO / "helm-templates" / "default", templates / "default")
        (templates / "bench").mkdir()
        (templates / "bench" / "values.yaml.j2").write_text(BENCH_VALUES)
        (templates / "bench" / "pod.yaml.j2").write_text(BENCH_POD)
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
