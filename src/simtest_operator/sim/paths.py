"""Paths: trajectory shapes (polyline, clothoid, clothoid spline, NURBS) sampled into polylines.

A :class:`Path` is a sequence of points with heading, cumulative length and optional times; the
trajectory follower interpolates it by distance or by time. Shapes are sampled once, when the
FollowTrajectoryAction starts, because their positions may be relative to entities at that moment.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from collections.abc import Callable, Sequence

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim import positions
from simtest_operator.sim.positions import Placement

SAMPLE_STEP = 0.5
"""Sampling distance (m) along curved shapes."""

Resolver = Callable[[model.Position], Placement]


@dataclasses.dataclass(frozen=True, slots=True)
class Path:
    """A sampled path: parallel sequences, ``lengths`` strictly increasing from 0."""

    xs: tuple[float, ...]
    ys: tuple[float, ...]
    headings: tuple[float, ...]
    lengths: tuple[float, ...]
    times: tuple[float, ...] | None

    @property
    def length(self) -> float:
        return self.lengths[-1]

    def at_distance(self, d: float) -> tuple[float, float, float]:
        """(x, y, heading) at distance ``d`` along the path (clamped)."""
        d = min(max(d, 0.0), self.length)
        i = max(1, bisect.bisect_left(self.lengths, d))
        i = min(i, len(self.lengths) - 1)
        seg = self.lengths[i] - self.lengths[i - 1]
        f = (d - self.lengths[i - 1]) / seg if seg > 0 else 1.0
        x = self.xs[i - 1] + f * (self.xs[i] - self.xs[i - 1])
        y = self.ys[i - 1] + f * (self.ys[i] - self.ys[i - 1])
        h0, h1 = self.headings[i - 1], self.headings[i]
        return x, y, h0 + f * math.remainder(h1 - h0, 2.0 * math.pi)

    def distance_at_time(self, t: float) -> float:
        """Distance along the path reached at path time ``t`` (linear between samples)."""
        assert self.times is not None
        times = self.times
        if t <= times[0]:
            return 0.0
        if t >= times[-1]:
            return self.length
        i = max(1, bisect.bisect_right(times, t))
        span = times[i] - times[i - 1]
        f = (t - times[i - 1]) / span if span > 0 else 1.0
        return self.lengths[i - 1] + f * (self.lengths[i] - self.lengths[i - 1])


def _build(
    points: Sequence[tuple[float, float]],
    times: Sequence[float | None],
    headings: Sequence[float] | None = None,
) -> Path:
    xs, ys, hs, ls, ts = [points[0][0]], [points[0][1]], [0.0], [0.0], [times[0]]
    for k in range(1, len(points)):
        x, y = points[k]
        step = math.hypot(x - xs[-1], y - ys[-1])
        if step < 1e-6:
            continue
        xs.append(x)
        ys.append(y)
        ls.append(ls[-1] + step)
        ts.append(times[k])
        hs.append(headings[k] if headings is not None else math.atan2(y - ys[-2], x - xs[-2]))
    if headings is not None:
        hs[0] = headings[0]
    elif len(xs) > 1:
        hs[0] = hs[1]
    if len(xs) < 2:
        raise ScenarioError("trajectory has fewer than two distinct points", element="Trajectory")
    known = [t for t in ts if t is not None]
    path_times = None
    if len(known) == len(ts):
        path_times = tuple(t for t in ts if t is not None)
    return Path(tuple(xs), tuple(ys), tuple(hs), tuple(ls), path_times)


def sample(shape: model.Shape, resolve: Resolver, start: Placement) -> Path:
    """Sample ``shape``; ``start`` is the following entity's pose at the action start."""
    if isinstance(shape, model.Unsupported):
        raise positions.unsupported(shape)
    if isinstance(shape, model.Polyline):
        placed = [resolve(vertex.position) for vertex in shape.vertices]
        return _build([(p.x, p.y) for p in placed], [v.time for v in shape.vertices])
    if isinstance(shape, model.Clothoid):
        origin = resolve(shape.position) if shape.position is not None else start
        return _clothoids(
            origin,
            [(shape.curvature, shape.curvature_prime, shape.length, 0.0)],
            [shape.start_time],
            shape.stop_time,
        )
    if isinstance(shape, model.ClothoidSpline):
        first = shape.segments[0].position_start if shape.segments else None
        origin = resolve(first) if first is not None else start
        pieces = [
            (
                seg.curvature_start,
                (seg.curvature_end - seg.curvature_start) / seg.length if seg.length > 0 else 0.0,
                seg.length,
                seg.h_offset,
            )
            for seg in shape.segments
        ]
        return _clothoids(
            origin, pieces, [seg.time_start for seg in shape.segments], shape.time_end
        )
    return _nurbs(shape, resolve)


def _clothoids(
    origin: Placement,
    pieces: Sequence[tuple[float, float, float, float]],
    start_times: Sequence[float | None],
    end_time: float | None,
) -> Path:
    x, y, h = origin.x, origin.y, origin.heading
    points, headings, distances = [(x, y)], [h], [0.0]
    total = 0.0
    piece_starts: list[float] = []
    for curvature, rate, length, h_offset in pieces:
        piece_starts.append(total)
        h += h_offset
        n = max(1, math.ceil(length / SAMPLE_STEP))
        ds = length / n
        for k in range(n):
            s_mid = (k + 0.5) * ds
            h_mid = h + curvature * s_mid + rate * s_mid * s_mid / 2.0
            x += ds * math.cos(h_mid)
            y += ds * math.sin(h_mid)
            s_end = (k + 1) * ds
            points.append((x, y))
            headings.append(h + curvature * s_end + rate * s_end * s_end / 2.0)
            total += ds
            distances.append(total)
        h += curvature * length + rate * length * length / 2.0
    times: list[float | None] = [None] * len(points)
    if start_times and start_times[0] is not None and end_time is not None:
        # Time runs uniformly along the whole curve between the first start and the end time.
        t0 = start_times[0]
        times = [t0 + (end_time - t0) * d / total if total > 0 else t0 for d in distances]
    return _build(points, times, headings)


def _nurbs(shape: model.Nurbs, resolve: Resolver) -> Path:
    placed = [resolve(cp.position) for cp in shape.control_points]
    weights = [cp.weight if cp.weight is not None else 1.0 for cp in shape.control_points]
    cp_times = [cp.time for cp in shape.control_points]
    with_times = all(t is not None for t in cp_times)
    order, knots = shape.order, shape.knots
    n = len(placed)
    if order < 1 or len(knots) != n + order:
        raise ScenarioError(
            "NURBS knot vector length must be control points + order",
            element="Nurbs",
            line=shape.line,
        )
    lo, hi = knots[order - 1], knots[n]
    samples = max(20, n * 20)
    points, times = [], []
    for k in range(samples + 1):
        u = lo + (hi - lo) * k / samples
        basis = [_basis(i, order, u, knots, hi) * weights[i] for i in range(n)]
        total = sum(basis) or 1.0
        points.append(
            (
                sum(b * p.x for b, p in zip(basis, placed, strict=True)) / total,
                sum(b * p.y for b, p in zip(basis, placed, strict=True)) / total,
            )
        )
        if with_times:
            times.append(sum(b * (t or 0.0) for b, t in zip(basis, cp_times, strict=True)) / total)
    return _build(points, times if with_times else [None] * len(points))


def _basis(i: int, order: int, u: float, knots: Sequence[float], end: float) -> float:
    """Cox-de Boor B-spline basis N_{i,order}(u); the last span is closed at ``end``."""
    if order == 1:
        inside = knots[i] <= u < knots[i + 1] or (u == end and knots[i] < u == knots[i + 1])
        return 1.0 if inside else 0.0
    value = 0.0
    left = knots[i + order - 1] - knots[i]
    if left > 0:
        value += (u - knots[i]) / left * _basis(i, order - 1, u, knots, end)
    right = knots[i + order] - knots[i + 1]
    if right > 0:
        value += (knots[i + order] - u) / right * _basis(i + 1, order - 1, u, knots, end)
    return value
