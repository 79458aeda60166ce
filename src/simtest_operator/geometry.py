"""Planar geometry between entities: oriented boxes, gaps, time to collision, time headway.

The simulator's conditions (Collision, Distance, TimeHeadway, TimeToCollision) and the online
evaluation (collision, min TTC, min THW, min distance) must agree on what "touching" and "gap"
mean, so both call these functions; likewise the evidence check and the simulation's declared
traffic jumps agree on which displacement velocities explain (:func:`unexplained_displacement`).
Everything is 2-D (x, y, heading) on the ground plane and works on
:class:`~simtest_operator.snapshots.EntityState` values; pure functions, no state.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from simtest_operator.snapshots import EntityState

Point = tuple[float, float]

INFINITE = math.inf
"""Returned for a TTC or headway that does not exist (not closing in, standing still)."""


def wrap_angle(angle: float) -> float:
    """``angle`` mapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def to_local(x: float, y: float, heading: float, px: float, py: float) -> Point:
    """World point (px, py) in the frame at (x, y) rotated by ``heading``."""
    dx, dy = px - x, py - y
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    return (dx * cos_h + dy * sin_h, -dx * sin_h + dy * cos_h)


def box_corners(state: EntityState) -> tuple[Point, Point, Point, Point]:
    """The four ground corners of ``state``'s box, counter-clockwise from front-left."""
    cx, cy, _ = state.box_center()
    half_l, half_w = state.box.length / 2.0, state.box.width / 2.0
    cos_h, sin_h = math.cos(state.heading), math.sin(state.heading)
    lx, ly = half_l * cos_h, half_l * sin_h
    wx, wy = -half_w * sin_h, half_w * cos_h
    return (
        (cx + lx + wx, cy + ly + wy),
        (cx - lx + wx, cy - ly + wy),
        (cx - lx - wx, cy - ly - wy),
        (cx + lx - wx, cy + ly - wy),
    )


def _project(corners: Sequence[Point], ax: float, ay: float) -> tuple[float, float]:
    values = [px * ax + py * ay for px, py in corners]
    return min(values), max(values)


def boxes_overlap(a: EntityState, b: EntityState) -> bool:
    """True when the two oriented boxes touch or overlap (separating-axis test)."""
    ca, cb = box_corners(a), box_corners(b)
    for heading in (a.heading, b.heading):
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        for ax, ay in ((cos_h, sin_h), (-sin_h, cos_h)):
            min_a, max_a = _project(ca, ax, ay)
            min_b, max_b = _project(cb, ax, ay)
            if max_a < min_b or max_b < min_a:
                return False
    return True


def _point_segment_distance(p: Point, s0: Point, s1: Point) -> float:
    sx, sy = s1[0] - s0[0], s1[1] - s0[1]
    length2 = sx * sx + sy * sy
    t = 0.0 if length2 == 0.0 else ((p[0] - s0[0]) * sx + (p[1] - s0[1]) * sy) / length2
    t = min(1.0, max(0.0, t))
    return math.hypot(p[0] - (s0[0] + t * sx), p[1] - (s0[1] + t * sy))


def box_distance(a: EntityState, b: EntityState) -> float:
    """Smallest distance between the two boxes (free space); 0 when they overlap."""
    if boxes_overlap(a, b):
        return 0.0
    ca, cb = box_corners(a), box_corners(b)
    best = INFINITE
    for corners, others in ((ca, cb), (cb, ca)):
        for p in corners:
            for i in range(4):
                best = min(best, _point_segment_distance(p, others[i], others[(i + 1) % 4]))
    return best


def reference_distance(a: EntityState, b: EntityState) -> float:
    """Euclidean distance between the two reference points."""
    return math.hypot(b.x - a.x, b.y - a.y)


def extent_along(state: EntityState, ax: float, ay: float) -> tuple[float, float]:
    """Interval of ``state``'s box projected on the unit axis (ax, ay), in world units."""
    return _project(box_corners(state), ax, ay)


def longitudinal_gap(a: EntityState, b: EntityState, *, freespace: bool) -> float:
    """Signed distance from ``a`` to ``b`` along ``a``'s heading (positive: ``b`` ahead).

    With ``freespace`` it is the gap between the box extents (0 when they overlap along the axis),
    otherwise the distance between reference points.
    """
    return _gap_along(a, b, math.cos(a.heading), math.sin(a.heading), freespace=freespace)


def lateral_gap(a: EntityState, b: EntityState, *, freespace: bool) -> float:
    """Signed distance from ``a`` to ``b`` across ``a``'s heading (positive: ``b`` to the left)."""
    return _gap_along(a, b, -math.sin(a.heading), math.cos(a.heading), freespace=freespace)


def _gap_along(a: EntityState, b: EntityState, ax: float, ay: float, *, freespace: bool) -> float:
    """Signed gap from ``a`` to ``b`` along the unit axis (ax, ay): box extents or centres."""
    if not freespace:
        return (b.x - a.x) * ax + (b.y - a.y) * ay
    min_a, max_a = extent_along(a, ax, ay)
    min_b, max_b = extent_along(b, ax, ay)
    if min_b >= max_a:
        return min_b - max_a
    if max_b <= min_a:
        return max_b - min_a
    return 0.0


def in_path(ego: EntityState, other: EntityState, *, margin: float = 0.0) -> bool:
    """True when ``other``'s box overlaps the corridor ``ego`` sweeps when driving straight on."""
    ax, ay = -math.sin(ego.heading), math.cos(ego.heading)
    min_e, max_e = extent_along(ego, ax, ay)
    min_o, max_o = extent_along(other, ax, ay)
    return min_o < max_e + margin and max_o > min_e - margin


def gap_ahead(ego: EntityState, other: EntityState) -> float | None:
    """Free-space gap from ``ego``'s front to ``other`` when ``other`` is ahead in ``ego``'s
    driving corridor (0 when touching), else None. One pass over both boxes' corners."""
    cos_h, sin_h = math.cos(ego.heading), math.sin(ego.heading)
    ego_corners, other_corners = box_corners(ego), box_corners(other)
    ego_lat = [-px * sin_h + py * cos_h for px, py in ego_corners]
    other_lat = [-px * sin_h + py * cos_h for px, py in other_corners]
    if not (min(other_lat) < max(ego_lat) and max(other_lat) > min(ego_lat)):
        return None
    ego_lon = [px * cos_h + py * sin_h for px, py in ego_corners]
    other_lon = [px * cos_h + py * sin_h for px, py in other_corners]
    ahead = (other.x - ego.x) * cos_h + (other.y - ego.y) * sin_h
    gap = min(other_lon) - max(ego_lon)
    if gap <= 0.0 and ahead <= 0.0:
        return None
    if max(other_lon) <= min(ego_lon):
        return None
    return max(gap, 0.0)


def time_to_collision(ego: EntityState, other: EntityState) -> float:
    """Classic in-path TTC of ``ego`` to ``other``: free-space gap ahead / closing speed.

    ``other`` counts only when it is ahead and inside ``ego``'s driving corridor; otherwise, or when
    the gap is not closing, the TTC is infinite.
    """
    gap = gap_ahead(ego, other)
    if gap is None:
        return INFINITE
    ax, ay = math.cos(ego.heading), math.sin(ego.heading)
    evx, evy = ego.velocity()
    ovx, ovy = other.velocity()
    closing = (evx - ovx) * ax + (evy - ovy) * ay
    return gap / closing if closing > 0.0 else INFINITE


def time_headway(ego: EntityState, other: EntityState) -> float:
    """In-path time headway of ``ego`` behind ``other``: free-space gap / ego speed."""
    gap = gap_ahead(ego, other)
    if gap is None or ego.speed <= 0.0:
        return INFINITE
    return gap / ego.speed


def unexplained_displacement(
    dt: npt.NDArray[np.float64],
    dx: npt.NDArray[np.float64],
    dy: npt.NDArray[np.float64],
    vx: npt.NDArray[np.float64],
    vy: npt.NDArray[np.float64],
) -> npt.NDArray[np.float64]:
    """Per frame interval, how far (m) the displacement lies from every one the recorded
    velocities explain: a mean velocity between the two frames' (the segment from ``v0 dt`` to
    ``v1 dt``; the trapezoid rule is its midpoint). A speed that steps within a frame interval
    (a ``step`` SpeedAction, a start from rest) is explained; a teleport or a box swinging round
    its reference point is not."""
    ex, ey = dx - vx[:-1] * dt, dy - vy[:-1] * dt
    wx, wy = (vx[1:] - vx[:-1]) * dt, (vy[1:] - vy[:-1]) * dt
    span = wx * wx + wy * wy
    share = np.divide(ex * wx + ey * wy, span, out=np.zeros_like(span), where=span > 0.0)
    share = np.clip(share, 0.0, 1.0)
    return np.asarray(np.hypot(ex - share * wx, ey - share * wy), dtype=np.float64)
