"""Tables and plot of ``operator_scale.py``: the runs side by side with the last/first ratio."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

Run = Mapping[str, Any]


def _live(kind: str, which: str = "live_peak") -> Callable[[Run], float]:
    return lambda r: float(r[which].get(kind, math.nan))


def _api(verb: str, field: str) -> Callable[[Run], float]:
    return lambda r: float(r["apiserver"].get(verb, {}).get(field, math.nan))


def _kib(key: str) -> Callable[[Run], float]:
    return lambda r: float(r["object_sizes"][key]) / 1024


ROWS: tuple[tuple[str, Callable[[Run], float]], ...] = (
    ("scenarios", lambda r: r["config"]["scenarios"]),
    ("kwok nodes (3 slots each)", lambda r: r["config"]["nodes"]),
    ("complete (1 = yes)", lambda r: float(r["complete"])),
    ("scenarios finished", lambda r: r["finished"]),
    ("scenarios passed", lambda r: r["passed"]),
    ("makespan s", lambda r: r["makespan"]),
    ("lower bound s", lambda r: r["bound"]),
    ("slot efficiency (bound / makespan)", lambda r: r["bound_efficiency"]),
    ("zero-overhead makespan s (list order)", lambda r: r["ideal"]),
    ("efficiency vs zero overhead", lambda r: r["ideal"] / r["makespan"]),
    ("peak in flight (operator gauge)", lambda r: r["window"]),
    ("peak live SimEnvironments", _live("simenvironments")),
    (
        "peak live SimEnvironments / window",
        lambda r: r["live_peak"]["simenvironments"] / r["window"],
    ),
    ("peak live Pods", _live("pods")),
    ("peak live Pods / window", lambda r: r["live_peak"]["pods"] / r["window"]),
    ("peak live ScenarioBatches", _live("scenariobatches")),
    ("peak live ConfigMaps", _live("configmaps")),
    ("Events at the end", _live("events", "live_final")),
    ("frozen-list ConfigMaps", lambda r: r["object_sizes"]["scenario_list_objects"]),
    (
        "largest frozen-list ConfigMap KiB",
        lambda r: r["object_sizes"]["scenario_list_max_bytes"] / 1024,
    ),
    ("TestCampaign object KiB", lambda r: r["object_sizes"]["campaign_bytes"] / 1024),
    ("largest ScenarioBatch KiB", lambda r: r["object_sizes"]["batch_max_bytes"] / 1024),
    ("operator RSS idle MiB", lambda r: r["operator_idle_rss_mib"]),
    ("operator RSS peak MiB", lambda r: r["operator_peak_rss_mib"]),
    ("operator RSS growth MiB", lambda r: r["operator_rss_growth_mib"]),
    ("operator CPU ms / scenario", lambda r: r["operator_cpu_ms_per_scenario"]),
    ("operator CPU % (median sample)", lambda r: r["operator_cpu_percent_median"]),
    ("operator API requests / scenario", lambda r: r["api_requests_per_scenario"]),
    ("reconcile step mean ms", lambda r: r["reconcile_mean_ms"]),
    ("reconcile step p99 ms", lambda r: r["reconcile_p99_ms"]),
    ("plan (cache read + planning) mean ms", lambda r: r["plan_mean_ms"]),
    ("plan p99 ms", lambda r: r["plan_p99_ms"]),
    ("plan mean ms, last quarter of the run", lambda r: r["plan_mean_ms_last_quarter"]),
    ("orchestration overhead p50 s", lambda r: r["overhead_p50_s"]),
    ("API server latency p50 ms (all verbs)", _api("ALL", "p50_ms")),
    ("API server latency p99 ms (all verbs)", _api("ALL", "p99_ms")),
    ("API server p99 ms GET", _api("GET", "p99_ms")),
    ("API server p99 ms LIST", _api("LIST", "p99_ms")),
    ("API server p99 ms POST", _api("POST", "p99_ms")),
    ("API server p99 ms PATCH", _api("PATCH", "p99_ms")),
    ("API server p99 ms DELETE", _api("DELETE", "p99_ms")),
    (
        "API server requests / s (all clients)",
        lambda r: r["apiserver"]["ALL"]["requests"] / r["makespan"],
    ),
    ("probe GET p50 ms (client side)", lambda r: r["probe_p50_ms"]),
    ("probe GET p99 ms (client side)", lambda r: r["probe_p99_ms"]),
    ("etcd DB peak MiB", lambda r: r["etcd_db_peak_mib"]),
    ("control plane CPU s", lambda r: sum(r["component_cpu_seconds"].values())),
    (
        "control plane CPU ms per API request",
        lambda r: (
            1000 * sum(r["component_cpu_seconds"].values()) / r["apiserver"]["ALL"]["requests"]
        ),
    ),
    ("load average (1 min) median", lambda r: r["load1_median"]),
)


def _fmt(value: float) -> str:
    if isinstance(value, float) and math.isnan(value):
        return "-"
    if float(value).is_integer() and abs(value) >= 10:
        return f"{int(value)}"
    return f"{value:.3g}" if abs(value) < 100 else f"{value:.0f}"


def rows(runs: Sequence[Run]) -> list[list[str]]:
    """One row per figure: its values per run and the last/first ratio."""
    out = []
    for label, getter in ROWS:
        values = []
        for run in runs:
            try:
                values.append(float(getter(run)))
            except (KeyError, TypeError, ZeroDivisionError):
                values.append(math.nan)
        ratio = values[-1] / values[0] if len(values) > 1 and values[0] else math.nan
        out.append([label, *map(_fmt, values), f"{ratio:.2f}x" if not math.isnan(ratio) else "-"])
    return out


def markdown(document: Mapping[str, Any]) -> str:
    runs = document["runs"]
    head = ["figure", *(r["label"] for r in runs), "ratio"]
    lines = [
        f"Window mode, {document['slots_per_node']} simulator slots per kwok node, batchSize "
        f"{document['batch_size']}, durations {document['cap_seconds']:.1f} s cap (mean 0.75 cap, "
        f"sd 0.2), {document['cpus']} CPUs shared with other work; ratio = last run / first.",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    lines += ["| " + " | ".join(row) + " |" for row in rows(runs)]
    for run in runs:
        sources = ", ".join(f"{k} {v}" for k, v in sorted(run["event_sources"].items()))
        lines.append(f"\n{run['label']}: events by source: {sources or 'none'}.")
    return "\n".join(lines) + "\n"


def print_table(document: Mapping[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    runs = document["runs"]
    table = Table(title="operator at scale (window mode, real control plane, kwok nodes)")
    table.add_column("figure")
    for run in runs:
        table.add_column(run["label"], justify="right")
    table.add_column("ratio", justify="right", style="bold")
    for row in rows(runs):
        table.add_row(*row)
    Console().print(table)


def plot(runs: Sequence[Run], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    live, rss, latency, progress = axes.flat
    styles = ("--", "-", ":", "-.")
    for run, style in zip(runs, styles, strict=False):
        samples = run["samples"]
        t = [s["t"] for s in samples]
        name = run["label"]
        for kind, color in (
            ("simenvironments", "tab:blue"),
            ("pods", "tab:orange"),
            ("scenariobatches", "tab:green"),
            ("events", "tab:grey"),
        ):
            live.plot(
                t,
                [s["live"].get(kind, 0) for s in samples],
                style,
                color=color,
                label=f"{kind} {name}",
            )
        rss.plot(
            t,
            [s["operator_rss_mib"] for s in samples],
            style,
            color="tab:purple",
            label=f"RSS {name}",
        )
        probe = [(s["t"], s["probe_ms_p50"]) for s in samples]
        latency.plot(
            *zip(*probe, strict=True), style, color="tab:red", label=f"probe GET p50 {name}"
        )
        api = [(s["t"], s["apiserver_p99_ms"]) for s in samples if "apiserver_p99_ms" in s]
        if api:
            latency.plot(
                *zip(*api, strict=True),
                style,
                color="black",
                marker=".",
                label=f"API server p99 {name}",
            )
        plans = [
            (s["t"], s["plan_ms_mean"]) for s in samples if s["plan_ms_mean"] == s["plan_ms_mean"]
        ]
        if plans:
            latency.plot(
                *zip(*plans, strict=True), style, color="tab:green", label=f"plan step mean {name}"
            )
        total = run["config"]["scenarios"]
        progress.plot(
            t,
            [s["finished"] / total for s in samples],
            style,
            color="tab:green",
            label=f"finished fraction {name}",
        )
        progress.plot(
            t,
            [s["operator_cpu_percent"] / 100 for s in samples],
            style,
            color="tab:purple",
            label=f"operator CPU (cores) {name}",
        )
    live.set_ylabel("live objects in the namespace")
    live.set_yscale("symlog")
    rss.set_ylabel("operator RSS MiB")
    rss.set_ylim(bottom=0)
    latency.set_ylabel("request latency ms")
    latency.set_yscale("log")
    progress.set_ylabel("fraction / cores")
    for axis in axes.flat:
        axis.legend(fontsize=6)
        axis.grid(alpha=0.3)
    for axis in axes[1]:
        axis.set_xlabel("seconds since the campaign was created")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
