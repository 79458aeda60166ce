"""Trajectory shapes -> paths: polylines, clothoids and clothoid splines (NURBS: :mod:`nurbs`).

Shapes are sampled once, when the FollowTrajectoryAction starts, because their positions may be
relative to entities at that moment. Clothoids are integrated piecewise with the chord of the
local arc (exact on arcs and lines, third order on spirals). A clothoid spline segment may start
at a pose of its own (a jump, as the standard allows) and turns its start heading by
``hOffset``; timed splines run each segment from its ``timeStart`` to the next one's at
constant speed.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from collections.abc import Sequence

from simtest_operator.openscenario import model
from simtest_operator.sim import nurbs, placements
from simtest_operator.sim.placements import Placement
from simtest_operator.sim.sampled_paths import Path, build

SAMPLE_STEP = 0.5
"""Sampling distance (m) along curved shapes."""


def sample(shape: model.Shape, resolve: placements.Resolver, start: Placement) -> Path:
    """Sample ``shape``; ``start`` is the following entity's pose at the action start."""
    if isinstance(shape, model.Unsupported):
        raise placements.unsupported(shape)
    if isinstance(shape, model.Polyline):
        placed = [resolve(vertex.position) for vertex in shape.vertices]
        return build([(p.x, p.y) for p in placed], [v.time for v in shape.vertices])
    if isinstance(shape, model.Clothoid):
        origin = resolve(shape.position) if shape.position is not None else start
        piece = _Piece(
            curvature=shape.curvature,
            rate=shape.curvature_prime,
            length=shape.length,
            time_start=shape.start_time,
        )
        return _clothoids(origin, [piece], shape.stop_time)
    if isinstance(shape, model.ClothoidSpline):
        pieces = [
            _Piece(
                curvature=seg.curvature_start,
                rate=(seg.curvature_end - seg.curvature_start) / seg.length
                if seg.length > 0
                else 0.0,
                length=seg.length,
                h_offset=seg.h_offset,
                time_start=seg.time_start,
                start=resolve(seg.position_start) if seg.position_start is not None else None,
            )
            for seg in shape.segments
        ]
        return _clothoids(start, pieces, shape.time_end)
    return nurbs.sample(shape, [resolve(cp.position) for cp in shape.control_points])


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class _Piece:
    """One clothoid piece: curvature at its start, its rate (1/m^2), length; a segment may
    start at a pose of its own (else where the previous one ended), turned by ``h_offset``."""

    curvature: float
    rate: float
    length: float
    h_offset: float = 0.0
    time_start: float | None = None
    start: Placement | None = None


def _clothoids(origin: Placement, pieces: Sequence[_Piece], end_time: float | None) -> Path:
    """Integrate the pieces from ``origin`` (the pose used when the first piece has no start).

    Timing, when the shape has some: a piece runs from its ``time_start`` to the next piece's
    (the last one to ``end_time``) at constant speed; missing start times in between are
    interpolated by distance.
    """
    x, y, h = origin.x, origin.y, origin.heading
    points: list[tuple[float, float]] = []
    headings: list[float] = []
    distances: list[float] = []
    piece_starts: list[float] = []
    total = 0.0
    for piece in pieces:
        if piece.start is not None:
            x, y, h = piece.start.x, piece.start.y, piece.start.heading
        h += piece.h_offset
        if not points or (x, y) != points[-1]:
            points.append((x, y))
            headings.append(h)
            distances.append(total)
        else:
            headings[-1] = h
        piece_starts.append(total)
        n = max(1, math.ceil(piece.length / SAMPLE_STEP))
        ds = piece.length / n
        curvature, rate = piece.curvature, piece.rate
        for k in range(n):
            s_mid = (k + 0.5) * ds
            h_mid = h + curvature * s_mid + rate * s_mid * s_mid / 2.0
            # Chord of the arc through the midpoint heading: exact on arcs, O(ds^3) on spirals.
            chord = ds * _sinc(ds * (curvature + rate * s_mid) / 2.0)
            x += chord * math.cos(h_mid)
            y += chord * math.sin(h_mid)
            s_end = (k + 1) * ds
            points.append((x, y))
            headings.append(h + curvature * s_end + rate * s_end * s_end / 2.0)
            total += ds
            distances.append(total)
        h += curvature * piece.length + rate * piece.length**2 / 2.0
    piece_starts.append(total)
    knots = _piece_times([p.time_start for p in pieces], end_time, piece_starts)
    times: list[float | None] = [None] * len(points)
    if knots is not None:
        times = [_interpolate(piece_starts, knots, d) for d in distances]
    return build(points, times, headings)


def _sinc(x: float) -> float:
    return math.sin(x) / x if abs(x) > 1e-9 else 1.0


def _piece_times(
    starts: Sequence[float | None], end_time: float | None, boundaries: Sequence[float]
) -> list[float] | None:
    """Times at the piece boundaries, or None without a first start time and an end time."""
    known = [*starts, end_time]
    first, last = known[0], known[-1]
    if first is None or last is None:
        return None
    times: list[float] = [first]
    for k in range(1, len(known)):
        value = known[k]
        if value is None:
            nxt = next(j for j in range(k + 1, len(known)) if known[j] is not None)
            later = known[nxt]
            assert later is not None
            span = boundaries[nxt] - boundaries[k - 1]
            f = (boundaries[k] - boundaries[k - 1]) / span if span > 0 else 0.0
            value = times[-1] + f * (later - times[-1])
        times.append(value)
    return times


def _interpolate(xs: Sequence[float], ys: Sequence[float], x: float) -> float:
    i = min(max(1, bisect.bisect_right(xs, x)), len(xs) - 1)
    span = xs[i] - xs[i - 1]
    f = (x - xs[i - 1]) / span if span > 0 else 1.0
    return ys[i - 1] + f * (ys[i] - ys[i - 1])
