"""Benchmark of the SUT interface: the 20-vehicle simulator bench (bench/simulator.py's
scenario) with the ego driven by the in-process driver model vs by the reference SUT as a
separate process on loopback (OSI SUT protocol v1, lockstep) vs by the Go example SUT
(deploy/sut-go, built by its script).

Each run is a fresh process (libsumo is one simulation per process), in ``--repeat`` rounds
alternating the order of the variants. Per variant: the median run's stepping time, steps per
second, real-time factor of the stepping loop; for the external SUT also the round trip per step
(p50/p99, measured by the simulator from
sending the encoded SensorView to receiving the answer: transfer plus the SUT's own work) and
whether the verdicts agree. Prints a table and writes JSON::

    python bench/sut.py [--vehicles 20] [--seconds 60] [--repeat 3] [--json FILE]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

_CHILD = r"""
import json, sys, time
from pathlib import Path
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from simtest_operator.drivermodel import ExternalSut, Launch
from simtest_operator.sut.launching import reference_command
path, nets, variant, go_sut = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3], sys.argv[4]
external = None
if variant != "in-process":
    command = reference_command() if variant == "external" else (go_sut,)
    external = ExternalSut(launch=Launch.LOCAL, command=command, step_deadline=1.0)
sut = SutConfig(takeover=Takeover.AFTER_INIT, external=external)
request = scenario_execution.RunRequest(scenario=path, nets_dir=nets, sut=sut, record=False,
                               backend=BackendChoice.SUMO)
t1 = time.perf_counter()
report = scenario_execution.run_scenario(request)
wall = time.perf_counter() - t1
o = report.outcome
print(json.dumps({"variant": variant, "verdict": o.verdict.value, "reason": o.reason,
                  "simulated": o.simulated_seconds, "wall": wall, "startup": report.startup_seconds,
                  "metrics": dict(o.metrics)}))
"""


def _scenario_text(vehicles: int, seconds: float) -> str:
    spec = importlib.util.spec_from_file_location(
        "bench_simulator", Path(__file__).with_name("simulator.py")
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    text: str = module.scenario_text(vehicles, seconds)
    return text


def run_child(path: Path, nets: Path, variant: str, go_sut: str) -> dict[str, object]:
    result = subprocess.run(
        [sys.executable, "-c", _CHILD, str(path), str(nets), variant, go_sut],
        check=True,
        capture_output=True,
        text=True,
    )
    return dict(json.loads(result.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vehicles", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="simtest-sut-bench-"))
    scenario = work / "bench.xosc"
    scenario.write_text(_scenario_text(args.vehicles, args.seconds), encoding="utf-8")
    nets = work / "nets"
    built = subprocess.run(
        ["bash", str(Path(__file__).resolve().parents[1] / "deploy" / "sut-go" / "build.sh")],
        check=True,
        capture_output=True,
        text=True,
    )
    go_sut = built.stdout.strip().splitlines()[-1]
    run_child(scenario, nets, "in-process", go_sut)  # warm the network cache
    variants = ["in-process", "external", "external-go"]
    runs: dict[str, list[dict[str, object]]] = {variant: [] for variant in variants}
    for round_ in range(args.repeat):
        for variant in variants if round_ % 2 == 0 else variants[::-1]:
            runs[variant].append(run_child(scenario, nets, variant, go_sut))
    step = 0.05
    table: dict[str, object] = {"load_average_1min": round(os.getloadavg()[0], 2)}
    for variant, rows in runs.items():
        stepping = [float(r["wall"]) - float(r["startup"]) for r in rows]  # type: ignore[arg-type]
        median = statistics.median(stepping)
        simulated = float(rows[0]["simulated"])  # type: ignore[arg-type]
        metrics = [dict(r["metrics"]) for r in rows]  # type: ignore[call-overload]
        entry = {
            "verdicts": sorted({str(r["verdict"]) for r in rows}),
            "stepping_seconds": round(median, 3),
            "steps_per_second": round(simulated / step / median, 1),
            "real_time_factor": round(simulated / median, 1),
        }
        if variant != "in-process":
            entry["round_trip_p50_ms"] = round(
                statistics.median(float(m["sutRoundTripP50Ms"]) for m in metrics), 4
            )
            entry["round_trip_p99_ms"] = round(
                statistics.median(float(m["sutRoundTripP99Ms"]) for m in metrics), 4
            )
        table[variant] = entry
    print(f"{args.vehicles} vehicles, {args.seconds:g} s simulated, {args.repeat} rounds")
    for label, figures in table.items():
        print(label.ljust(17), json.dumps(figures))
    if args.json:
        args.json.write_text(json.dumps(table, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
