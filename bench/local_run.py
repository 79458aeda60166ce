"""Benchmark of ``simtest run``: the 200-scenario suite with one worker against all cores.

Runs the same campaign twice in one go, side by side — ``--parallel 1`` and the default (all
cores) — each as a real ``simtest run`` process, after a warm-up run of the smoke campaign (so
the SUMO network cache is warm for every road and both configurations start equal). Reports
per configuration:

* wall time, throughput and speed-up against ``--parallel 1``;
* CPU time of ``simtest run`` and all its workers (``wait4`` rusage) and CPU utilisation
  (CPU seconds / (wall seconds x cores));
* engine time: the sum and median of the per-scenario wall times measured inside the workers;
* orchestration overhead per scenario and slot: ``(wall x workers - sum of engine time) / n``,
  i.e. what a slot spends on anything but running a scenario (process start, imports, locating,
  result writing, the results store, JUnit and the report);
* that both runs reached identical verdicts (they must: seeds are fixed).

Prints a rich table, writes the figures as JSON and a PNG plot (matplotlib)::

    python bench/local_run.py                      # scenarios/seed-experiment-campaign.yaml
    python bench/local_run.py --png docs/local-run.png --json docs/local-run.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

REPO = Path(__file__).resolve().parents[1]
SIMTEST = [sys.executable, "-c", "from simtest_operator.cli.main import main; main()"]


def run_once(manifest: Path, out: Path, parallel: int | None) -> dict[str, Any]:
    """One ``simtest run`` process; returns wall time, CPU time and the per-scenario results."""
    args = [*SIMTEST, "run", str(manifest), "-o", str(out), "--plain"]
    if parallel is not None:
        args += ["--parallel", str(parallel)]
    load_before = os.getloadavg()[0]
    log = out.with_suffix(".log")
    with log.open("w") as sink:
        started = time.perf_counter()
        epoch = time.time()
        process = subprocess.Popen(args, stdout=sink, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - started
    process.returncode = os.waitstatus_to_exitcode(status)
    state = json.loads((out / "campaign.json").read_text())
    scenarios = [json.loads(p.read_text()) for p in sorted(out.glob("scenarios/*/result.json"))]
    return {
        "parallel": state["parallel"],
        "exitCode": process.returncode,
        "wall": wall,
        "campaignWall": state["wallSeconds"],
        "cpu": usage.ru_utime + usage.ru_stime,
        "loadBefore": load_before,
        "loadAfter": os.getloadavg()[0],
        "engine": [s["wallSeconds"] for s in scenarios],
        "simulated": [s["simulatedSeconds"] for s in scenarios],
        "verdicts": {s["scenarioId"]: s["verdict"] for s in scenarios},
        "launched": epoch,
        "timings": [
            (_epoch(s["timing"]["started"]), _epoch(s["timing"]["finished"]), s["timing"]["pid"])
            for s in scenarios
            if "timing" in s
        ],
    }


def _epoch(iso: str) -> float:
    return datetime.datetime.fromisoformat(iso).timestamp()


def figures(run: dict[str, Any], cores: int, baseline_wall: float) -> dict[str, float]:
    """The derived figures of one configuration."""
    n = len(run["engine"])
    engine_sum = sum(run["engine"])
    first = min(t[0] for t in run["timings"])
    last = max(t[1] for t in run["timings"])
    busy = sum(t[1] - t[0] for t in run["timings"])
    return {
        "startupSeconds": first - run["launched"],
        "executionSeconds": last - first,
        "finishingSeconds": run["launched"] + run["wall"] - last,
        "slotBusy": busy / ((last - first) * run["parallel"]),
        "scenarios": n,
        "workers": run["parallel"],
        "wallSeconds": run["wall"],
        "speedup": baseline_wall / run["wall"],
        "throughputPerMinute": 60.0 * n / run["wall"],
        "cpuSeconds": run["cpu"],
        "cpuUtilisation": run["cpu"] / (run["wall"] * cores),
        "engineSecondsSum": engine_sum,
        "engineSecondsMedian": statistics.median(run["engine"]),
        "simulatedSecondsMedian": statistics.median(run["simulated"]),
        "overheadPerScenario": (run["wall"] * run["parallel"] - engine_sum) / n,
        "loadBefore": run["loadBefore"],
        "loadAfter": run["loadAfter"],
    }


def table(rows: dict[str, dict[str, float]], cores: int) -> Table:
    """The side-by-side rich table."""
    result = Table(
        title=f"simtest run, {next(iter(rows.values()))['scenarios']:.0f} scenarios, {cores} cores"
    )
    result.add_column("figure")
    for name in rows:
        result.add_column(name, justify="right")
    lines = [
        ("worker processes", "workers", "{:.0f}"),
        ("wall time (s)", "wallSeconds", "{:.1f}"),
        ("  start-up until the first scenario (s)", "startupSeconds", "{:.1f}"),
        ("  first start to last finish (s)", "executionSeconds", "{:.1f}"),
        ("  last finish to exit: store, JUnit, report (s)", "finishingSeconds", "{:.1f}"),
        ("slots busy in between", "slotBusy", "{:.0%}"),
        ("speed-up vs --parallel 1", "speedup", "{:.2f}x"),
        ("throughput (scenarios/min)", "throughputPerMinute", "{:.0f}"),
        ("CPU time (s)", "cpuSeconds", "{:.1f}"),
        ("CPU utilisation", "cpuUtilisation", "{:.0%}"),
        ("engine time, sum (s)", "engineSecondsSum", "{:.1f}"),
        ("engine time per scenario, median (s)", "engineSecondsMedian", "{:.2f}"),
        ("simulated time per scenario, median (s)", "simulatedSecondsMedian", "{:.1f}"),
        ("overhead per scenario and slot (s)", "overheadPerScenario", "{:.3f}"),
        ("load average before / after", "loadBefore", "{:.1f}"),
    ]
    for label, key, fmt in lines:
        cells = [fmt.format(r[key]) for r in rows.values()]
        if key == "loadBefore":
            cells = [f"{r['loadBefore']:.1f} / {r['loadAfter']:.1f}" for r in rows.values()]
        result.add_row(label, *cells)
    return result


def plot(runs: dict[str, dict[str, Any]], rows: dict[str, dict[str, float]], png: Path) -> None:
    """Wall time and utilisation bars, and the per-scenario engine time distributions."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(rows)
    fig, (left, right, timeline) = plt.subplots(
        1, 3, figsize=(15, 4), gridspec_kw={"width_ratios": [1, 1, 2]}
    )
    bars = left.bar(names, [rows[n]["wallSeconds"] for n in names], color=["#999", "#2a7"])
    for bar, name in zip(bars, names, strict=True):
        left.annotate(
            f"{rows[name]['wallSeconds']:.0f} s\nCPU {rows[name]['cpuUtilisation']:.0%}"
            f"\noverhead {rows[name]['overheadPerScenario'] * 1000:.0f} ms",
            (bar.get_x() + bar.get_width() / 2, bar.get_height()),
            ha="center",
            va="bottom",
            fontsize=8,
        )
    left.set_ylabel("wall time (s)")
    left.set_title("whole campaign")
    left.margins(y=0.3)
    right.boxplot([runs[n]["engine"] for n in names], showfliers=True)
    right.set_xticks(range(1, len(names) + 1), names)
    right.set_ylabel("engine wall time per scenario (s)")
    right.set_title("per scenario")
    default = runs[names[-1]]
    lanes = {pid: i for i, pid in enumerate(sorted({t[2] for t in default["timings"]}))}
    for started, finished, pid in default["timings"]:
        timeline.barh(
            lanes[pid],
            finished - started,
            left=started - default["launched"],
            height=0.6,
            color="#2a7",
            edgecolor="white",
            linewidth=0.3,
        )
    timeline.set_yticks(list(lanes.values()), [f"worker {pid}" for pid in lanes])
    timeline.set_xlim(left=0)
    timeline.set_xlabel("seconds since simtest run started")
    timeline.set_title(f"{names[-1]}: scenarios per worker process")
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--manifest", type=Path, default=REPO / "scenarios/seed-experiment-campaign.yaml"
    )
    parser.add_argument("--warm-up", type=Path, default=REPO / "scenarios/smoke-campaign.yaml")
    parser.add_argument("--png", type=Path, default=REPO / "docs/local-run.png")
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--keep", type=Path, default=None, help="Keep the output folders here.")
    options = parser.parse_args()
    console = Console()
    cores = len(os.sched_getaffinity(0))
    with tempfile.TemporaryDirectory() as scratch:
        base = options.keep or Path(scratch)
        base.mkdir(parents=True, exist_ok=True)
        console.print(f"warm-up: {options.warm_up.name}")
        run_once(options.warm_up, base / "warm-up", None)
        runs: dict[str, dict[str, Any]] = {}
        for name, parallel in (("--parallel 1", 1), ("default", None)):
            console.print(f"running {options.manifest.name} with {name} ...")
            runs[name] = run_once(
                options.manifest, base / name.strip("-").replace(" ", ""), parallel
            )
    baseline = runs["--parallel 1"]["wall"]
    rows = {name: figures(run, cores, baseline) for name, run in runs.items()}
    console.print(table(rows, cores))
    same = runs["--parallel 1"]["verdicts"] == runs["default"]["verdicts"]
    counts: dict[str, int] = {}
    for verdict in runs["default"]["verdicts"].values():
        counts[verdict] = counts.get(verdict, 0) + 1
    console.print(f"verdicts {dict(sorted(counts.items()))}; identical in both runs: {same}")
    plot(runs, rows, options.png)
    console.print(f"plot written to {options.png}")
    if options.json is not None:
        options.json.write_text(
            json.dumps({"cores": cores, "figures": rows, "identicalVerdicts": same}, indent=2)
            + "\n"
        )


if __name__ == "__main__":
    main()
