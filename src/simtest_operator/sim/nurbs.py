"""NURBS trajectories: sampling the curve and timing it the way the reference player does.

A NURBS control point carries a time, but the curve passes through control points only at its
ends, so "when" a point of the curve is reached needs a rule. The reference player (esmini)
associates each control point with the curve parameter where its basis function peaks (where
it pulls the curve most) and interpolates time linearly in the parameter between consecutive
control points; matching that reproduces its speeds along the curve within a few percent.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim.placements import Placement
from simtest_operator.sim.sampled_paths import Path, build

STEPS_PER_METRE = 2.0
"""Curve samples per metre of control polygon."""


def sample(shape: model.Nurbs, placed: Sequence[Placement]) -> Path:
    """Sample ``shape`` whose control points were resolved to ``placed``."""
    points = shape.control_points
    order, knots, n = shape.order, shape.knots, len(points)
    if order < 1 or n < order or len(knots) != n + order:
        raise ScenarioError(
            "NURBS needs at least `order` control points and a knot vector of control points"
            " + order values",
            element="Nurbs",
            line=shape.line,
        )
    weights = [cp.weight if cp.weight is not None else 1.0 for cp in points]
    lo, hi = knots[order - 1], knots[n]
    polygon = sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in itertools.pairwise(placed))
    steps = max(20 * n, math.ceil(polygon * STEPS_PER_METRE))
    params: list[float] = []
    xy: list[tuple[float, float]] = []
    peak_value = [0.0] * n
    peak_param = [lo] * n
    for k in range(steps + 1):
        u = lo + (hi - lo) * k / steps
        basis = [basis_function(i, order, u, knots, hi) for i in range(n)]
        for i, b in enumerate(basis):
            if b > peak_value[i]:
                peak_value[i], peak_param[i] = b, u
        weighted = [b * w for b, w in zip(basis, weights, strict=True)]
        total = sum(weighted) or 1.0
        xy.append(
            (
                sum(b * p.x for b, p in zip(weighted, placed, strict=True)) / total,
                sum(b * p.y for b, p in zip(weighted, placed, strict=True)) / total,
            )
        )
        params.append(u)
    cp_times = [cp.time for cp in points]
    if any(t is None for t in cp_times):
        return build(xy, [None] * len(xy))
    known = [t for t in cp_times if t is not None]
    return build(xy, [_time_at(u, peak_param, known) for u in params])


def _time_at(u: float, peaks: Sequence[float], times: Sequence[float]) -> float:
    """Time at parameter ``u``: linear between the peaks of consecutive control points."""
    i = 0
    while i < len(peaks) - 2 and u >= peaks[i + 1]:
        i += 1
    span = peaks[i + 1] - peaks[i]
    f = (u - peaks[i]) / span if span > 0 else 1.0
    return times[i] + f * (times[i + 1] - times[i])


def basis_function(i: int, order: int, u: float, knots: Sequence[float], end: float) -> float:
    """Cox-de Boor B-spline basis N_{i,order}(u); the last span is closed at ``end``."""
    if order == 1:
        inside = knots[i] <= u < knots[i + 1] or (u == end and knots[i] < u == knots[i + 1])
        return 1.0 if inside else 0.0
    value = 0.0
    left = knots[i + order - 1] - knots[i]
    if left > 0:
        value += (u - knots[i]) / left * basis_function(i, order - 1, u, knots, end)
    right = knots[i + order] - knots[i + 1]
    if right > 0:
        value += (knots[i + order] - u) / right * basis_function(i + 1, order - 1, u, knots, end)
    return value
