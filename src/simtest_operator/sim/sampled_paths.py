"""Paths: a trajectory sampled into a polyline with headings, lengths and optional times.

The trajectory follower interpolates a :class:`Path` by distance (untimed following) or by time
(timed following). :mod:`~simtest_operator.sim.shapes` turns trajectory shapes into paths.

Timed following has two flavours, as in the reference player. In ``position`` mode the entity is
exactly where the path says at every instant: constant speed between consecutive samples. In
``follow`` mode the entity drives there: its speed changes linearly in time between samples, and
the speeds at the samples are chosen so that every sample is still reached at its time (see
:meth:`Path.following`).
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from collections.abc import Sequence

from simtest_operator.errors import ScenarioError


@dataclasses.dataclass(frozen=True, slots=True)
class Path:
    """A sampled path: parallel sequences, ``lengths`` non-decreasing from 0 (a repeated point
    with a later time is a stop on the path)."""

    xs: tuple[float, ...]
    ys: tuple[float, ...]
    headings: tuple[float, ...]
    lengths: tuple[float, ...]
    times: tuple[float, ...] | None
    speeds: tuple[float, ...] | None = None
    """Speed at each sample in ``follow`` mode (linear in time in between); None: constant
    speed between samples."""

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

    def direction_at(self, d: float) -> float:
        """Direction (rad) the path runs in at distance ``d``: that of the segment there (at a
        stop, of the next segment that moves; at the end, of the last one). The headings may
        differ: a trajectory may give its entity a heading of its own."""
        d = min(max(d, 0.0), self.length)
        last = len(self.lengths) - 1
        i = min(max(1, bisect.bisect_right(self.lengths, d)), last)
        ahead = i
        while ahead < last and self.lengths[ahead] - self.lengths[ahead - 1] <= 0:
            ahead += 1
        while ahead > 1 and self.lengths[ahead] - self.lengths[ahead - 1] <= 0:
            ahead -= 1
        return math.atan2(self.ys[ahead] - self.ys[ahead - 1], self.xs[ahead] - self.xs[ahead - 1])

    def _span(self, t: float) -> int:
        """Index i of the sample interval [i-1, i] (of positive duration) containing time t."""
        assert self.times is not None
        times = self.times
        i = min(max(1, bisect.bisect_right(times, t)), len(times) - 1)
        while i > 1 and times[i] - times[i - 1] <= 0:
            i -= 1
        return i

    def speed_at_time(self, t: float) -> float:
        """Path speed (distance per path time) at path time ``t``."""
        assert self.times is not None
        i = self._span(t)
        t0, t1 = self.times[i - 1], self.times[i]
        span = t1 - t0
        if span <= 0:
            return 0.0
        if self.speeds is not None:
            f = min(max((t - t0) / span, 0.0), 1.0)
            return self.speeds[i - 1] + f * (self.speeds[i] - self.speeds[i - 1])
        return (self.lengths[i] - self.lengths[i - 1]) / span

    def distance_at_time(self, t: float) -> float:
        """Distance along the path reached at path time ``t``."""
        assert self.times is not None
        times = self.times
        if t <= times[0]:
            return 0.0
        if t >= times[-1]:
            return self.length
        i = self._span(t)
        t0, t1 = times[i - 1], times[i]
        d0, d1 = self.lengths[i - 1], self.lengths[i]
        span = t1 - t0
        tau = min(max(t - t0, 0.0), span)
        if span <= 0:
            return d1
        if self.speeds is None:
            return d0 + tau / span * (d1 - d0)
        v0, v1 = self.speeds[i - 1], self.speeds[i]
        return min(d0 + v0 * tau + (v1 - v0) * tau * tau / (2.0 * span), d1)

    def time_at_distance(self, d: float) -> float:
        """Path time at which distance ``d`` is reached (0 for an untimed path; linear between
        samples)."""
        if self.times is None:
            return 0.0
        d = min(max(d, 0.0), self.length)
        i = min(max(1, bisect.bisect_left(self.lengths, d)), len(self.lengths) - 1)
        d0, d1 = self.lengths[i - 1], self.lengths[i]
        f = (d - d0) / (d1 - d0) if d1 > d0 else 0.0
        return self.times[i - 1] + f * (self.times[i] - self.times[i - 1])

    def following(self, start_speed: float) -> Path:
        """This path driven in ``follow`` mode by an entity moving at ``start_speed`` (its
        magnitude) when the action starts: the speed changes linearly in time so that each
        sample is reached at its time (the speed at the next sample is twice the interval's
        mean minus the speed at its start, never below zero). As in the reference player, a
        car braking along a trajectory whose times describe its deceleration keeps the
        deceleration instead of jumping to the first interval's mean speed."""
        if self.times is None or len(self.times) < 2:
            return self
        times, lengths = self.times, self.lengths
        speeds = [abs(start_speed)]
        for i in range(1, len(times)):
            span = times[i] - times[i - 1]
            mean = (lengths[i] - lengths[i - 1]) / span if span > 0 else 0.0
            speeds.append(max(2.0 * mean - speeds[-1], 0.0) if span > 0 else speeds[-1])
        return dataclasses.replace(self, speeds=tuple(speeds))


def build(
    points: Sequence[tuple[float, float]],
    times: Sequence[float | None],
    headings: Sequence[float] | None = None,
) -> Path:
    """A path through ``points``; headings default to the direction of the incoming segment
    (the first point: of the outgoing one). Repeated points are dropped unless they carry a
    later time (a stop)."""
    xs, ys, hs, ls, ts = [points[0][0]], [points[0][1]], [0.0], [0.0], [times[0]]
    for k in range(1, len(points)):
        x, y = points[k]
        step = math.hypot(x - xs[-1], y - ys[-1])
        if step < 1e-6:
            previous, now = ts[-1], times[k]
            if previous is None or now is None or now <= previous:
                continue
            step = 0.0
        xs.append(x)
        ys.append(y)
        ls.append(ls[-1] + step)
        ts.append(times[k])
        if headings is not None:
            hs.append(headings[k])
        elif step > 0.0:
            hs.append(math.atan2(y - ys[-2], x - xs[-2]))
        else:
            hs.append(hs[-1])
    if headings is not None:
        hs[0] = headings[0]
    elif len(xs) > 1:
        hs[0] = hs[1]
    if len(xs) < 2 or ls[-1] <= 0.0:
        raise ScenarioError("trajectory has fewer than two distinct points", element="Trajectory")
    known = [t for t in ts if t is not None]
    path_times = None
    if len(known) == len(ts):
        path_times = tuple(known)
    return Path(tuple(xs), tuple(ys), tuple(hs), tuple(ls), path_times)
