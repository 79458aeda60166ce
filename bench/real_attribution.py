"""Where a real-node Table 1 run's time went beyond the lower bound, from its pod timelines.

Reads a ``bench/results/real_table1-*.json`` written by ``bench/real_table1.py`` and splits the
slot-time of each run, ``makespan x s``, into the scenarios' own run time ``W`` and the rest,
per pod phase (seconds since the campaign was created, as the bench's pod watch saw them):

* pod start: bound to the node -> container running (sandbox, CNI, runc; kubelet);
* runner start-up: container running -> the first scenario's start (its ``finished`` line
  minus its run time): Python start, imports, run spec, scenario and network, first step;
* between runs: inside a warm pod, from one scenario's ``finished`` line to the next one's
  start (fork, reset check, next scenario and network, result write);
* exit: the last ``finished`` line -> the container seen terminated (the runner's result
  write and exit, then the kubelet noticing it on its next PLEG relist, 0-1 s);
* slot idle: no pod on the slot. Split into the campaign's start (creation to each slot's
  first binding), the end (each slot's last pod's end to the campaign's Complete; queue packing
  and the last scenarios' lengths) and the refills in between (a pod's end to the next binding).

Each phase is given as seconds of makespan (its slot-seconds over ``s``), so the rows add up to
``makespan - W / s``; with ``W / s`` the bound (it is, for these campaigns) that is the gap to the
bound. Prints a markdown table::

    python bench/real_attribution.py bench/results/real_table1-session9.json
    python bench/real_attribution.py --per-pod bench/results/real_table1-session9.json
"""

from __future__ import annotations

import argparse
import itertools
import json
import statistics
from pathlib import Path
from typing import Any

PHASES = (
    "pod start",
    "runner start-up",
    "between runs",
    "exit",
    "idle: start",
    "idle: refill",
    "idle: end",
)


def attribute(result: dict[str, Any]) -> dict[str, float]:
    """Seconds of makespan per phase (see the module docstring) for one run of the bench."""
    slots = int(result["config"]["slots"])
    runs: dict[str, float] = result["durations"]
    makespan = float(result["makespan"])
    spent = dict.fromkeys(PHASES, 0.0)
    pods = [m for m in result["marks"].values() if "scheduled" in m and "terminated" in m]
    for marks in pods:
        for phase, seconds in pod_phases(marks, runs).items():
            spent[phase] += seconds
    binds = sorted(m["scheduled"] for m in pods)
    ends = sorted(m["terminated"] for m in pods)
    busy = sum(m["terminated"] - m["scheduled"] for m in pods)
    idle = makespan * slots - busy
    spent["idle: start"] = sum(binds[:slots])
    spent["idle: end"] = sum(makespan - end for end in ends[-slots:])
    spent["idle: refill"] = idle - spent["idle: start"] - spent["idle: end"]
    return {phase: seconds / slots for phase, seconds in spent.items()}


def pod_phases(marks: dict[str, float], runs: dict[str, float]) -> dict[str, float]:
    """One pod's seconds in pod start, runner start-up, between runs and exit."""
    finished = sorted(
        (at, key.removeprefix("finished ")) for key, at in marks.items()
        if key.startswith("finished ")
    )  # fmt: skip
    phases = {"pod start": marks["running"] - marks["scheduled"]}
    if not finished:  # no log lines seen: the whole pod counts as start-up
        return phases | {"runner start-up": marks["terminated"] - marks["running"]}
    first_at, first = finished[0]
    phases["runner start-up"] = first_at - runs.get(first, 0.0) - marks["running"]
    phases["between runs"] = sum(
        at - runs.get(scenario, 0.0) - previous
        for (previous, _), (at, scenario) in itertools.pairwise(finished)
    )
    phases["exit"] = marks["terminated"] - finished[-1][0]
    return phases


def per_pod(results: list[dict[str, Any]]) -> str:
    """One row per run: the median pod's start, runner start-up and exit (seconds)."""
    head = ["config", "pods", "pod start", "runner start-up", "exit"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for result in results:
        pods = [
            pod_phases(m, result["durations"])
            for m in result["marks"].values()
            if "scheduled" in m and "terminated" in m
        ]
        cells = [label(result["config"]), str(len(pods))]
        for phase in head[2:]:
            values = [p[phase] for p in pods if phase in p]
            cells.append(f"{statistics.median(values):.2f}" if values else "-")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def label(config: dict[str, Any]) -> str:
    mode = "barrier" if config["barrier"] else "window"
    return f"s{config['slots']} {mode} {'Reuse' if config['reuse'] else 'PerScenario'}"


def markdown(results: list[dict[str, Any]]) -> str:
    """One row per run: makespan, W / s, the gap and its phases (seconds of makespan)."""
    head = ["config", "pods", "makespan", "W / s", "gap", *PHASES]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for result in results:
        slots = int(result["config"]["slots"])
        work = float(result["work"]) / slots
        phases = attribute(result)
        pods = sum(1 for m in result["marks"].values() if "scheduled" in m)
        cells = [
            label(result["config"]),
            str(pods),
            f"{result['makespan']:.1f}",
            f"{work:.1f}",
            f"{result['makespan'] - work:.1f}",
            *(f"{phases[p]:.1f}" for p in PHASES),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n", 1)[0])
    parser.add_argument("results", type=Path, nargs="+")
    parser.add_argument(
        "--per-pod", action="store_true", help="the median pod's phases instead (seconds per pod)"
    )
    args = parser.parse_args()
    found = [r for path in args.results for r in json.loads(path.read_text())["results"]]
    print((per_pod if args.per_pod else markdown)(found), end="")


if __name__ == "__main__":
    main()
