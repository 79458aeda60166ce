"""Benchmark of start-up: ``simtest --help``, ``simtest scenario run`` and ``simtest-runner``.

Runs each command as a fresh process, side by side for two source trees in one go: ``before``
(a git worktree of ``--before``, default 7d849da, the commit before the start-up work) and
``after`` (this checkout), both on this interpreter with ``PYTHONPATH=<tree>/src``, in
``--repeat`` interleaved rounds (the order alternates, so both see the same background load).
Every round runs each command three ways:

* plain, as the console script does (``from <module> import main; main()``): wall and CPU time;
* with probes: wrappers installed by an import hook around the start-up steps (libsumo import,
  scenario and map load, network cache lookup, SUMO loading the network, each process's first
  simulation step, each forked scenario), timestamped on the system-wide monotonic clock;
* with ``-X importtime``: imports before the first simulation step, summed by top-level package.

Commands: ``simtest --help``; ``simtest scenario run`` of a 10-second smoke scenario (recording
on); the runner entrypoint with one scenario (``PerScenario``, what a pod per scenario runs); and
the runner with the six smoke scenarios (``Reuse``, a warm pod): its per-scenario start-up from
fork to first step and how many processes import libsumo. The SUMO network cache is warmed
first; one more runner variant starts every run with an empty cache, as a pod without a shared
cache does (netconvert converts the map). Prints rich tables of medians and writes JSON::

    python bench/startup.py [--repeat 7] [--before 7d849da] [--json bench/results/startup.json]
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import hashlib
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

REPO = Path(__file__).resolve().parents[1]
SMOKE = REPO / "scenarios" / "smoke"
SCENARIO = SMOKE / "hard-braking_rural_v15_thw2_d4.xosc"

PROBES = r"""
import importlib.abc, json, os, sys, time

_EVENTS = os.environ["SIMTEST_BENCH_EVENTS"]
_stepped = set()


def _mark(event, begin=None):
    with open(_EVENTS, "a", encoding="utf-8") as sink:
        sink.write(json.dumps({"event": event, "pid": os.getpid(), "begin": begin,
                               "end": time.monotonic()}) + "\n")


def _timed(owner, name, event, first_only=False):
    original = getattr(owner, name)

    def probe(*args, **kwargs):
        begin = time.monotonic()
        try:
            return original(*args, **kwargs)
        finally:
            if not first_only:
                _mark(event, begin)
            elif os.getpid() not in _stepped:
                _stepped.add(os.getpid())
                sys.stderr.write("import time: -1 | -1 | simtest-bench-first-step\n")
                _mark(event, begin)

    setattr(owner, name, probe)


_PROBES = {
    "simtest_operator.sim.engine": lambda m: (
        _timed(m.Simulation, "step", "first_step", first_only=True),
        _timed(m.Simulation, "start", "simulation_start")),
    "simtest_operator.sim.sumo": lambda m: (
        _timed(m, "_load_libsumo", "libsumo"), _timed(m.SumoBackend, "start", "backend_start")),
    "simtest_operator.sim.netcache": lambda m: _timed(m, "ensure_net", "ensure_net"),
    "simtest_operator.sim.session": lambda m: _timed(m, "open_simulation", "open_simulation"),
    "simtest_operator.runner.entrypoint": lambda m: _timed(m, "run_forked", "forked"),
    "simtest_operator.provenance": lambda m: _timed(m, "versions", "provenance"),
}


class _Probing(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name not in _PROBES:
            return None
        for finder in sys.meta_path:
            spec = None if finder is self else finder.find_spec(name, path, target)
            if spec is not None:
                break
        else:
            return None
        loaded = spec.loader.exec_module

        def exec_module(module):
            loaded(module)
            _PROBES[name](module)

        spec.loader.exec_module = exec_module
        return spec


sys.meta_path.insert(0, _Probing())
_mark("main")
"""

ENTRY = (
    "import sys; from {module} import {function} as main; sys.argv[0] = {name!r}; sys.exit(main())"
)
CLI = "simtest"
RUNNER = "simtest-runner"
IMPORT_LINE = re.compile(r"import time:\s+(-?\d+) \|\s+(-?\d+) \|(\s*)(\S+)")


@dataclasses.dataclass(frozen=True, slots=True)
class Command:
    """One benchmarked command line."""

    name: str
    entry: str
    """The console script, run as its ``module:function`` in the tree's pyproject.toml says."""
    args: tuple[str, ...]
    spec: str = ""
    """The runner's run spec (``SIMTEST_RUN_SPEC``), empty for the CLI."""
    cold: bool = False
    """Every run with an empty network cache (a fresh pod without a shared cache)."""


def run_spec(isolation: str, scenarios: list[Path], artifacts: Path) -> str:
    """A run spec as the operator renders it, over local scenario files."""
    return json.dumps(
        {
            "version": 1,
            "campaign": "bench",
            "environment": "bench-e0",
            "attempt": 1,
            "scenarios": [
                {
                    "id": p.name,
                    "source": p.as_uri(),
                    "sha256": hashlib.sha256(p.read_bytes()).hexdigest(),
                    "overrides": {},
                }
                for p in scenarios
            ],
            "isolation": isolation,
            "timeoutSeconds": 60,
            "artifactsDir": str(artifacts),
            "artifactsUri": "",
            "evaluation": {},
            "sut": {},
            "simulator": {},
        }
    )


def commands(work: Path) -> list[Command]:
    """The benchmarked command lines, writing below ``work``."""
    smoke = sorted(SMOKE.glob("*.xosc"))
    log = str(work / "termination-log")
    return [
        Command("simtest --help", CLI, ("--help",)),
        Command(
            "simtest scenario run",
            CLI,
            ("scenario", "run", str(SCENARIO), "--out", str(work / "scenario")),
        ),
        Command(
            "simtest-runner (1 scenario)",
            RUNNER,
            ("--termination-log", log),
            run_spec("PerScenario", [SCENARIO], work / "pod"),
        ),
        Command(
            "simtest-runner (1 scenario, cold network cache)",
            RUNNER,
            ("--termination-log", log),
            run_spec("PerScenario", [SCENARIO], work / "pod"),
            cold=True,
        ),
        Command(
            "simtest-runner (6, Reuse)",
            RUNNER,
            ("--termination-log", log),
            run_spec("Reuse", smoke, work / "warm-pod"),
        ),
    ]


def execute(
    command: Command, tree: Path, cache: Path, *, probes: Path | None, importtime: bool
) -> dict[str, Any]:
    """Run ``command`` once on the sources in ``tree``: wall/CPU seconds, events, imports."""
    module, function = console_scripts(tree)[command.entry].split(":")
    code = ENTRY.format(module=module, function=function, name=command.entry)
    if command.cold:
        cache = Path(tempfile.mkdtemp(dir=cache.parent, prefix="cold-cache-"))
    env = {**os.environ, "PYTHONPATH": str(tree / "src"), "SIMTEST_CACHE_DIR": str(cache)}
    env["SIMTEST_RUN_SPEC"] = command.spec
    if probes is not None:
        probes.unlink(missing_ok=True)
        env["SIMTEST_BENCH_EVENTS"] = str(probes)
        code = PROBES + code
    argv = [sys.executable, *(["-X", "importtime"] if importtime else []), "-c", code]
    started = time.monotonic()
    process = subprocess.Popen(
        [*argv, *command.args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE if importtime else subprocess.DEVNULL,
        env=env,
        text=True,
    )
    stderr = process.stderr.read() if process.stderr is not None else ""
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.monotonic() - started
    if os.waitstatus_to_exitcode(status) not in (0, 1):  # 1: the scenario failed, still ran
        raise RuntimeError(f"{command.name} on {tree} exited with status {status}")
    result: dict[str, Any] = {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime}
    if probes is not None:
        lines = probes.read_text(encoding="utf-8").splitlines()
        events = [json.loads(line) for line in lines]
        result["events"] = [{**e, "begin": _rel(e["begin"], started), "end": e["end"] - started}
                            for e in events]  # fmt: skip
    if importtime:
        result["imports"] = imports_by_package(stderr)
    return result


def console_scripts(tree: Path) -> dict[str, str]:
    """The ``[project.scripts]`` of the tree: each tree runs its own entry points."""
    with (tree / "pyproject.toml").open("rb") as file:
        scripts: dict[str, str] = tomllib.load(file)["project"]["scripts"]
    return scripts


def _rel(value: float | None, started: float) -> float | None:
    return None if value is None else value - started


def imports_by_package(stderr: str) -> dict[str, float]:
    """Self import time (s) by top-level package until the first simulation step."""
    totals: dict[str, float] = collections.defaultdict(float)
    for line in stderr.splitlines():
        match = IMPORT_LINE.match(line)
        if match is None:
            continue
        if match.group(4) == "simtest-bench-first-step":
            break
        totals[match.group(4).split(".")[0]] += int(match.group(1)) / 1e6
    small = sum(seconds for seconds in totals.values() if seconds < 1e-3)
    kept = {package: round(s, 6) for package, s in totals.items() if s >= 1e-3}
    return kept | {"(below 1 ms each)": round(small, 6)}


def phases(run: dict[str, Any]) -> dict[str, float]:
    """Start-up phases (s) of one probed run of a single process."""
    events: list[dict[str, Any]] = run["events"]
    pid = events[0]["pid"]

    def spent(event: str) -> float:
        mine = [e for e in events if e["event"] == event and e["pid"] == pid]
        return float(sum(e["end"] - e["begin"] for e in mine))

    result = {"process start": float(events[0]["end"])}
    first = [e for e in events if e["event"] == "first_step"]
    if not first:
        return result
    network = spent("ensure_net") + spent("backend_start") - spent("libsumo")
    result |= {
        "reproducibility record": spent("provenance"),
        "libsumo import": spent("libsumo"),
        "scenario + map load": spent("open_simulation") - spent("ensure_net"),
        "network load": network,
        "first step": first[0]["end"] - first[0]["begin"],
        "start -> first step": first[0]["end"],
    }
    return result


def warm_pod(run: dict[str, Any]) -> dict[str, float]:
    """Per-scenario start-up of a Reuse pod: fork -> the forked worker's first step."""
    events: list[dict[str, Any]] = run["events"]
    forks = sorted(e["begin"] for e in events if e["event"] == "forked")
    firsts = sorted(e["end"] for e in events if e["event"] == "first_step")
    libsumo = [e for e in events if e["event"] == "libsumo" and e["end"] - e["begin"] > 0.01]
    per_scenario = [step - fork for fork, step in zip(forks, firsts, strict=True)]
    return {
        "scenarios": len(forks),
        "fork -> first step (median)": statistics.median(per_scenario),
        "processes importing libsumo": len({e["pid"] for e in libsumo}),
        "libsumo import (sum)": sum(e["end"] - e["begin"] for e in libsumo),
        "start -> first step": firsts[0],
    }


def baseline(repeat: int) -> float:
    """Median wall time of ``python -c pass``: the interpreter's own start."""
    walls = []
    for _ in range(repeat):
        started = time.monotonic()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        walls.append(time.monotonic() - started)
    return statistics.median(walls)


def worktree(rev: str) -> Path:
    """A checkout of ``rev`` next to the temporary files (reused when it is there)."""
    path = Path(tempfile.gettempdir()) / f"startup-{rev}"
    if not (path / "src").is_dir():
        subprocess.run(
            ["git", "-C", str(REPO), "worktree", "add", "--detach", str(path), rev], check=True
        )
    return path


def rounds(
    trees: dict[str, Path], work: Path, repeat: int
) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """``repeat`` rounds of every command, plain, probed and import-timed, per tree."""
    cache = work / "cache"
    samples: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for command in commands(work):
        for tree in trees.values():  # warm the network cache and the bytecode
            execute(command, tree, cache, probes=None, importtime=False)
        per_tree: dict[str, list[dict[str, Any]]] = {label: [] for label in trees}
        for k in range(repeat):
            for label in trees if k % 2 == 0 else reversed(trees):
                tree = trees[label]
                plain = execute(command, tree, cache, probes=None, importtime=False)
                probed = execute(command, tree, cache, probes=work / "events", importtime=False)
                timed = execute(command, tree, cache, probes=work / "events", importtime=True)
                per_tree[label].append(
                    {"plain": plain, "probed": probed, "imports": timed["imports"]}
                )
        samples[command.name] = per_tree
    return samples


def summary(runs: list[dict[str, Any]], reuse: bool) -> dict[str, float]:
    """Median figures of one command on one tree."""
    rows: dict[str, list[float]] = collections.defaultdict(list)
    for run in runs:
        found = warm_pod(run["probed"]) if reuse else phases(run["probed"])
        for key, value in found.items():
            rows[key].append(value)
        rows["imports before first step"].append(sum(run["imports"].values()))
        for package, seconds in run["imports"].items():
            rows[f"  {package}"].append(seconds)
        rows["wall (plain run)"].append(run["plain"]["wall"])
        rows["CPU (plain run)"].append(run["plain"]["cpu"])
    return {key: statistics.median(values + [0.0] * (len(runs) - len(values)))
            for key, values in rows.items()}  # fmt: skip


def table(name: str, figures: dict[str, dict[str, float]], labels: list[str]) -> Table:
    """One command's figures side by side, with the ratio after / before."""
    out = Table(title=name)
    out.add_column("median")
    for label in labels:
        out.add_column(label, justify="right")
    out.add_column(f"{labels[1]} / {labels[0]}", justify="right")
    keys = list(dict.fromkeys(k for label in labels for k in figures[label]))
    packages = sorted(
        (k for k in keys if k.startswith("  ")),
        key=lambda k: -max(figures[label].get(k, 0.0) for label in labels),
    )
    top = [k for k in packages if not k.startswith("  (")][:8]
    rest = [k for k in packages if k not in top]
    ordered = [k for k in keys if not k.startswith("  ") and k != "imports before first step"]
    at = ordered.index("wall (plain run)")
    ordered[at:at] = ["imports before first step", *top, "  (other packages)"]
    for key in ordered:
        values = [
            sum(figures[label].get(k, 0.0) for k in rest)
            if key == "  (other packages)"
            else figures[label].get(key, 0.0)
            for label in labels
        ]
        counts = key in ("scenarios", "processes importing libsumo")
        cells = [f"{v:.0f}" if counts else f"{v * 1000:.0f} ms" for v in values]
        ratio = f"{values[1] / values[0]:.2f}" if values[0] > 0 else "-"
        out.add_row(key, *cells, ratio)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n", 1)[0])
    parser.add_argument("--repeat", type=int, default=7, help="interleaved rounds")
    parser.add_argument("--before", default="7d849da", help="git revision of the baseline")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    trees = {"before": worktree(args.before), "after": REPO}
    load = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        samples = rounds(trees, Path(tmp), args.repeat)
    python = baseline(args.repeat)
    figures = {
        name: {label: summary(runs, "Reuse" in name) for label, runs in per_tree.items()}
        for name, per_tree in samples.items()
    }
    console = Console()
    for name, per_tree in figures.items():
        console.print(table(name, per_tree, list(trees)))
    console.print(
        f"python -c pass: {python * 1000:.0f} ms; medians of {args.repeat} rounds; load average "
        f"(1 min) {load[0]:.2f} at start, {os.getloadavg()[0]:.2f} at the end"
    )
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        document = {
            "repeat": args.repeat,
            "before": args.before,
            "python_c_pass": python,
            "load_average": {"start": list(load), "end": list(os.getloadavg())},
            "medians": figures,
            "samples": samples,
        }
        args.json.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
