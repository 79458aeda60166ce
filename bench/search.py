"""Benchmark of the search for failures: grid, random, TPE, boundary active learning, hybrid.

Three logical scenarios of ``scenarios/library`` with three parameters each, the built-in driver
model as the system under test, every run a real simulation through the runner's
``run_scenario`` on two spawned worker processes (one libsumo per process). Ground truth is a
dense grid of each scenario. For each scenario and seed, every strategy searches with budget
200 in waves of four (a window of two slots, kept full: the next wave is asked as soon as a wave
is told); random, TPE, boundary and hybrid do not depend on the budget, so their first 100 runs
are the budget-100 search; grid is run at 100 and 200 (its grid depends on the budget).
Reported:

* failures found (failing runs) and failure regions found: dense-grid regions (connected sets
  of failing grid points, diagonal neighbours included: :func:`analysis.cluster` at the grid's
  :func:`analysis.resolution`) that hold a failure of the search, or whose nearest failure lies
  within one grid step of it; and how many regions the search itself reports (the same two
  functions on its own runs) — a search is right about regions when that equals the truth;
* boundary misclassification: the share of the dense grid that the boundary classifier fitted on
  the search's runs gets wrong;
* runs to the dense grid's accuracy: the fewest runs after which the search's classifier reaches
  90 % of the dense grid's own balanced accuracy (5-fold cross-validated classifier on the dense
  grid; balanced, so "everything passes" cannot score), checked after every wave (``WAVE`` runs,
  the steps in which a search asks and is told): a coarser step would report the next multiple
  of it, not the runs the search needed.

Every simulation is cached under ``~/.cache/simtest/search-truth/`` by scenario content and
parameter values, so a rerun (and the dense grid) is free; the output says what came from the
cache. Runs finish in any order and are told as they finish, so a strategy that depends on the
tell order (TPE) may propose differently from one invocation to the next; the rest repeat
exactly. Writes ``bench/results/search.json`` (the issue's shape: per scenario and budget, random
and the default adaptive strategy), ``search.details.json`` (the dense grid's own figures, grid,
every adaptive strategy, runs to accuracy for all) and ``search.png`` (failures found over runs)::

    python bench/search.py                 # seed 0
    python bench/search.py --seeds 0 1 2   # medians over seeds
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import multiprocessing
import os
import statistics
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table
from sklearn.model_selection import StratifiedKFold

from simtest_operator.api.v1alpha1 import SearchSpec, SearchStrategy
from simtest_operator.runner import scenario_execution
from simtest_operator.search import Outcome, Searcher, SearchSpace, analysis, boundaries
from simtest_operator.settings import Settings
from simtest_operator.verdicts import Verdict

REPO = Path(__file__).resolve().parents[1]
LIBRARY = REPO / "scenarios" / "library"
RESULTS = REPO / "bench" / "results"
BUDGETS = (100, 200)
WAVE = 4
CHECKPOINT = WAVE
"""Runs between two checks of the boundary's accuracy: every wave, for every strategy."""
ACCURACY_SHARE = 0.9
ADAPTIVE = (SearchStrategy.TPE, SearchStrategy.BOUNDARY, SearchStrategy.HYBRID)


@dataclasses.dataclass(frozen=True)
class Case:
    name: str
    scenario: Path
    parameters: list[dict[str, Any]]
    dense: tuple[int, ...]
    """Dense-grid values per parameter."""


CASES = (
    Case(
        "cut-in",
        LIBRARY / "cut-in" / "cut-in_highway_v25_gap15_dv10.xosc",
        [
            {"name": "EgoSpeed", "min": 15, "max": 35, "step": 0.25},
            {"name": "CutInGap", "min": 5, "max": 40, "step": 0.25},
            {"name": "TargetSpeed", "min": 5, "max": 30, "step": 0.25},
        ],
        (8, 8, 6),
    ),
    Case(
        "pedestrian-crossing",
        LIBRARY / "pedestrian-crossing" / "pedestrian-crossing_junction_v11_tta2.5_walk1.4.xosc",
        [
            {"name": "EgoSpeed", "min": 6, "max": 16, "step": 0.1},
            {"name": "TriggerDistance", "min": 15, "max": 60, "step": 0.25},
            {"name": "WalkSpeed", "min": 0.8, "max": 3.0, "step": 0.05},
        ],
        (8, 8, 6),
    ),
    Case(
        "ltap",
        LIBRARY / "ltap" / "ltap_junction_v10_vt6_dt0.5.xosc",
        [
            {"name": "EgoSpeed", "min": 8, "max": 16, "step": 0.1},
            {"name": "TargetS", "min": 5, "max": 45, "step": 0.25},
            {"name": "TargetSpeed", "min": 4, "max": 10, "step": 0.1},
        ],
        (8, 8, 6),
    ),
    Case(
        "pedestrian-turn-back",
        LIBRARY / "pedestrian-turn-back" / "pedestrian-turn-back_junction_v8_tta7_walk2.5.xosc",
        [
            {"name": "EgoSpeed", "min": 6, "max": 16, "step": 0.1},
            {"name": "TriggerDistance", "min": 15, "max": 60, "step": 0.25},
            {"name": "WalkSpeed", "min": 0.8, "max": 3.0, "step": 0.05},
        ],
        (8, 8, 6),
    ),
)


class Simulator:
    """Runs override sets of one scenario on the worker pool, through a persistent cache."""

    def __init__(self, pool: Any, settings: Settings, case: Case) -> None:
        self.pool, self.settings, self.case = pool, settings, case
        digest = hashlib.sha256(case.scenario.read_bytes()).hexdigest()[:16]
        root = settings.cache.root / "search-truth"
        root.mkdir(parents=True, exist_ok=True)
        self.path = root / f"{case.name}-{digest}.json"
        self.runs: dict[str, dict[str, Any]] = (
            json.loads(self.path.read_text()) if self.path.is_file() else {}
        )
        self.hits = self.misses = 0
        self.sim_seconds = 0.0

    @staticmethod
    def key(overrides: Mapping[str, str]) -> str:
        return json.dumps(sorted(overrides.items()))

    def run(self, batch: Sequence[Mapping[str, str]]) -> Iterator[tuple[int, Outcome]]:
        """Outcomes of ``batch`` as they finish (cached ones first)."""
        todo = []
        for i, overrides in enumerate(batch):
            cached = self.runs.get(self.key(overrides))
            if cached is None:
                todo.append(i)
                continue
            self.hits += 1
            yield i, Outcome(Verdict(cached["verdict"]), cached["metrics"])
        requests = [
            scenario_execution.RunRequest(
                scenario=self.case.scenario,
                nets_dir=self.settings.cache.nets,
                overrides=dict(batch[i]),
                record=False,
            )
            for i in todo
        ]
        for j, report in self.pool.imap_unordered(_indexed, list(enumerate(requests))):
            outcome = report.outcome
            self.misses += 1
            self.sim_seconds += outcome.wall_seconds
            metrics = {k: v for k, v in outcome.metrics.items() if k in _METRICS}
            self.runs[self.key(batch[todo[j]])] = {
                "verdict": outcome.verdict.value,
                "metrics": metrics,
            }
            yield todo[j], Outcome(outcome.verdict, metrics)

    def save(self) -> None:
        """Merge with what is on disk (another invocation may have cached runs meanwhile) and
        replace the file atomically."""
        if self.path.is_file():
            self.runs = json.loads(self.path.read_text()) | self.runs
        partial = self.path.with_suffix(f".{os.getpid()}.tmp")
        partial.write_text(json.dumps(self.runs, sort_keys=True))
        partial.replace(self.path)


_METRICS = ("minTTC", "minTHW", "minDistance", "maxDecel")


def _indexed(item: tuple[int, scenario_execution.RunRequest]) -> tuple[int, Any]:
    index, request = item
    return index, scenario_execution.run_scenario(request)


def dense_grid(space: SearchSpace, case: Case) -> list[dict[str, float | str]]:
    axes = [np.linspace(0.0, 1.0, n) for n in case.dense]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, space.size)
    # Dense-grid values are not snapped to the search step: the truth is the scenario's.
    return [
        {
            d.name: round(d.low + float(u) * (d.high - d.low), 6)
            for d, u in zip(space.dimensions, p, strict=True)
        }
        for p in points
    ]


def overrides(values: Mapping[str, float | str]) -> dict[str, str]:
    from simtest_operator.openscenario import parameters

    return {k: v if isinstance(v, str) else parameters.to_text(v) for k, v in values.items()}


@dataclasses.dataclass
class Truth:
    points: np.ndarray
    step: float
    """The dense grid's resolution (its largest spacing): failures within one step in every
    parameter are one region."""
    failed: np.ndarray
    region_of: np.ndarray
    """Dense-grid region label of each failing dense point (-1 for passes)."""
    regions: int
    accuracy: float
    """Cross-validated balanced accuracy of the boundary classifier on the dense grid."""
    misclassification: float


def truth(
    space: SearchSpace, values: list[dict[str, float | str]], outcomes: list[Outcome]
) -> Truth:
    judged = [i for i, o in enumerate(outcomes) if o.judged]
    points = space.encode_all([values[i] for i in judged])
    failed = np.array([outcomes[i].failed for i in judged], dtype=bool)
    region_of = np.full(len(judged), -1)
    step = analysis.resolution(points)
    if failed.any():
        region_of[failed] = analysis.cluster(points[failed], step)
    folds = StratifiedKFold(n_splits=5, shuffle=True, random_state=0)
    accuracies, errors = [], []
    for train, test in folds.split(points, failed):
        fitted = boundaries.fit(points[train], failed[train])
        assert fitted is not None
        accuracies.append(fitted.balanced_accuracy(points[test], failed[test]))
        errors.append(fitted.misclassification(points[test], failed[test]))
    return Truth(
        points,
        step,
        failed,
        region_of,
        int(region_of.max()) + 1,
        float(np.mean(accuracies)),
        float(np.mean(errors)),
    )


def regions_found(space: SearchSpace, records: list[tuple[Any, Outcome]], t: Truth) -> int:
    """Dense-grid regions holding a failure of the search: its nearest dense-grid failure lies
    within one grid step in every parameter (the regions' own neighbourhood)."""
    found: set[int] = set()
    fail_points = t.points[t.failed]
    fail_regions = t.region_of[t.failed]
    for proposal, outcome in records:
        if not outcome.failed or len(fail_points) == 0:
            continue
        steps = np.abs(fail_points - np.array(space.encode(proposal.values))) / t.step
        gaps = steps.max(axis=1)
        nearest = int(np.argmin(gaps))
        if gaps[nearest] <= 1.0 + 1e-6:
            found.add(int(fail_regions[nearest]))
    return len(found)


def score(space: SearchSpace, records: list[tuple[Any, Outcome]], t: Truth) -> dict[str, Any]:
    fitted = analysis.fit_boundary(space, records)
    runs_to = None
    for n in range(CHECKPOINT, len(records) + 1, CHECKPOINT):
        partial = analysis.fit_boundary(space, records[:n])
        if (
            partial is not None
            and partial.balanced_accuracy(t.points, t.failed) >= ACCURACY_SHARE * t.accuracy
        ):
            runs_to = n
            break
    failed = [p for p, o in records if o.failed]
    step = analysis.resolution(analysis.labelled(space, records)[0])
    return {
        "failures": len(failed),
        "regions": regions_found(space, records, t),
        "reported_regions": len(analysis.regions(space, failed, step)),
        "misclassification": round(fitted.misclassification(t.points, t.failed), 4)
        if fitted
        else 1.0,
        "runs_to_grid_accuracy": runs_to,
    }


def search(
    sim: Simulator, case: Case, strategy: SearchStrategy, budget: int, seed: int
) -> tuple[list[tuple[Any, Outcome]], float]:
    spec = SearchSpec.model_validate(
        {
            "scenario": str(case.scenario),
            "parameters": case.parameters,
            "strategy": strategy,
            "budget": budget,
            "seed": seed,
        }
    )
    space = SearchSpace.from_spec(spec, case.scenario)
    searcher = Searcher(spec, space)
    thinking = 0.0
    while searcher.remaining:
        started = time.perf_counter()
        wave = searcher.ask(WAVE)
        thinking += time.perf_counter() - started
        for i, outcome in sim.run([p.overrides() for p in wave]):
            searcher.tell(wave[i].index, outcome)
    return searcher.records, thinking


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--only", nargs="*", default=None, help="scenario names, in run order")
    parser.add_argument(
        "--strategies",
        nargs="*",
        default=[s.value for s in SearchStrategy],
        help="strategies to run (random and the default are always run: search.json needs them)",
    )
    parser.add_argument("--json", type=Path, default=RESULTS / "search.json")
    parser.add_argument("--png", type=Path, default=RESULTS / "search.png")
    args = parser.parse_args()
    console = Console()
    settings = Settings.from_env()
    context = multiprocessing.get_context("spawn")
    out: dict[str, Any] = {"scenarios": []}
    details: list[dict[str, Any]] = []
    curves: dict[str, dict[str, list[tuple[int, int]]]] = {}
    chosen = [
        s
        for s in SearchStrategy
        if s.value in args.strategies or s in (SearchStrategy.RANDOM, SearchStrategy(_default()))
    ]
    with context.Pool(processes=args.workers) as pool:
        order = [c for name in args.only for c in CASES if c.name == name] if args.only else CASES
        for case in order:
            sim = Simulator(pool, settings, case)
            spec = SearchSpec.model_validate(
                {"scenario": str(case.scenario), "parameters": case.parameters, "budget": 1}
            )
            space = SearchSpace.from_spec(spec, case.scenario)
            values = dense_grid(space, case)
            started = time.perf_counter()
            outcomes: list[Outcome | None] = [None] * len(values)
            for i, outcome in sim.run([overrides(v) for v in values]):
                outcomes[i] = outcome
            sim.save()
            cached = sim.misses == 0
            console.print(
                f"{case.name}: dense grid {'x'.join(map(str, case.dense))} = {len(values)} runs, "
                f"{'from the cache' if cached else f'{sim.misses} simulated, {sim.hits} cached'} "
                f"({time.perf_counter() - started:.0f} s) -> {sim.path}"
            )
            t = truth(space, values, [o for o in outcomes if o is not None])
            console.print(
                f"  {int(t.failed.sum())} failures, {t.regions} regions, dense-grid boundary "
                f"balanced accuracy {t.accuracy:.3f} (5-fold), "
                f"misclassification {t.misclassification:.3f}"
            )
            per: dict[str, dict[int, list[dict[str, Any]]]] = {}
            for seed in args.seeds:
                for strategy in chosen:
                    budgets = BUDGETS if strategy is SearchStrategy.GRID else (max(BUDGETS),)
                    for budget in budgets:
                        hits, misses = sim.hits, sim.misses
                        started = time.perf_counter()
                        records, thinking = search(sim, case, strategy, budget, seed)
                        sim.save()
                        console.print(
                            f"  {strategy.value:8} seed {seed} budget {budget}: "
                            f"{sim.misses - misses} simulated, {sim.hits - hits} cached, "
                            f"{time.perf_counter() - started:.0f} s (proposing {thinking:.1f} s)"
                        )
                        targets = BUDGETS if strategy is not SearchStrategy.GRID else (budget,)
                        for target in targets:
                            result = score(space, records[:target], t)
                            per.setdefault(strategy.value, {}).setdefault(target, []).append(result)
                        if seed == args.seeds[0] and budget == max(BUDGETS):
                            running, curve = 0, []
                            for n, (_, o) in enumerate(records, start=1):
                                running += o.failed
                                curve.append((n, running))
                            curves.setdefault(case.name, {})[strategy.value] = curve
            entries = summarise_case(case, t, len(values), per, details)
            out["scenarios"].extend(entries)
            table(console, case, t, per)
            # Written after every scenario: a long run that is stopped keeps what it measured.
            write(args.json, args.png, out, details, curves)
            console.print(f"wrote {args.json} and {args.png}")


def write(
    json_path: Path,
    png: Path,
    out: dict[str, Any],
    details: list[dict[str, Any]],
    curves: dict[str, dict[str, list[tuple[int, int]]]],
) -> None:
    json_path.parent.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(out, indent=2) + "\n")
    # The issue fixes search.json's shape; the rest of the measurements sit beside it.
    json_path.with_suffix(".details.json").write_text(json.dumps(details, indent=2) + "\n")
    plot(curves, png)


def median(results: list[dict[str, Any]], key: str) -> Any:
    values = [r[key] for r in results]
    if any(v is None for v in values):
        known = [v for v in values if v is not None]
        # A seed that never reached the accuracy counts as worse than any that did.
        return (
            None
            if len(known) * 2 <= len(values)
            else statistics.median_low(sorted(known + [10**9] * (len(values) - len(known))))
        )
    return statistics.median(values)


def summarise_case(
    case: Case,
    t: Truth,
    grid_runs: int,
    per: dict[str, dict[int, list[dict[str, Any]]]],
    details: list[dict[str, Any]],
) -> list[dict[str, Any]]:
    """The issue's entries per budget; everything else measured goes to ``details``."""
    entries = []
    for budget in BUDGETS:
        adaptive = []
        for strategy in ADAPTIVE:
            if strategy.value not in per:
                continue
            results = per[strategy.value][budget]
            adaptive.append(
                {"strategy": strategy.value}
                | {
                    k: median(results, k)
                    for k in (
                        "failures",
                        "regions",
                        "misclassification",
                        "runs_to_grid_accuracy",
                        "reported_regions",
                    )
                }
            )
        random = per[SearchStrategy.RANDOM.value][budget]
        grid = per.get(SearchStrategy.GRID.value, {}).get(budget, [])
        chosen = {
            k: v
            for k, v in next(a for a in adaptive if a["strategy"] == _default()).items()
            if k != "reported_regions"
        }
        keys = ("failures", "regions", "misclassification")
        more = ("runs_to_grid_accuracy", "reported_regions")
        entries.append(
            {
                "name": case.name,
                "parameters": [p["name"] for p in case.parameters],
                "grid_runs": grid_runs,
                "budget": budget,
                "random": {k: median(random, k) for k in keys},
                "adaptive": chosen,
            }
        )
        details.append(
            {
                "name": case.name,
                "budget": budget,
                "truth": {
                    "failures": int(t.failed.sum()),
                    "regions": t.regions,
                    "balanced_accuracy": round(t.accuracy, 4),
                    "misclassification": round(t.misclassification, 4),
                },
                "grid": {k: median(grid, k) for k in (*keys, *more)} if grid else None,
                "random": {k: median(random, k) for k in (*keys, *more)},
                "adaptive": adaptive,
                "seeds": len(random),
            }
        )
    return entries


def _default() -> str:
    from simtest_operator.api.v1alpha1.search import DEFAULT_STRATEGY

    return DEFAULT_STRATEGY.value


def table(
    console: Console, case: Case, t: Truth, per: dict[str, dict[int, list[dict[str, Any]]]]
) -> None:
    out = Table(
        title=f"{case.name}: dense grid {t.failed.size} runs, "
        f"{int(t.failed.sum())} failures, {t.regions} regions"
    )
    for column in (
        "strategy",
        "budget",
        "failures",
        "regions",
        "reported regions",
        "misclassification",
        "runs to grid accuracy",
    ):
        out.add_column(column, justify="right")
    for strategy in SearchStrategy:
        for budget in BUDGETS:
            results = per.get(strategy.value, {}).get(budget)
            if not results:
                continue
            out.add_row(
                strategy.value,
                str(budget),
                str(median(results, "failures")),
                f"{median(results, 'regions')}/{t.regions}",
                str(median(results, "reported_regions")),
                f"{median(results, 'misclassification'):.3f}",
                str(median(results, "runs_to_grid_accuracy") or "-"),
            )
    console.print(out)


def plot(curves: dict[str, dict[str, list[tuple[int, int]]]], png: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(4.2 * max(len(curves), 1), 3.4), dpi=100)
    for k, (name, per) in enumerate(curves.items()):
        axes = figure.add_subplot(1, len(curves), k + 1)
        for strategy, curve in per.items():
            axes.plot([n for n, _ in curve], [f for _, f in curve], label=strategy)
        axes.set_title(name)
        axes.set_xlabel("runs")
        axes.set_ylabel("failures found")
        axes.legend(fontsize=8)
    figure.tight_layout()
    FigureCanvasAgg(figure).print_png(str(png))


if __name__ == "__main__":
    main()
