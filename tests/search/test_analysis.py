"""Summaries on synthetic data: failures, regions, boundary, critical runs, plots."""

from __future__ import annotations

import numpy as np

from simtest_operator.api.v1alpha1 import SearchObjective
from simtest_operator.search import Dimension, Outcome, Proposal, SearchSpace, analysis, boundaries
from simtest_operator.search.plotting import plot_pairs
from simtest_operator.verdicts import Verdict

SPACE = SearchSpace(
    scenario=None,
    dimensions=(
        Dimension(name="gap", low=0.0, high=100.0),
        Dimension(name="speed", low=0.0, high=10.0),
    ),
)


def record(
    index: int, gap: float, speed: float, verdict: Verdict, ttc: float
) -> tuple[Proposal, Outcome]:
    return (
        Proposal(index=index, values={"gap": gap, "speed": speed}, basis=0),
        Outcome(verdict, {"minTTC": ttc}),
    )


def two_pockets() -> list[tuple[Proposal, Outcome]]:
    """Failures in two separate corners (gap < 20 and speed > 8; gap > 80 and speed < 2)."""
    rng = np.random.default_rng(1)
    records = []
    for index, (u, v) in enumerate(rng.random((160, 2))):
        gap, speed = 100 * u, 10 * v
        failed = (gap < 20 and speed > 8) or (gap > 80 and speed < 2)
        verdict = Verdict.FAILED if failed else Verdict.PASSED
        records.append(record(index, gap, speed, verdict, 0.0 if failed else gap / 10))
    records.append(record(160, 50, 5, Verdict.ERROR, 0.0))
    return records


def test_summary_counts_regions_and_critical_runs() -> None:
    records = two_pockets()
    summary = analysis.summarise(SPACE, records, [SearchObjective()])
    failures = [p for p, o in records if o.failed]
    assert summary.runs == 161 and summary.not_judged == 1
    assert summary.failures == len(failures)
    # 160 random runs resolve about 0.1 of a range; the upper-left corner's 9 failures leave a
    # wider empty gap, so it may show as two regions, but no region spans both corners.
    assert 2 <= len(summary.regions) <= 3
    assert sum(r.count for r in summary.regions) == len(failures)
    corners = {float(r.centre["gap"]) > 50 for r in summary.regions}  # type: ignore[arg-type]
    assert corners == {False, True}
    for region in summary.regions:
        gaps = [float(v) for v in region.bounds["gap"]]  # type: ignore[arg-type]
        assert max(gaps) < 20 or min(gaps) > 80
    for region in summary.regions:
        low, high = region.bounds["gap"]
        assert float(low) <= float(region.centre["gap"]) <= float(high)  # type: ignore[arg-type]
    assert summary.best == -1.0
    assert all(c.verdict == "Failed" for c in summary.critical)
    assert summary.boundary is not None
    assert abs(summary.boundary.failure_share - 0.08) < 0.04  # two 0.2 x 0.2 corners


def test_boundary_misclassification_on_a_reference_set() -> None:
    fitted = analysis.fit_boundary(SPACE, two_pockets())
    assert fitted is not None
    reference = analysis.reference_points(2, 2000)
    truth = ((reference[:, 0] < 0.2) & (reference[:, 1] > 0.8)) | (
        (reference[:, 0] > 0.8) & (reference[:, 1] < 0.2)
    )
    assert fitted.misclassification(reference, truth) < 0.05
    assert fitted.balanced_accuracy(reference, truth) > 0.8
    # Against inverted labels the same classifier is nearly always wrong: the measure bites.
    assert fitted.misclassification(reference, ~truth) > 0.9


def test_one_class_gives_a_constant_boundary() -> None:
    fitted = boundaries.fit(np.array([[0.1, 0.2], [0.5, 0.5]]), np.array([False, False]))
    assert fitted is not None and fitted.constant is False
    assert not fitted.predict(np.array([[0.9, 0.9]])).any()
    assert boundaries.fit(np.zeros((0, 2)), np.zeros(0, dtype=bool)) is None


def test_a_metric_objective_ranks_by_the_metric() -> None:
    records = two_pockets()
    summary = analysis.summarise(
        SPACE, records, [SearchObjective(metric="minTTC", goal="maximize")]
    )
    best = max(o.metrics["minTTC"] for p, o in records if o.judged)
    assert summary.best == -best


def test_plot_pairs_draws_every_pair() -> None:
    space = SearchSpace(
        scenario=None, dimensions=(*SPACE.dimensions, Dimension(name="mode", choices=("a", "b")))
    )
    records = [
        (Proposal(index=p.index, values={**p.values, "mode": "ab"[p.index % 2]}, basis=0), o)
        for p, o in two_pockets()
    ]
    summary = analysis.summarise(space, records, [SearchObjective()])
    plots = plot_pairs(space, records, summary)
    assert [(x, y) for x, y, _ in plots] == [("gap", "speed"), ("gap", "mode"), ("speed", "mode")]
    assert all(png.startswith(b"\x89PNG") for _, _, png in plots)


def test_separate_pockets_stay_separate_at_any_density() -> None:
    for runs in (40, 160, 640):
        rng = np.random.default_rng(runs)
        records = []
        for index, (u, v) in enumerate(rng.random((runs, 2))):
            failed = (u < 0.2 and v > 0.8) or (u > 0.8 and v < 0.2)
            records.append(
                record(index, 100 * u, 10 * v, Verdict.FAILED if failed else Verdict.PASSED, 1.0)
            )
        summary = analysis.summarise(SPACE, records, [SearchObjective()])
        assert len(summary.regions) == 2, runs


def test_grid_regions_connect_diagonal_neighbours() -> None:
    # An oblique band on a 5 x 5 grid touches only diagonally; a point two steps off is apart.
    grid = np.array([[i / 4, j / 4] for i in range(5) for j in range(5)])
    assert analysis.resolution(grid) == 0.25
    band_points = np.array([[k / 4, k / 4] for k in range(5)])
    apart = np.array([[0.0, 1.0]])
    labels = analysis.cluster(np.vstack([band_points, apart]), analysis.resolution(grid))
    assert len(set(labels[:5].tolist())) == 1
    assert labels[5] not in labels[:5]
    # Spacing per dimension (5 x 3 points): the largest step links the diagonal neighbours.
    grid = np.array([[i / 4, j / 2] for i in range(5) for j in range(3)])
    assert analysis.resolution(grid) == 0.5
    labels = analysis.cluster(np.array([[0.0, 0.0], [0.25, 0.5], [0.5, 1.0]]), 0.5)
    assert len(set(labels.tolist())) == 1
