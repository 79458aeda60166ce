"""Benchmark of ``simtest evaluate``: re-evaluating 200 recordings against re-simulating them.

Side by side, in rounds (so a busy neighbour on the shared machine hits both): each round runs
the 200-scenario suite with ``simtest run --parallel 1`` into a fresh folder (re-simulating), then
``simtest evaluate`` on that folder (re-evaluating the same 200 recordings with the default
criteria set: read, evidence quality, base-scenario decomposition, checks, store). Both are real
processes timed end to end (start-up, imports and the results store included), after a warm-up
run so SUMO's network cache is warm. Also reported:

* per recording, the median time of one scenario's simulation (``wallSeconds`` measured inside
  the worker) against one recording's evaluation (measured in-process here, warm);
* what omega-prime itself would cost for the same job: ``import omega_prime``, and per recording
  ``Recording.from_file`` (validation and map parsing off) -- the reason re-evaluation reads the
  wire format with ``recording.objects`` instead.

Prints a table and writes ``bench/results/evaluate.json`` and ``.md``::

    python bench/evaluate.py                  # 3 rounds
    python bench/evaluate.py --rounds 1 --omega-prime-sample 5
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
SIMTEST = [sys.executable, "-c", "from simtest_operator.cli.main import main; main()"]
MANIFEST = REPO / "scenarios" / "seed-experiment-campaign.yaml"


def timed(args: list[str], log: Path) -> float:
    with log.open("w") as sink:
        started = time.perf_counter()
        done = subprocess.run(args, stdout=sink, stderr=subprocess.STDOUT, check=False)
        wall = time.perf_counter() - started
    if done.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(args[3:])} failed ({done.returncode}), see {log}")
    return wall


def per_recording_evaluation(out: Path) -> list[float]:
    """Warm, in-process: read + quality + decomposition + checks of each recording."""
    from simtest_operator import results
    from simtest_operator.evaluation import reevaluating
    from simtest_operator.runner import reevaluation

    times = []
    with results.open_store(out) as store:
        (record,) = store.campaigns(limit=1)
        for original in store.outcomes(record.run_key):
            path = out / original.outcome.artifacts["recording"]
            started = time.perf_counter()
            reevaluation.evaluate_recording(
                path,
                reevaluating.DEFAULT_CRITERIA,
                simulated_seconds=original.outcome.simulated_seconds,
                original=original,
            )
            times.append(time.perf_counter() - started)
    return times


def omega_prime_cost(out: Path, sample: int) -> dict[str, Any]:
    """``import omega_prime`` in a fresh interpreter, and ``Recording.from_file`` per file."""
    code = (
        "import time; t = time.perf_counter(); import omega_prime; print(time.perf_counter() - t)"
    )
    imported = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    import warnings

    import omega_prime

    paths = sorted(out.glob("scenarios/*/recording.mcap"))[:: max(1, 200 // sample)][:sample]
    reads = []
    for path in paths:
        started = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            omega_prime.Recording.from_file(
                str(path), validate=False, parse_map=False, apply_proj=False
            )
        reads.append(time.perf_counter() - started)
    return {"import_seconds": float(imported.stdout.strip()), "from_file_seconds": reads}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--omega-prime-sample", type=int, default=10)
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "results" / "evaluate")
    options = parser.parse_args()
    rounds = []
    with tempfile.TemporaryDirectory(prefix="bench-evaluate-") as scratch:
        work = Path(scratch)
        timed([*SIMTEST, "run", str(MANIFEST), "-o", str(work / "warm"), "-j", "1", "--plain"],
              work / "warm.log")  # fmt: skip
        for index in range(options.rounds):
            out = work / f"sim{index}"
            simulate = timed(
                [*SIMTEST, "run", str(MANIFEST), "-o", str(out), "-j", "1", "--plain"],
                work / f"sim{index}.log",
            )
            evaluate = timed([*SIMTEST, "evaluate", str(out), "-q"], work / f"eval{index}.log")
            results = [json.loads(p.read_text()) for p in out.glob("scenarios/*/result.json")]
            rounds.append(
                {
                    "scenarios": len(results),
                    "simulate_seconds": simulate,
                    "evaluate_seconds": evaluate,
                    "ratio": simulate / evaluate,
                    "simulation_median": statistics.median(r["wallSeconds"] for r in results),
                    "evaluation_median": statistics.median(per_recording_evaluation(out)),
                    "evaluate_log": (work / f"eval{index}.log").read_text().strip(),
                }
            )
            print(
                f"round {index + 1}: simulate {simulate:.2f} s, evaluate {evaluate:.2f} s, "
                f"ratio {simulate / evaluate:.1f}x",
                flush=True,
            )
        omega = omega_prime_cost(work / "sim0", options.omega_prime_sample)
    summary = {
        "rounds": rounds,
        "median_simulate_seconds": statistics.median(r["simulate_seconds"] for r in rounds),
        "median_evaluate_seconds": statistics.median(r["evaluate_seconds"] for r in rounds),
        "median_ratio": statistics.median(r["ratio"] for r in rounds),
        "omega_prime": omega,
    }
    table = [
        "| round | scenarios | re-simulate (simtest run -j 1) | re-evaluate (simtest evaluate) "
        "| ratio | median per scenario: simulation / evaluation |",
        "|---|---|---|---|---|---|",
    ]
    for index, r in enumerate(rounds, 1):
        table.append(
            f"| {index} | {r['scenarios']} | {r['simulate_seconds']:.2f} s "
            f"| {r['evaluate_seconds']:.2f} s | {r['ratio']:.1f}x "
            f"| {r['simulation_median'] * 1000:.1f} ms / {r['evaluation_median'] * 1000:.1f} ms |"
        )
    reads = omega["from_file_seconds"]
    omega_total = statistics.median(reads) * 200 + omega["import_seconds"]
    table += [
        "",
        f"Median ratio {summary['median_ratio']:.1f}x (re-simulate "
        f"{summary['median_simulate_seconds']:.2f} s, re-evaluate "
        f"{summary['median_evaluate_seconds']:.2f} s).",
        f"omega-prime for comparison: `import omega_prime` {omega['import_seconds']:.2f} s; "
        f"`Recording.from_file` median {statistics.median(reads) * 1000:.0f} ms per recording "
        f"(n={len(reads)}), i.e. about {omega_total:.0f} s "
        "for 200 recordings before any metric.",
    ]
    text = "\n".join(table)
    print(text)
    options.out.parent.mkdir(parents=True, exist_ok=True)
    options.out.with_suffix(".json").write_text(json.dumps(summary, indent=2) + "\n")
    options.out.with_suffix(".md").write_text(text + "\n")


if __name__ == "__main__":
    main()
