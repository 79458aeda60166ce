"""Benchmark of the simulator stand-in: real-time factor, recording overhead, startup costs.

Generates a 20-vehicle OpenSCENARIO scenario on ``e6mini.xodr`` of the development corpus (three
lanes per direction on a long curved road; every vehicle gets a speed profile, a third of them
change lanes; 60 s simulated) and runs it side by side,
each variant in a fresh process because libsumo is one simulation per process, in ``--repeat``
rounds over the variants:

* ``sumo``: the default -- SUMO hosts the network; no SUMO traffic, so actors are not mirrored;
* ``sumo+mirror``: every actor pushed into SUMO every step (``BackendConfig.mirror=True``);
* ``sumo+record``: the default plus the omega-prime recording at 10 Hz;
* ``memory``: the pure-Python backend (no SUMO at all), for reference.

The table shows each variant's median run (by stepping time) and its best stepping RTF. Recording
overhead is measured robustly on a shared machine: ``sumo`` and ``sumo+record`` run back to back
in every round, in alternating order, and each pair gives one overhead (stepping time with / without
recording - 1); the median over the pairs and its spread are reported, next to the whole-run
overhead (startup included) and the recorder's own cost measured inside the recording runs
(``Recorder.write`` and ``close`` timed per frame, and as a share of the paired plain run's stepping
time). The 1-minute load average is sampled every round. Startup is measured separately: importing
the engine, loading scenario + map, and the SUMO network on a cache miss (netconvert) vs a hit.
Prints a table and writes JSON::

    python bench/simulator.py [--vehicles 20] [--seconds 60] [--repeat 7] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

CORPUS = Path(__file__).resolve().parents[2] / "shared" / "scenarios-dev" / "esmini" / "resources"
CATALOGS = CORPUS / "xosc" / "Catalogs" / "Vehicles"


def scenario_text(vehicles: int, seconds: float) -> str:
    """A scenario with ``vehicles`` cars: speed changes for all, lane changes for every third."""
    entities, inits, events = [], [], []
    for k in range(vehicles):
        name = "Ego" if k == 0 else f"Car{k}"
        lane = -1 - (k % 3)
        s = 50.0 + (k // 3) * 35.0
        speed = 20.0 + (k % 5) * 2.0
        entities.append(
            f'<ScenarioObject name="{name}"><CatalogReference catalogName="VehicleCatalog" '
            f'entryName="car_white"/></ScenarioObject>'
        )
        inits.append(
            f'<Private entityRef="{name}"><PrivateAction><TeleportAction><Position>'
            f'<LanePosition roadId="0" laneId="{lane}" offset="0" s="{s}"/></Position>'
            f"</TeleportAction></PrivateAction><PrivateAction><LongitudinalAction><SpeedAction>"
            f'<SpeedActionDynamics dynamicsShape="step" dynamicsDimension="time" value="0"/>'
            f'<SpeedActionTarget><AbsoluteTargetSpeed value="{speed}"/></SpeedActionTarget>'
            f"</SpeedAction></LongitudinalAction></PrivateAction></Private>"
        )
        body = (
            '<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="sinusoidal" '
            f'dynamicsDimension="time" value="4"/><SpeedActionTarget><AbsoluteTargetSpeed '
            f'value="{speed + 5}"/></SpeedActionTarget></SpeedAction></LongitudinalAction>'
        )
        if k % 3 == 1:
            body = (
                "<LateralAction><LaneChangeAction>"
                '<LaneChangeActionDynamics dynamicsShape="sinusoidal" '
                'dynamicsDimension="time" value="3"/><LaneChangeTarget><RelativeTargetLane '
                f'entityRef="{name}" value="1"/></LaneChangeTarget></LaneChangeAction>'
                "</LateralAction>"
            )
        events.append(
            f'<ManeuverGroup maximumExecutionCount="1" name="G{k}">'
            '<Actors selectTriggeringEntities="false">'
            f'<EntityRef entityRef="{name}"/></Actors><Maneuver name="M{k}"><Event name="E{k}" '
            f'priority="overwrite"><Action name="A{k}"><PrivateAction>{body}</PrivateAction>'
            "</Action>"
            f'<StartTrigger><ConditionGroup><Condition name="C{k}" delay="0" '
            'conditionEdge="rising">'
            f'<ByValueCondition><SimulationTimeCondition value="{5 + k % 7}" rule="greaterThan"/>'
            f"</ByValueCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>"
            f"</ManeuverGroup>"
        )
    return (
        '<?xml version="1.0" encoding="UTF-8"?><OpenSCENARIO><FileHeader revMajor="1" revMinor="1" '
        'date="2026-01-01T00:00:00" description="bench" author="bench"/><ParameterDeclarations/>'
        f'<CatalogLocations><VehicleCatalog><Directory path="{CATALOGS}"/></VehicleCatalog>'
        f'</CatalogLocations><RoadNetwork><LogicFile filepath="{CORPUS / "xodr" / "e6mini.xodr"}"/>'
        f"</RoadNetwork><Entities>{''.join(entities)}</Entities><Storyboard><Init><Actions>"
        f'{"".join(inits)}</Actions></Init><Story name="S"><Act name="A">{"".join(events)}'
        '<StartTrigger><ConditionGroup><Condition name="go" delay="0" conditionEdge="none">'
        '<ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/>'
        "</ByValueCondition></Condition></ConditionGroup></StartTrigger></Act></Story>"
        '<StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="rising">'
        f'<ByValueCondition><SimulationTimeCondition value="{seconds}" rule="greaterThan"/>'
        "</ByValueCondition></Condition></ConditionGroup></StopTrigger></Storyboard></OpenSCENARIO>"
    )


_CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
from pathlib import Path
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from simtest_operator.sim import session
t_import = time.perf_counter() - t0
path, nets, out, variant = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3], sys.argv[4]
if variant == "sumo+mirror":
    original = session.BackendConfig
    def mirrored(**kw):
        return original(**kw, mirror=True)
    session.BackendConfig = mirrored
spent = {"seconds": 0.0, "frames": 0}
if variant == "sumo+record":
    # The recorder's own cost, timed around each call (the wrapper adds well under 1 us per call).
    from simtest_operator.recording import writing
    plain_write, plain_close = writing.Recorder.write, writing.Recorder.close
    def timed_write(self, snapshot, *, force=False):
        begun = time.perf_counter()
        done = plain_write(self, snapshot, force=force)
        spent["seconds"] += time.perf_counter() - begun
        return done
    def timed_close(self):
        begun = time.perf_counter()
        plain_close(self)
        spent["seconds"] += time.perf_counter() - begun
        spent["frames"] = self.frames
    writing.Recorder.write, writing.Recorder.close = timed_write, timed_close
request = scenario_execution.RunRequest(
    scenario=path, nets_dir=nets, sut=SutConfig(takeover=Takeover.NEVER),
    output_dir=Path(out) if variant == "sumo+record" else None,
    record=variant == "sumo+record",
    backend=BackendChoice.MEMORY if variant == "memory" else BackendChoice.SUMO,
)
t1 = time.perf_counter()
report = scenario_execution.run_scenario(request)
wall = time.perf_counter() - t1
o = report.outcome
print(json.dumps({"variant": variant, "verdict": o.verdict.value, "reason": o.reason,
                  "simulated": o.simulated_seconds, "wall": wall, "startup": report.startup_seconds,
                  "net_cache_hit": report.net_from_cache, "import": t_import,
                  "record_seconds": spent["seconds"], "record_frames": spent["frames"]}))
"""


def run_child(path: Path, nets: Path, out: Path, variant: str) -> dict[str, object]:
    result = subprocess.run(
        [sys.executable, "-c", _CHILD, str(path), str(nets), str(out), variant],
        check=True,
        capture_output=True,
        text=True,
    )
    return dict(json.loads(result.stdout.strip().splitlines()[-1]))


def _stepping(row: dict[str, object]) -> float:
    """Wall seconds spent stepping (the run without loading and starting)."""
    return float(str(row["wall"])) - float(str(row["startup"]))


def _spread(values: list[float]) -> dict[str, float]:
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def _median_run(runs: list[dict[str, object]]) -> dict[str, object]:
    """The run with the median stepping time (the lower middle one for an even count)."""
    ordered = sorted(runs, key=_stepping)
    return dict(ordered[(len(ordered) - 1) // 2])


def _rounds(
    path: Path, nets: Path, folder: Path, repeat: int
) -> tuple[dict[str, list[dict[str, object]]], list[float]]:
    """``repeat`` rounds over the variants; plain and recording runs back to back, alternating
    which comes first, so each pair sees the same background load."""
    variants = ("sumo", "sumo+record", "sumo+mirror", "memory")
    runs: dict[str, list[dict[str, object]]] = {variant: [] for variant in variants}
    load: list[float] = []
    for k in range(repeat):
        pair = ("sumo", "sumo+record") if k % 2 == 0 else ("sumo+record", "sumo")
        for variant in (*pair, "sumo+mirror", "memory"):
            runs[variant].append(run_child(path, nets, folder / f"{variant}{k}", variant))
        load.append(os.getloadavg()[0])
    return runs, load


def _recording_figures(runs: dict[str, list[dict[str, object]]]) -> dict[str, list[float]]:
    """Per pair: stepping and whole-run overhead, the recorder's cost per frame (us) and its
    share of the paired plain run's stepping time."""
    plain, recorded = runs["sumo"], runs["sumo+record"]
    pairs = list(zip(plain, recorded, strict=True))
    return {
        "stepping_overhead": [_stepping(r) / _stepping(p) - 1.0 for p, r in pairs],
        "whole_run_overhead": [
            float(str(r["wall"])) / float(str(p["wall"])) - 1.0 for p, r in pairs
        ],
        "recorder_us_per_frame": [
            float(str(r["record_seconds"])) / int(str(r["record_frames"])) * 1e6 for r in recorded
        ],
        "recorder_share_of_stepping": [
            float(str(r["record_seconds"])) / _stepping(p) for p, r in pairs
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n", 1)[0])
    parser.add_argument("--vehicles", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=7, help="rounds over the variants")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = folder / "bench.xosc"
        path.write_text(scenario_text(args.vehicles, args.seconds), encoding="utf-8")
        nets = folder / "nets"
        cold = run_child(path, nets, folder / "cold", "sumo")  # network cache miss
        runs, load = _rounds(path, nets, folder, args.repeat)
    rows = [_median_run(variant_runs) for variant_runs in runs.values()]
    print(
        f"{'variant':14} {'sim s':>6} {'wall s':>7} {'startup s':>9} {'RTF':>6} "
        f"{'RTF steps':>9} {'best':>6}   (median run of {args.repeat})"
    )
    for row in rows:
        simulated, wall = float(str(row["simulated"])), float(str(row["wall"]))
        startup = float(str(row["startup"]))
        row["rtf"] = simulated / wall
        row["rtf_stepping"] = simulated / (wall - startup)
        row["rtf_stepping_best"] = simulated / min(map(_stepping, runs[str(row["variant"])]))
        print(
            f"{row['variant']:14} {simulated:6.1f} {wall:7.2f} {startup:9.2f} "
            f"{row['rtf']:6.1f} {row['rtf_stepping']:9.1f} {row['rtf_stepping_best']:6.1f}"
        )
    figures = _recording_figures(runs)
    spreads = {name: _spread(values) for name, values in figures.items()}
    overhead, whole = spreads["stepping_overhead"], spreads["whole_run_overhead"]
    cost, share = spreads["recorder_us_per_frame"], spreads["recorder_share_of_stepping"]
    frames = runs["sumo+record"][0]["record_frames"]
    print(
        f"recording overhead over {args.repeat} interleaved pairs: stepping median "
        f"{overhead['median'] * 100:.1f} % (min {overhead['min'] * 100:.1f}, max "
        f"{overhead['max'] * 100:.1f}), whole run median {whole['median'] * 100:.1f} % (min "
        f"{whole['min'] * 100:.1f}, max {whole['max'] * 100:.1f})"
    )
    print(
        f"recorder itself: median {cost['median']:.1f} us per frame of {args.vehicles} objects "
        f"(min {cost['min']:.1f}, max {cost['max']:.1f}; {frames} frames), "
        f"{share['median'] * 100:.1f} % of the plain run's stepping time"
    )
    base = rows[0]
    print(
        f"startup: imports {base['import']:.2f} s; scenario, map and SUMO start with the network "
        f"cache missed {cold['startup']:.2f} s, hit {base['startup']:.2f} s"
    )
    print(
        f"load average (1 min): {load_start[0]:.2f} at start, {min(load):.2f}-{max(load):.2f} "
        "during the rounds"
    )
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        summary = {
            "vehicles": args.vehicles,
            "seconds": args.seconds,
            "repeat": args.repeat,
            "rows": rows,
            "recording_overhead": overhead["median"],
            "recording": {
                "frames": frames,
                **{name: {**spreads[name], "pairs": values} for name, values in figures.items()},
            },
            "startup_miss": cold["startup"],
            "startup_hit": base["startup"],
            "import": base["import"],
            "load_average": {"start": list(load_start), "rounds": load},
        }
        args.json.write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
