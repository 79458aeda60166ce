"""What a finished (or running) search found: failures, failure regions, boundary, critical runs.

A failure region is a set of failures connected at the resolution the runs themselves have:
two failures are neighbours when they differ by at most one step in every parameter (Chebyshev
distance in the unit cube), and a region is a chain of neighbours (single linkage). The step is
the longest edge of the minimum spanning tree of all judged runs, the finest distance at which
the sample is one connected set. On a grid that is the grid's spacing, so a region is a
connected set of failing grid points, diagonal neighbours included (a thin oblique band is one
region, not pieces that touch only at corners); a sparse search gets a coarser step, so its
failures do not each become a "region" of their own. The dense grid of the benchmark and a
search are clustered by the same two functions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from pydantic import BaseModel, ConfigDict

from simtest_operator.api.v1alpha1.search import SearchObjective
from simtest_operator.search import boundaries
from simtest_operator.search.records import Outcome, Proposal, criticality
from simtest_operator.search.spaces import Points, SearchSpace, Value

CRITICAL_COUNT = 10
"""How many of the most critical proposals the summary lists."""

Records = Sequence[tuple[Proposal, Outcome]]


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class Region(_Model):
    """One cluster of failures."""

    count: int
    centre: dict[str, Value]
    """Parameter values at the members' mean unit-cube point."""
    bounds: dict[str, tuple[Value, Value]]
    """Smallest and largest member value per parameter."""
    members: list[int]
    """Proposal indices."""


class BoundarySummary(_Model):
    """The fitted pass/fail classifier, summarised."""

    training_points: int
    failure_share: float
    """Share of the unit cube predicted to fail (on a fixed quasi-random reference set)."""
    training_misclassification: float


class CriticalRun(_Model):
    """One of the most critical proposals."""

    index: int
    values: dict[str, Value]
    verdict: str
    score: float
    """Criticality under the first objective (lower is more critical)."""


class SearchSummary(_Model):
    """The bounded summary of a search (the full record is in the results store)."""

    runs: int
    failures: int
    not_judged: int
    """Error and Invalid runs: no verdict on the system, left out of regions and boundary."""
    regions: list[Region]
    boundary: BoundarySummary | None
    critical: list[CriticalRun]
    best: float | None
    """The most critical score reached under the first objective."""


def summarise(
    space: SearchSpace, records: Records, objectives: Sequence[SearchObjective]
) -> SearchSummary:
    """Summarise ``records`` (proposal, outcome) of a search over ``space``."""
    judged = [(p, o) for p, o in records if o.judged]
    failed = [p for p, o in judged if o.failed]
    fitted = fit_boundary(space, records)
    boundary = None
    if fitted is not None:
        points, labels = labelled(space, records)
        boundary = BoundarySummary(
            training_points=len(points),
            failure_share=float(np.mean(fitted.predict(reference_points(space.size)))),
            training_misclassification=fitted.misclassification(points, labels),
        )
    scored = [
        (score, p, o)
        for p, o in records
        if (score := criticality(o, objectives[0])) is not None and math.isfinite(score)
    ]
    scored.sort(key=lambda item: (item[0], item[1].index))
    return SearchSummary(
        runs=len(records),
        failures=len(failed),
        not_judged=len(records) - len(judged),
        regions=regions(space, failed, resolution(labelled(space, records)[0])),
        boundary=boundary,
        critical=[
            CriticalRun(index=p.index, values=dict(p.values), verdict=o.verdict.value, score=s)
            for s, p, o in scored[:CRITICAL_COUNT]
        ],
        best=scored[0][0] if scored else None,
    )


def labelled(space: SearchSpace, records: Records) -> tuple[Points, npt.NDArray[np.bool_]]:
    """Unit-cube points and failure labels of the judged records."""
    judged = [(p, o) for p, o in records if o.judged]
    points = space.encode_all([p.values for p, _ in judged])
    return points, np.array([o.failed for _, o in judged], dtype=bool)


def fit_boundary(space: SearchSpace, records: Records) -> boundaries.Boundary | None:
    """The estimated boundary of ``records``; :meth:`.Boundary.predict` takes unit-cube points
    (:meth:`SearchSpace.encode_all`)."""
    return boundaries.fit(*labelled(space, records))


def regions(space: SearchSpace, failed: Sequence[Proposal], step: float) -> list[Region]:
    """Failure regions of ``failed`` at ``step`` (:func:`resolution` of the judged runs),
    largest first (ties by the smallest member index)."""
    if not failed:
        return []
    points = space.encode_all([p.values for p in failed])
    labels = cluster(points, step)
    found = []
    for label in sorted(set(labels.tolist())):
        members = [p for p, lab in zip(failed, labels, strict=True) if lab == label]
        inside = points[labels == label]
        bounds: dict[str, tuple[Value, Value]] = {}
        for d in space.dimensions:
            values = [m.values[d.name] for m in members]
            if d.categorical:
                texts = sorted({str(v) for v in values})
                bounds[d.name] = (texts[0], texts[-1])
            else:
                numbers = [float(v) for v in values]
                bounds[d.name] = (min(numbers), max(numbers))
        found.append(
            Region(
                count=len(members),
                centre=space.decode(inside.mean(axis=0)),
                bounds=bounds,
                members=sorted(m.index for m in members),
            )
        )
    found.sort(key=lambda r: (-r.count, r.members[0]))
    return found


def resolution(points: Points) -> float:
    """The step at which the runs at ``points`` (unit cube) form one connected set: the longest
    edge of their minimum spanning tree under the Chebyshev distance. On a grid it is the grid's
    spacing (its largest, if the spacing differs per dimension); a scattered sample's gaps are
    uneven, so it is what the sparsest part of the sample resolves."""
    if len(points) < 2:
        return 1.0
    from sklearn.cluster import AgglomerativeClustering

    # Single linkage merges along the minimum spanning tree: its last merge is the longest edge.
    model = AgglomerativeClustering(
        n_clusters=1, metric="chebyshev", linkage="single", compute_distances=True
    )
    model.fit(points)
    return max(float(model.distances_.max()), 1e-9)


def cluster(points: Points, step: float) -> npt.NDArray[np.int64]:
    """Region labels of unit-cube failure points: chains of neighbours at most ``step`` apart in
    every dimension (see the module docstring)."""
    if len(points) == 1:
        return np.zeros(1, dtype=np.int64)
    from sklearn.cluster import AgglomerativeClustering

    # Merged below the threshold: a hair above one step keeps grid neighbours (whose values
    # are rounded to the scenario's precision) together.
    model = AgglomerativeClustering(
        n_clusters=None,
        distance_threshold=step * (1.0 + 1e-6),
        metric="chebyshev",
        linkage="single",
    )
    labels: npt.NDArray[np.int64] = model.fit_predict(points).astype(np.int64)
    return labels


def reference_points(size: int, count: int = 4096) -> Points:
    """A fixed quasi-random reference set of the unit cube (a Halton sequence, unscrambled)."""
    from scipy.stats import qmc

    points: Points = qmc.Halton(d=size, scramble=False).random(count)
    return points
