"""World point -> road coordinates (road, s, t): nearest-road search plus exact refinement.

Every road's reference line is sampled into short segments (with the road's lateral extent at each
sample) once per network. A query measures, for all segments at once with numpy, how far the point
lies outside each road's surface, keeps the best few roads and refines s on their exact reference
lines with Newton steps. Overlapping roads (junction connecting roads) are told apart by a hint
(the road the entity was on) and the entity heading. With a hint the search usually skips the
sampled index entirely: one Newton refinement on the hinted road.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from simtest_operator.opendrive import lanes, planview

SAMPLE_STEP = 2.0
"""Reference-line sampling distance of the search index, metres."""
GRID_CELL = 20.0
"""Cell size of the search grid, metres."""
_CANDIDATE_SLACK = 1.0
_MAX_CANDIDATES = 6
_MAX_SEGMENT_CELLS = 256
"""Grid cells one segment may enter; wider segments (absurdly wide roads) are scanned with every
query instead, so building the grid stays linear in the number of segments."""

_Array = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Projection:
    """A point's exact coordinates relative to one road."""

    road_index: int
    s: float
    t: float
    heading: float
    outside: float
    """How far the point lies outside the road surface (0 when on it), metres."""


class RoadIndex:
    """Sampled segments of every road, for nearest-road search."""

    __slots__ = (
        "_bounds",
        "_ends",
        "_grid",
        "_layouts",
        "_lines",
        "_rolls",
        "_seg",
        "_spans",
        "_wide",
    )

    def __init__(
        self,
        lines: Sequence[planview.ReferenceLine],
        layouts: Sequence[lanes.RoadLayout],
        rolls: Sequence[lanes.Piecewise] = (),
    ) -> None:
        self._lines = lines
        self._layouts = layouts
        self._rolls = rolls
        """Superelevation per road (none: flat): t runs along the banked cross-section."""
        columns: list[list[float]] = [[] for _ in range(8)]
        spans: list[tuple[int, int]] = []
        for road_index, (line, layout) in enumerate(zip(lines, layouts, strict=True)):
            samples = line.sample_s(SAMPLE_STEP)
            points = [line.at(s) for s in samples]
            extents = [_extent(layout, s) for s in samples]
            first = len(columns[0])
            for k in range(len(samples) - 1):
                (x0, y0, _, _), (x1, y1, _, _) = points[k], points[k + 1]
                values = (
                    x0,
                    y0,
                    x1 - x0,
                    y1 - y0,
                    samples[k],
                    float(road_index),
                    min(extents[k][0], extents[k + 1][0]),
                    max(extents[k][1], extents[k + 1][1]),
                )
                for column, value in zip(columns, values, strict=True):
                    column.append(value)
            spans.append((first, len(columns[0])))
        self._seg = np.array(columns, dtype=np.float64).reshape(8, -1)
        self._spans = spans
        nonempty = [(first, last) for first, last in spans if last > first]
        self._ends = [last for _, last in nonempty]
        self._bounds = self._road_bounds()
        self._wide: npt.NDArray[np.intp] = np.zeros(0, dtype=np.intp)
        self._grid = self._build_grid()

    def _road_bounds(self) -> _Array:
        """Per-road axis-aligned box (xmin, ymin, xmax, ymax) grown by the lateral extent."""
        boxes = np.zeros((len(self._spans), 4))
        seg = self._seg
        for road_index, (first, last) in enumerate(self._spans):
            if first == last:
                boxes[road_index] = (np.inf, np.inf, -np.inf, -np.inf)
                continue
            x0, y0 = seg[0, first:last], seg[1, first:last]
            x1, y1 = x0 + seg[2, first:last], y0 + seg[3, first:last]
            grow = float(np.max(np.maximum(np.abs(seg[6, first:last]), np.abs(seg[7, first:last]))))
            boxes[road_index] = (
                min(x0.min(), x1.min()) - grow,
                min(y0.min(), y1.min()) - grow,
                max(x0.max(), x1.max()) + grow,
                max(y0.max(), y1.max()) + grow,
            )
        return boxes

    def _build_grid(self) -> dict[tuple[int, int], npt.NDArray[np.intp]]:
        """Cells of GRID_CELL metres -> segments whose box, grown by the road's lateral extent
        plus the candidate slack, touches the cell."""
        seg = self._seg
        x0, y0 = seg[0], seg[1]
        x1, y1 = x0 + seg[2], y0 + seg[3]
        grow = np.maximum(np.abs(seg[6]), np.abs(seg[7])) + _CANDIDATE_SLACK
        low_x = np.floor((np.minimum(x0, x1) - grow) / GRID_CELL).astype(np.int64)
        high_x = np.floor((np.maximum(x0, x1) + grow) / GRID_CELL).astype(np.int64)
        low_y = np.floor((np.minimum(y0, y1) - grow) / GRID_CELL).astype(np.int64)
        high_y = np.floor((np.maximum(y0, y1) + grow) / GRID_CELL).astype(np.int64)
        cells: dict[tuple[int, int], list[int]] = {}
        wide: list[int] = []
        for k in range(seg.shape[1]):
            if (high_x[k] - low_x[k] + 1) * (high_y[k] - low_y[k] + 1) > _MAX_SEGMENT_CELLS:
                wide.append(k)
                continue
            for i in range(int(low_x[k]), int(high_x[k]) + 1):
                for j in range(int(low_y[k]), int(high_y[k]) + 1):
                    cells.setdefault((i, j), []).append(k)
        self._wide = np.array(wide, dtype=np.intp)
        return {
            cell: np.concatenate((np.array(members, dtype=np.intp), self._wide))
            for cell, members in cells.items()
        }

    def candidates(self, x: float, y: float) -> list[tuple[int, float]]:
        """(road index, approximate s) of the roads nearest to the point, best first."""
        if not self._ends:
            return []
        members = self._grid.get((math.floor(x / GRID_CELL), math.floor(y / GRID_CELL)))
        if members is not None:
            best, found = self._scan(x, y, self._seg[:, members])
            # Segments outside the cell are more than the slack off, so a hit this close is final.
            if best <= _CANDIDATE_SLACK:
                return found
        return self._scan(x, y, self._seg)[1]

    @staticmethod
    def _scan(x: float, y: float, seg: _Array) -> tuple[float, list[tuple[int, float]]]:
        """Best outside distance and the nearest roads among the given segments."""
        dx, dy = seg[2], seg[3]
        rx, ry = x - seg[0], y - seg[1]
        length2 = dx * dx + dy * dy
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.clip(np.where(length2 > 0, (rx * dx + ry * dy) / length2, 0.0), 0.0, 1.0)
        distance = np.hypot(rx - u * dx, ry - u * dy)
        margin = np.where(dx * ry - dy * rx >= 0, np.maximum(seg[7], 0.0), np.maximum(-seg[6], 0.0))
        outside = np.maximum(distance - margin, 0.0)
        order = np.argsort(outside, kind="stable")
        best = float(outside[order[0]])
        limit = best + _CANDIDATE_SLACK
        result: list[tuple[int, float]] = []
        seen: set[int] = set()
        for k in order.tolist():
            if outside[k] > limit or len(result) >= _MAX_CANDIDATES:
                break
            road_index = int(seg[5, k])
            if road_index not in seen:
                seen.add(road_index)
                result.append((road_index, float(seg[4, k] + u[k] * math.sqrt(length2[k]))))
        return best, result

    def nearest_s(self, road_index: int, x: float, y: float) -> float:
        """Approximate s of the point on one road from its sampled segments."""
        first, last = self._spans[road_index]
        seg = self._seg[:, first:last]
        if seg.shape[1] == 0:
            return 0.0
        dx, dy = seg[2], seg[3]
        rx, ry = x - seg[0], y - seg[1]
        length2 = dx * dx + dy * dy
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.clip(np.where(length2 > 0, (rx * dx + ry * dy) / length2, 0.0), 0.0, 1.0)
        distance = np.hypot(rx - u * dx, ry - u * dy)
        k = int(np.argmin(distance))
        return float(seg[4, k] + u[k] * math.sqrt(length2[k]))

    def may_contain(self, road_index: int, x: float, y: float) -> bool:
        xmin, ymin, xmax, ymax = self._bounds[road_index]
        return bool(xmin <= x <= xmax and ymin <= y <= ymax)

    def refine(self, road_index: int, x: float, y: float, s: float) -> Projection:
        """Exact projection onto one road's reference line, starting from ``s``."""
        line = self._lines[road_index]
        length = line.length
        for _ in range(12):
            rx, ry, heading, curvature = line.at(s)
            cos_h, sin_h = math.cos(heading), math.sin(heading)
            along = (x - rx) * cos_h + (y - ry) * sin_h
            lateral = -(x - rx) * sin_h + (y - ry) * cos_h
            denominator = 1.0 - curvature * lateral
            step = along / denominator if denominator > 0.2 else along
            new_s = min(max(s + step, 0.0), length)
            if abs(new_s - s) < 1e-7:
                s = new_s
                break
            s = new_s
        rx, ry, heading, _ = line.at(s)
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        along = (x - rx) * cos_h + (y - ry) * sin_h
        t = -(x - rx) * sin_h + (y - ry) * cos_h
        if road_index < len(self._rolls) and self._rolls[road_index]:
            t /= max(math.cos(self._rolls[road_index].value(s)), 1e-3)
        t_min, t_max = _extent(self._layouts[road_index], s)
        lateral_out = max(t - t_max, t_min - t, 0.0)
        overshoot = abs(along) if (s <= 0.0 and along < 0) or (s >= length and along > 0) else 0.0
        return Projection(
            road_index=road_index,
            s=s,
            t=t,
            heading=heading,
            outside=math.hypot(lateral_out, overshoot if overshoot > 1e-6 else 0.0),
        )


def _extent(layout: lanes.RoadLayout, s: float) -> tuple[float, float]:
    return layout.extent(s)
