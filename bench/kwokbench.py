"""Shared machinery of the operator benches on kwok nodes with the real control plane.

Both ``operator_table1.py`` (the seed's Table 1) and ``operator_scale.py`` (2,000 scenarios on
50 nodes) start the dev control plane, write N copies of a smoke scenario whose file names carry
their fake durations, render pods through a bench-only environment template that turns the
duration into kwok's fake-run annotations, run the real ``simtest operator`` process and read
/proc and Prometheus text. This module holds those pieces so the benches only differ in what they
vary and measure.
"""

from __future__ import annotations

import contextlib
import math
import os
import random
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from kubernetes import client, watch

from simtest_operator.devcluster import provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.state import ClusterInfo
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.settings import Settings

REPO = Path(__file__).resolve().parents[1]
GROUP, VERSION = "simtest.dev", "v1alpha1"
CAP_SECONDS = 35.0
"""The seed paper's scenario length cap."""
SMOKE = REPO / "scenarios" / "smoke" / "cut-in_highway_v25_gap30_dv5.xosc"
CAMPAIGN = "bench"

BENCH_VALUES = """{#- Bench-only: kwok fake runs; the id holds the duration (d<ms>). -#}
{%- set ms = scenario.id.split("-d")[1].split(".")[0] | int %}
{%- set message = {"verdict": "Passed", "wallSeconds": ms / 1000} | json %}
{%- set extraPodAnnotations = {"simtest.dev/fake-duration": (ms / 1000) ~ "s",
    "simtest.dev/fake-termination-message": message} %}
{% include "default/values.yaml.j2" %}
"""
BENCH_POD = '{% include "default/pod.yaml.j2" %}\n'


# --- workload ----------------------------------------------------------------------------------


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


def lower_bound(seconds: Sequence[float], *, slots: int) -> float:
    """No schedule on ``slots`` slots is shorter: max(sum(d) / slots, max(d))."""
    return max(sum(seconds) / slots, max(seconds))


def prepare_templates(workdir: Path) -> Path:
    """The default environment templates plus the bench's ``bench`` template; returns the root."""
    templates = workdir / "templates"
    shutil.copytree(REPO / "helm-templates" / "default", templates / "default")
    (templates / "bench").mkdir()
    (templates / "bench" / "values.yaml.j2").write_text(BENCH_VALUES)
    (templates / "bench" / "pod.yaml.j2").write_text(BENCH_POD)
    return templates


def write_scenarios(sources: Path, seconds: Sequence[float]) -> None:
    """``sources/scenarios/s<i>-d<ms>.xosc``: distinct copies of the smoke scenario."""
    (sources / "scenarios").mkdir(parents=True)
    text = SMOKE.read_text()
    for i, duration in enumerate(seconds):
        name = f"s{i:04d}-d{int(duration * 1000)}.xosc"
        (sources / "scenarios" / name).write_text(text + f"<!-- {name} -->\n")


def campaign_body(execution: Mapping[str, Any]) -> dict[str, Any]:
    """The bench campaign: every scenario of the sources, the ``bench`` template."""
    return {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "TestCampaign",
        "metadata": {"name": CAMPAIGN},
        "spec": {
            "scenarios": {"sources": [{"path": "scenarios"}], "include": ["*.xosc"]},
            "environment": {"template": "bench"},
            "execution": dict(execution),
        },
    }


def campaign_complete(status: Mapping[str, Any]) -> bool:
    return any(
        c.get("type") == "Complete" and c.get("status") == "True"
        for c in status.get("conditions", [])
    )


# --- cluster and operator ----------------------------------------------------------------------


@contextlib.contextmanager
def dev_cluster(workdir: Path, *, nodes: int, slots: int) -> Iterator[ClusterInfo]:
    """A fresh dev cluster with ``nodes`` kwok nodes, stopped on exit."""
    dev = DevCluster(
        workdir, Toolchain(root=Settings.from_env().cache.toolchain), tied_to_this_process=True
    )
    info = dev.up(nodes=nodes, slots=slots, crds_dir=REPO / "crds", timeout=180.0)
    try:
        yield info
    finally:
        dev.down()


def fake_nodes(kubeconfig: Path) -> list[str]:
    """Names of the kwok nodes of an already running cluster."""
    api = provisioning.api_client(kubeconfig)
    try:
        return [
            str(n.metadata.name)
            for n in client.CoreV1Api(api).list_node().items
            if n.metadata and (n.metadata.annotations or {}).get("kwok.x-k8s.io/node") == "fake"
        ]
    finally:
        api.close()  # type: ignore[no-untyped-call]


def new_namespace(api: client.ApiClient) -> str:
    """A fresh ``bench-*`` namespace, once its default service account exists."""
    namespace = f"bench-{secrets.token_hex(3)}"
    client.CoreV1Api(api).create_namespace({"metadata": {"name": namespace}})  # type: ignore[arg-type]
    while not provisioning.default_service_account_exists(api, namespace):
        time.sleep(0.1)
    return namespace


def set_slots(core: client.CoreV1Api, nodes: Sequence[str], slots: int) -> None:
    for node in nodes:
        patch = {
            "status": {
                "capacity": {"simtest.dev/simulator": str(slots)},
                "allocatable": {"simtest.dev/simulator": str(slots)},
            }
        }
        core.patch_node_status(node, patch)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextlib.contextmanager
def operator_process(
    *,
    namespace: str,
    kubeconfig: Path,
    templates: Path,
    sources: Path,
    cache: Path,
    log: Path,
    ready_timeout: float = 90.0,
    env: Mapping[str, str] | None = None,
) -> Iterator[tuple[subprocess.Popen[bytes], int]]:
    """A real ``simtest operator`` for ``namespace``, ready; yields (process, metrics port)."""
    port = free_port()
    with log.open("wb") as out:
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
                str(cache),
                "--metrics-port",
                str(port),
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
            env={**os.environ, **(env or {})},
        )
        try:
            wait_ready(port, operator, timeout=ready_timeout)
            yield operator, port
        finally:
            operator.send_signal(signal.SIGTERM)
            with contextlib.suppress(subprocess.TimeoutExpired):
                operator.wait(timeout=20)
            if operator.poll() is None:
                operator.kill()
                operator.wait(timeout=10)


def wait_ready(port: int, operator: subprocess.Popen[bytes], timeout: float = 60.0) -> None:
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


def operator_metrics(port: int) -> str:
    return str(
        urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=10).read().decode()
    )


# --- measuring ---------------------------------------------------------------------------------


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


def metric_total(text: str, name: str) -> float:
    """Sum of every sample of ``name`` (all label sets) in Prometheus text."""
    return sum(
        float(m.group(1)) for m in re.finditer(rf"^{name}(?:{{[^}}]*}})? ([0-9.e+-]+)$", text, re.M)
    )


Buckets = dict[float, float]
"""Upper bound -> cumulative count of one Prometheus histogram."""


def histogram_buckets(
    text: str, name: str, group_by: str, *, where: Mapping[str, str] | None = None
) -> dict[str, Buckets]:
    """Cumulative ``<name>_bucket`` counts summed over all other labels, per value of
    ``group_by``; ``where`` keeps only samples whose labels equal its values."""
    out: dict[str, Buckets] = {}
    pattern = re.compile(rf"^{name}_bucket{{([^}}]*)}} ([0-9.e+-]+)$", re.M)
    for match in pattern.finditer(text):
        labels = dict(re.findall(r'(\w+)="([^"]*)"', match.group(1)))
        if where and any(labels.get(k) != v for k, v in where.items()):
            continue
        bound = math.inf if labels.get("le") == "+Inf" else float(labels.get("le", "nan"))
        group = out.setdefault(labels.get(group_by, ""), {})
        group[bound] = group.get(bound, 0.0) + float(match.group(2))
    return out


def bucket_delta(after: Buckets, before: Buckets | None) -> Buckets:
    return {b: c - (before or {}).get(b, 0.0) for b, c in after.items()}


def bucket_quantile(buckets: Buckets, q: float) -> float:
    """Prometheus ``histogram_quantile``: linear interpolation inside the bucket."""
    ordered = sorted(buckets.items())
    if not ordered or ordered[-1][1] <= 0:
        return math.nan
    rank = q * ordered[-1][1]
    lower, below = 0.0, 0.0
    for bound, count in ordered:
        if count >= rank:
            if math.isinf(bound):
                return lower
            if count == below:
                return bound
            return lower + (bound - lower) * (rank - below) / (count - below)
        lower, below = bound, count
    return lower


def proc_usage(pid: int) -> tuple[float, float, float]:
    """(CPU seconds, current RSS MiB, peak RSS MiB) of a process, from /proc."""
    with Path(f"/proc/{pid}/stat").open() as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    cpu = (int(fields[11]) + int(fields[12])) / ticks
    rss = peak = 0.0
    with Path(f"/proc/{pid}/status").open() as handle:
        for line in handle:
            if line.startswith("VmRSS:"):
                rss = int(line.split()[1]) / 1024
            elif line.startswith("VmHWM:"):
                peak = int(line.split()[1]) / 1024
    return cpu, rss, peak


def percentile(values: Sequence[float], q: float) -> float:
    """Nearest-rank percentile (NaN when empty)."""
    ordered = sorted(values)
    if not ordered:
        return math.nan
    return ordered[min(int(q * (len(ordered) - 1) + 0.5), len(ordered) - 1)]
