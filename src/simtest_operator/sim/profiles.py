"""Speed profiles (SpeedProfileAction) planned into piecewise speed segments.

Entry times are durations from the previous entry (an entry without a time is reached at the
allowed acceleration or deceleration; in ``follow`` mode one whose time asks for more is reached
later, at the allowed rate). The entries become vertices (time, speed) joined by
straight speed lines; collinear middle vertices are merged.

``position`` mode drives the lines themselves (speed piecewise linear in time). ``follow`` mode
drives them the way a vehicle with limited jerk would, as the reference player does: it starts
from the current speed and acceleration, and turns from one line onto the next with a constant
jerk (the allowed acceleration/deceleration rate) so that it rides the next line from the end of
the turn on. A single target in ``follow`` mode is reached at its time with a jerk, an optional
constant-acceleration stretch and a jerk back to zero acceleration (later, when the limits do
not allow it on time).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

EPSILON = 1e-9


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Limits:
    """Acceleration and deceleration (m/s^2, positive) and their rates (m/s^3, positive; inf:
    no jerk limit)."""

    acceleration: float
    deceleration: float
    acceleration_rate: float = math.inf
    deceleration_rate: float = math.inf


@dataclasses.dataclass(frozen=True, slots=True)
class Segment:
    """From time ``t``: speed ``v + k (τ) + j τ² / 2`` with τ = time - t."""

    t: float
    v: float
    k: float
    j: float = 0.0

    def speed(self, time: float) -> float:
        tau = time - self.t
        return self.v + self.k * tau + 0.5 * self.j * tau * tau


@dataclasses.dataclass(slots=True)
class _Vertex:
    t: float
    v: float
    k: float = 0.0
    """Slope of the speed line leaving this vertex."""

    @property
    def m(self) -> float:
        """Intercept of that line (v = k t + m)."""
        return self.v - self.k * self.t


def vertices(
    entries: Sequence[tuple[float | None, float]],
    *,
    start: float,
    speed: float,
    follow: bool,
    limits: Limits,
) -> list[_Vertex]:
    """Vertices of the speed lines for ``entries`` (duration or None, target speed)."""
    first_time = entries[0][0]
    out: list[_Vertex] = []
    index = 0
    if first_time is not None and abs(first_time) <= EPSILON and not follow:
        out.append(_Vertex(start, entries[0][1]))  # position mode starts at the given speed
    else:
        out.append(_Vertex(start, speed))
        if first_time is not None and abs(first_time) <= EPSILON:
            index = 1  # follow mode replaces a first entry at time 0 by the current state
    time = start
    for i in range(index, len(entries)):
        duration, target = entries[i]
        last = out[-1]
        dv = target - last.v
        least = dv / (limits.acceleration if dv > 0 else -limits.deceleration)
        if duration is None:
            if abs(dv) <= EPSILON:
                continue
            time += least
        elif follow:
            # a vehicle cannot change speed faster than its limits: it arrives later
            time = max(time + duration, last.t + least)
        else:
            time += duration
        span = time - last.t
        final = i == len(entries) - 1
        if span <= EPSILON:
            if not final:
                out[-1] = _Vertex(time, target)
                continue
            span = EPSILON
        last.k = (target - last.v) / span
        if len(out) > 1 and abs(last.k - out[-2].k) <= EPSILON:
            # collinear with the previous line: drop the middle vertex
            out.pop()
            previous = out[-1]
            previous.k = (target - previous.v) / (time - previous.t)
        out.append(_Vertex(time, target))
    return out


def plan(
    entries: Sequence[tuple[float | None, float]],
    *,
    start: float,
    speed: float,
    acceleration: float,
    follow: bool,
    limits: Limits,
) -> list[Segment]:
    """Speed segments from ``start`` (current ``speed`` and ``acceleration``)."""
    points = vertices(entries, start=start, speed=speed, follow=follow, limits=limits)
    if len(points) == 1:
        return [Segment(points[0].t, points[0].v, 0.0)]
    if not follow:
        return [Segment(p.t, p.v, p.k) for p in points]
    if len(points) == 2:
        return _single_target(points[0], points[1], acceleration, limits)
    return _follow_lines(points, acceleration, limits)


def _jerk(from_k: float, to_k: float, limits: Limits) -> float:
    return -limits.deceleration_rate if to_k - from_k < 0 else limits.acceleration_rate


def _follow_lines(points: list[_Vertex], k0: float, limits: Limits) -> list[Segment]:
    first = points[0]
    segments: list[Segment] = []
    t, v = first.t, first.v
    if abs(first.k - k0) > EPSILON:
        j = _jerk(k0, first.k, limits)
        if math.isfinite(j):
            segments.append(Segment(t, v, k0, j))
            tau = (first.k - k0) / j
            v += k0 * tau + 0.5 * j * tau * tau
            t += tau
    k, m = first.k, v - first.k * t
    segments.append(Segment(t, v, k))
    for vertex in points[1:]:
        k1, m1 = vertex.k, vertex.m
        if abs(k - k1) <= EPSILON:
            k, m = k1, m1  # same slope: ride on, aim later turns at this vertex's line
            continue
        j = _jerk(k, k1, limits)
        tau = (k1 - k) / j if math.isfinite(j) else 0.0
        # Start turning where a constant jerk lands exactly on the next line.
        t1 = (m1 - m + 0.5 * (k1 - k) * tau) / (k - k1)
        if t1 < segments[-1].t - EPSILON:
            # No room to turn: fall back to the lines themselves from here on.
            segments.extend(Segment(p.t, p.v, p.k) for p in points[points.index(vertex) :])
            return segments
        v1 = k * t1 + m
        if tau > 0:
            segments.append(Segment(t1, v1, k, j))
        t3 = t1 + tau
        segments.append(Segment(t3, k1 * t3 + m1, k1))
        k, m = k1, m1
    return segments


def _single_target(p0: _Vertex, p1: _Vertex, k0: float, limits: Limits) -> list[Segment]:
    """Reach p1.v with zero acceleration at p1.t: jerk j0 for a, constant k1 for b, jerk j1
    for c = -k1/j1 (a, b, c >= 0); b = 0 and a later arrival when the time is too short, and
    k1 clamped to the acceleration limits (arriving later) when it would exceed them."""
    j0 = _jerk(k0, p0.k, limits)
    j1 = limits.acceleration_rate if p0.k < 0 else -limits.deceleration_rate
    if not (math.isfinite(j0) and math.isfinite(j1)):
        return [Segment(p0.t, p0.v, p0.k), Segment(p1.t, p1.v, 0.0)]
    dv, total = p1.v - p0.v, p1.t - p0.t
    # dv = k0 a + j0 a²/2 + k1 (T - a) + k1²/(2 j1) with k1 = k0 + j0 a  (b = T - a - c >= 0)
    a = _smallest_root(
        0.5 * j0 * j0 / j1 - 0.5 * j0,
        k0 * j0 / j1 + j0 * total,
        k0 * total + 0.5 * k0 * k0 / j1 - dv,
    )
    k1 = k0 + j0 * a if a is not None else 0.0
    b = total - (a or 0.0) + k1 / j1 if a is not None else -1.0
    if a is None or b < -EPSILON:
        # dv = k0 a + j0 a²/2 - k1²/(2 j1)  (b = 0, arrive when the jerks allow)
        a = _smallest_root(
            0.5 * j0 - 0.5 * j0 * j0 / j1, k0 - k0 * j0 / j1, -0.5 * k0 * k0 / j1 - dv
        )
        a = a or 0.0
        k1, b = k0 + j0 * a, 0.0
    limit_hi, limit_lo = limits.acceleration, -limits.deceleration
    if k1 > limit_hi or k1 < limit_lo:
        k1 = min(max(k1, limit_lo), limit_hi)
        a = (k1 - k0) / j0
        gained = k0 * a + 0.5 * j0 * a * a - 0.5 * k1 * k1 / j1
        b = (dv - gained) / k1 if abs(k1) > EPSILON else 0.0
    c = -k1 / j1
    t1, t2 = p0.t + a, p0.t + a + max(b, 0.0)
    v1 = p0.v + k0 * a + 0.5 * j0 * a * a
    v2 = v1 + k1 * (t2 - t1)
    segments = [Segment(p0.t, p0.v, k0, j0)]
    if t2 > t1 + EPSILON:
        segments.append(Segment(t1, v1, k1))
    segments.append(Segment(t2, v2, k1, j1))
    segments.append(Segment(t2 + c, p1.v, 0.0))
    return segments


def _smallest_root(qa: float, qb: float, qc: float) -> float | None:
    """Smallest non-negative root of qa x² + qb x + qc (None if there is none)."""
    if abs(qa) <= EPSILON:
        if abs(qb) <= EPSILON:
            return None
        root = -qc / qb
        return root if root >= -EPSILON else None
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0.0:
        return None
    roots = sorted(((-qb - math.sqrt(disc)) / (2 * qa), (-qb + math.sqrt(disc)) / (2 * qa)))
    good = [max(r, 0.0) for r in roots if r >= -EPSILON]
    return good[0] if good else None


def speed_at(segments: Sequence[Segment], time: float) -> float:
    """Speed at ``time`` (the first segment before its start, the last one after its end)."""
    index = 0
    while index < len(segments) - 1 and time > segments[index + 1].t - EPSILON:
        index += 1
    return segments[index].speed(time)
