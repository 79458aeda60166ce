"""Vectorised planar geometry for offline evaluation: boxes, distances, paths.

The online evaluator works one snapshot at a time (``simtest_operator.geometry``); re-evaluating a
recording sees all frames at once, so the same questions are answered here for whole arrays.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


def corners(x: Array, y: Array, yaw: Array, length: float, width: float) -> Array:
    """Box corners, shape (n, 4, 2), counter-clockwise, for boxes centred at (x, y)."""
    c, s = np.cos(yaw), np.sin(yaw)
    hl, hw = length / 2.0, width / 2.0
    local = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
    out = np.empty((len(x), 4, 2))
    out[:, :, 0] = x[:, None] + local[None, :, 0] * c[:, None] - local[None, :, 1] * s[:, None]
    out[:, :, 1] = y[:, None] + local[None, :, 0] * s[:, None] + local[None, :, 1] * c[:, None]
    return out


def _point_segment_distances(points: Array, boxes: Array) -> Array:
    """Min distance of each of the (n, 4) points to the (n, 4) edges of ``boxes``: shape (n,)."""
    a = boxes[:, None, :, :]  # (n, 1, 4, 2) edge starts
    b = np.roll(boxes, -1, axis=1)[:, None, :, :]
    p = points[:, :, None, :]  # (n, 4, 1, 2)
    ab = b - a
    t = np.clip(
        np.sum((p - a) * ab, axis=-1) / np.maximum(np.sum(ab * ab, axis=-1), 1e-12), 0.0, 1.0
    )
    closest = a + t[..., None] * ab
    distances: Array = np.sqrt(np.sum((p - closest) ** 2, axis=-1)).min(axis=(1, 2))
    return distances


def overlaps(first: Array, second: Array) -> npt.NDArray[np.bool_]:
    """Separating-axis test per row: True where the two boxes intersect."""
    separated = np.zeros(len(first), dtype=bool)
    for box in (first, second):
        for k in range(2):
            edge = box[:, k + 1] - box[:, k]
            axis = np.stack([-edge[:, 1], edge[:, 0]], axis=1)
            pa = np.einsum("nij,nj->ni", first, axis)
            pb = np.einsum("nij,nj->ni", second, axis)
            separated |= (pa.max(axis=1) < pb.min(axis=1)) | (pb.max(axis=1) < pa.min(axis=1))
    return ~separated


def box_distance(first: Array, second: Array) -> Array:
    """Distance between two boxes per row (0 where they touch or overlap)."""
    distance = np.minimum(
        _point_segment_distances(first, second), _point_segment_distances(second, first)
    )
    distance[overlaps(first, second)] = 0.0
    return distance


@dataclasses.dataclass(frozen=True, slots=True)
class Path:
    """A polyline with arc length, extended far beyond both ends along its end headings, so that
    objects ahead of where the path ends (or behind its start) still project onto it."""

    start: Array
    """(k, 2) segment starts."""
    delta: Array
    """(k, 2) segment vectors."""
    s0: Array
    """(k,) arc length at each segment start."""
    offset: float
    """Arc length of the first real point (the backward extension's length)."""
    trusted_end: float
    """Arc length up to which a projection means something: the driven path, plus as much of the
    straight forward extension as the path's end curvature allows (it drifts off a curved road
    by curvature * length^2 / 2; half a metre is the limit)."""

    @classmethod
    def of(cls, x: Array, y: Array, yaw: Array, *, extension: float = 1000.0) -> Path:
        keep = np.ones(len(x), dtype=bool)
        keep[1:] = np.hypot(np.diff(x), np.diff(y)) > 1e-6
        px, py = x[keep], y[keep]
        head, tail = yaw[0], yaw[-1]
        if len(px) >= 2:
            head = float(np.arctan2(py[1] - py[0], px[1] - px[0]))
            tail = float(np.arctan2(py[-1] - py[-2], px[-1] - px[-2]))
        points = np.concatenate(
            [
                [[px[0] - extension * np.cos(head), py[0] - extension * np.sin(head)]],
                np.stack([px, py], axis=1),
                [[px[-1] + extension * np.cos(tail), py[-1] + extension * np.sin(tail)]],
            ]
        )
        delta = np.diff(points, axis=0)
        lengths = np.hypot(delta[:, 0], delta[:, 1])
        s0 = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        driven = float(np.sum(lengths[1:-1]))
        return cls(
            start=points[:-1],
            delta=delta,
            s0=s0,
            offset=extension,
            trusted_end=extension + driven + _straight_reach(px, py, extension),
        )

    def project(self, x: Array, y: Array) -> tuple[Array, Array, Array]:
        """(arc length, signed lateral offset -- left positive --, tangent angle) per point.

        The nearest vertex is found for all points at once; the exact projection is then made
        on its two adjacent segments only (the path's points are close together, so the
        closest segment touches the closest vertex; the long extensions touch the end points).
        """
        vx = np.append(self.start[:, 0], self.start[-1, 0] + self.delta[-1, 0])
        vy = np.append(self.start[:, 1], self.start[-1, 1] + self.delta[-1, 1])
        ddx = x[:, None] - vx[None, :]
        ddy = y[:, None] - vy[None, :]
        nearest = np.argmin(ddx * ddx + ddy * ddy, axis=1)
        last = len(self.delta) - 1
        candidates = np.stack([np.clip(nearest - 1, 0, last), np.clip(nearest, 0, last)], axis=1)
        sx, sy = self.start[candidates, 0], self.start[candidates, 1]
        dx, dy = self.delta[candidates, 0], self.delta[candidates, 1]
        px, py = x[:, None] - sx, y[:, None] - sy
        length2 = np.maximum(dx * dx + dy * dy, 1e-12)
        t = np.clip((px * dx + py * dy) / length2, 0.0, 1.0)
        ex, ey = px - t * dx, py - t * dy
        pick = np.argmin(ex * ex + ey * ey, axis=1)
        rows = np.arange(len(x))
        best = candidates[rows, pick]
        tb = t[rows, pick]
        seg_dx, seg_dy = self.delta[best, 0], self.delta[best, 1]
        seg_len = np.hypot(seg_dx, seg_dy)
        s = self.s0[best] + tb * seg_len
        cross = seg_dx * py[rows, pick] - seg_dy * px[rows, pick]
        lateral = cross / np.maximum(seg_len, 1e-12)
        return s, lateral, np.arctan2(seg_dy, seg_dx)

    def arc_of_vertices(self, x: Array, y: Array) -> Array:
        """Arc length of the path's own points, in the order given (those it was built from)."""
        steps = np.hypot(np.diff(x), np.diff(y))
        return np.concatenate([[self.offset], self.offset + np.cumsum(steps)])


def _straight_reach(x: Array, y: Array, limit: float, *, window: float = 30.0) -> float:
    """How far a straight continuation of the path's end stays within 0.5 m of a circle with
    the curvature of its last ``window`` metres."""
    if len(x) < 3:
        return 0.0
    steps = np.hypot(np.diff(x), np.diff(y))
    back = np.cumsum(steps[::-1])
    count = int(np.searchsorted(back, window)) + 1
    count = min(count, len(steps))
    headings = np.unwrap(np.arctan2(np.diff(y), np.diff(x)))[-count:]
    length = float(np.sum(steps[-count:]))
    if count < 2 or length < 1.0:
        return 0.0
    curvature = abs(float(headings[-1] - headings[0])) / length
    return limit if curvature < 1e-9 else min(limit, 1.0 / math.sqrt(curvature))


def wrap(angle: Array) -> Array:
    """Angles into [-pi, pi)."""
    wrapped: Array = (angle + np.pi) % (2.0 * np.pi) - np.pi
    return wrapped
