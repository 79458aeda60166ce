"""Benchmark of the SUT lifetime: what an external Python SUT costs per scenario when it is
started for every scenario (``lifetime: Scenario``) and when one warm process serves a worker's
scenarios (``lifetime: Worker``), against the in-process driver model, side by side in one run.

The campaign is the smoke campaign's six scenarios copied ``--copies`` times (so a worker runs
many), run by ``simtest run`` as a user runs it (a fresh process per campaign, ``-j`` workers),
in ``--repeat`` rounds alternating the order of the variants. The SUT is the reference SUT
(the built-in model behind the OSI protocol) or, with ``--sut example``, the standalone Python
example (deploy/sut-python/sut.py). Per variant: the campaign's wall time (median over rounds),
the overhead per scenario over the in-process model, the median scenario's own wall time, and
whether every verdict equals the in-process run's. Prints a table and writes JSON::

    python bench/sut_lifetime.py [--copies 5] [--jobs 1] [--repeat 3] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
VARIANTS = ("in-process", "Scenario", "Worker")


def scenarios(work: Path, copies: int) -> Path:
    """The smoke scenarios ``copies`` times over, in one folder (the road files beside them)."""
    folder = work / "scenarios"
    shutil.copytree(REPO / "scenarios" / "smoke", folder)
    shutil.copytree(REPO / "scenarios" / "roads", work / "roads")  # they name ../roads/
    originals = sorted(folder.glob("*.xosc"))
    for copy in range(1, copies):
        for path in originals:
            path.with_name(f"{path.stem}-copy{copy}.xosc").write_text(path.read_text())
    return folder


def campaign(work: Path, folder: Path, variant: str, sut: str) -> Path:
    manifest = yaml.safe_load((REPO / "scenarios" / "external-sut-campaign.yaml").read_text())
    spec = manifest["spec"]
    spec["scenarios"]["sources"] = [{"path": str(folder)}]
    spec["execution"]["batchSize"] = 1000
    external = spec["environment"]["sut"].pop("external")
    if variant != "in-process":
        if sut == "example":
            external["command"] = ["{python}", str(REPO / "deploy/sut-python/sut.py"), "--port",
                                   "{port}"]  # fmt: skip
        external["lifetime"] = variant
        spec["environment"]["sut"]["external"] = external
    path = work / f"{variant}.yaml"
    path.write_text(yaml.safe_dump(manifest))
    return path


def run(manifest: Path, out: Path, jobs: int) -> dict[str, object]:
    shutil.rmtree(out, ignore_errors=True)
    simtest = Path(sys.executable).with_name("simtest")
    started = time.perf_counter()
    subprocess.run(
        [str(simtest), "run", str(manifest), "-o", str(out), "-j", str(jobs), "--plain"],
        check=False,
        capture_output=True,
    )
    wall = time.perf_counter() - started
    results = [json.loads(p.read_text()) for p in out.glob("scenarios/*/result.json")]
    return {
        "wall": wall,
        "verdicts": {r["scenarioId"]: r["verdict"] for r in results},
        "scenario_median": statistics.median(float(r["wallSeconds"]) for r in results),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--copies", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--sut", choices=("reference", "example"), default="reference")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="simtest-sut-lifetime-"))
    folder = scenarios(work, args.copies)
    manifests = {v: campaign(work, folder, v, args.sut) for v in VARIANTS}
    run(manifests["in-process"], work / "warm-up", args.jobs)  # the network cache
    rounds: dict[str, list[dict[str, object]]] = {v: [] for v in VARIANTS}
    for index in range(args.repeat):
        for variant in VARIANTS if index % 2 == 0 else VARIANTS[::-1]:
            rounds[variant].append(run(manifests[variant], work / variant, args.jobs))
    count = args.copies * 6
    base = statistics.median(float(r["wall"]) for r in rounds["in-process"])  # type: ignore[arg-type]
    reference = rounds["in-process"][0]["verdicts"]
    judged = {"Passed", "Failed"}
    if len(reference) != count or not set(reference.values()) <= judged:  # type: ignore[attr-defined, arg-type]
        raise SystemExit(f"the in-process campaign did not judge every scenario: {reference}")
    table: dict[str, object] = {
        "scenarios": count,
        "jobs": args.jobs,
        "rounds": args.repeat,
        "sut": args.sut,
        "load_average_1min": round(os.getloadavg()[0], 2),
    }
    print(f"{count} scenarios, -j {args.jobs}, {args.repeat} rounds, SUT: {args.sut}")
    print(f"{'variant':<12} {'campaign s':>10} {'overhead s/scenario':>20} "
          f"{'scenario p50 s':>15}  verdicts")  # fmt: skip
    for variant, rows in rounds.items():
        wall = statistics.median(float(r["wall"]) for r in rows)  # type: ignore[arg-type]
        same = all(r["verdicts"] == reference for r in rows)
        entry = {
            "campaign_seconds": round(wall, 2),
            "overhead_per_scenario_seconds": round((wall - base) / count * args.jobs, 3),
            "scenario_wall_p50_seconds": round(
                statistics.median(float(r["scenario_median"]) for r in rows),  # type: ignore[arg-type]
                3,
            ),
            "verdicts_equal_in_process": same,
        }
        table[variant] = entry
        verdicts = "same" if same else "DIFFER"
        print(f"{variant:<12} {entry['campaign_seconds']:>10} "
              f"{entry['overhead_per_scenario_seconds']:>20} "
              f"{entry['scenario_wall_p50_seconds']:>15}  {verdicts}")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(table, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
