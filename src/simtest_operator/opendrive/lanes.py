"""Lateral road layout: lane offset, lane sections and lane t-bounds at a road's ``s``.

OpenDRIVE describes lanes by widths stacked outwards from the centre lane, which itself is shifted
by the road's laneOffset. This module turns that into lateral coordinates: for a lane at some s,
its inner and outer border t (positive to the left of the reference line) and their slopes dt/ds
(needed for the lane's heading where widths change).
"""

from __future__ import annotations

import bisect
import dataclasses

from simtest_operator.opendrive import models


class Piecewise:
    """A sequence of cubic records, each valid from its ``s`` to the next one's."""

    __slots__ = ("_records", "_starts")

    def __init__(self, records: tuple[models.Poly3, ...]) -> None:
        self._records = records
        self._starts = [record.s for record in records]

    def __bool__(self) -> bool:
        return bool(self._records)

    def _record(self, s: float) -> models.Poly3 | None:
        if not self._records:
            return None
        return self._records[max(bisect.bisect_right(self._starts, s) - 1, 0)]

    def value(self, s: float) -> float:
        record = self._record(s)
        return record.value(s) if record is not None else 0.0

    def value_slope(self, s: float) -> tuple[float, float]:
        records = self._records
        if not records:
            return (0.0, 0.0)
        record = (
            records[0]
            if len(records) == 1
            else records[max(bisect.bisect_right(self._starts, s) - 1, 0)]
        )
        ds = s - record.s
        return (
            record.a + ds * (record.b + ds * (record.c + ds * record.d)),
            record.b + ds * (2.0 * record.c + ds * 3.0 * record.d),
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneBounds:
    """A lane's lateral extent at one s: ``t_inner`` is the border towards the centre lane."""

    lane_id: int
    type: str
    t_inner: float
    t_outer: float
    slope_inner: float
    slope_outer: float

    @property
    def width(self) -> float:
        return abs(self.t_outer - self.t_inner)

    @property
    def t_center(self) -> float:
        return 0.5 * (self.t_inner + self.t_outer)

    @property
    def slope_center(self) -> float:
        return 0.5 * (self.slope_inner + self.slope_outer)

    @property
    def t_min(self) -> float:
        return min(self.t_inner, self.t_outer)

    @property
    def t_max(self) -> float:
        return max(self.t_inner, self.t_outer)


_Edge = tuple[float, float, float, float]
"""Inner t, outer t, inner slope, outer slope of one lane."""


class _SideLanes:
    """One side (left or right) of a lane section, lanes ordered from the centre outwards."""

    __slots__ = ("_borders", "_by_border", "_ids", "_sign", "_types", "_widths", "position")

    def __init__(self, lanes: tuple[models.Lane, ...], sign: int) -> None:
        self._sign = sign
        self._ids = [lane.id for lane in lanes]
        self._types = [lane.type for lane in lanes]
        self._widths = [Piecewise(lane.widths) for lane in lanes]
        self._borders = [Piecewise(lane.borders) for lane in lanes]
        self._by_border = any(not lane.widths and lane.borders for lane in lanes)
        self.position = {lane.id: index for index, lane in enumerate(lanes)}

    @property
    def ids(self) -> list[int]:
        return self._ids

    def _outer(
        self,
        index: int,
        ds: float,
        inner: float,
        inner_slope: float,
        offset: float,
        offset_slope: float,
    ) -> tuple[float, float]:
        widths = self._widths[index]
        sign = self._sign
        if widths or not self._borders[index]:
            width, slope = widths.value_slope(ds)
            return inner + sign * width, inner_slope + sign * slope
        border, border_slope = self._borders[index].value_slope(ds)
        return (
            offset + sign * abs(border),
            offset_slope + (sign if border >= 0 else -sign) * border_slope,
        )

    def outermost(self, ds: float, offset: float) -> float:
        """t of the side's outer edge."""
        if self._by_border:
            inner = offset
            for index in range(len(self._ids)):
                inner = self._outer(index, ds, inner, 0.0, offset, 0.0)[0]
            return inner
        total = 0.0
        for widths in self._widths:
            total += widths.value_slope(ds)[0]
        return offset + self._sign * total

    def edges(self, ds: float, offset: float, offset_slope: float, count: int) -> list[_Edge]:
        """Edges of the first ``count`` lanes from the centre outwards."""
        result: list[_Edge] = []
        inner, inner_slope = offset, offset_slope
        for index in range(min(count, len(self._ids))):
            outer, outer_slope = self._outer(index, ds, inner, inner_slope, offset, offset_slope)
            result.append((inner, outer, inner_slope, outer_slope))
            inner, inner_slope = outer, outer_slope
        return result

    def bounds(self, index: int, edge: _Edge) -> LaneBounds:
        return LaneBounds(
            lane_id=self._ids[index],
            type=self._types[index],
            t_inner=edge[0],
            t_outer=edge[1],
            slope_inner=edge[2],
            slope_outer=edge[3],
        )

    def all_bounds(self, ds: float, offset: float, offset_slope: float) -> list[LaneBounds]:
        edges = self.edges(ds, offset, offset_slope, len(self._ids))
        return [self.bounds(index, edge) for index, edge in enumerate(edges)]

    def find(self, ds: float, offset: float, t: float) -> tuple[LaneBounds | None, float]:
        """The lane containing ``t`` (or None) and the side's outermost t."""
        inner = offset
        sign = self._sign
        for index in range(len(self._ids)):
            outer, _ = self._outer(index, ds, inner, 0.0, offset, 0.0)
            if (inner <= t <= outer if sign > 0 else outer <= t <= inner) and outer != inner:
                edges = self.edges(ds, offset, 0.0, index + 1)
                return self.bounds(index, edges[-1]), outer
            inner = outer
        return None, inner


class SectionLayout:
    """Lane geometry of one lane section."""

    __slots__ = ("_left", "_right", "ids", "s", "section")

    def __init__(self, section: models.LaneSection) -> None:
        self.section = section
        self.s = section.s
        self._left = _SideLanes(section.left, 1)
        self._right = _SideLanes(section.right, -1)
        self.ids = frozenset(self._left.ids) | frozenset(self._right.ids)

    def lane_bounds(
        self, s: float, lane_id: int, offset: float, offset_slope: float
    ) -> LaneBounds | None:
        side = self._left if lane_id > 0 else self._right
        index = side.position.get(lane_id)
        if index is None:
            return None
        return side.bounds(index, side.edges(s - self.s, offset, offset_slope, index + 1)[-1])

    def all_bounds(self, s: float, offset: float, offset_slope: float) -> list[LaneBounds]:
        """Every lane's bounds, left outermost first, then right lanes outwards."""
        ds = s - self.s
        left = self._left.all_bounds(ds, offset, offset_slope)
        right = self._right.all_bounds(ds, offset, offset_slope)
        return [*reversed(left), *right]

    def extent(self, s: float, offset: float) -> tuple[float, float]:
        """Outermost right and left t of all lanes."""
        ds = s - self.s
        right = self._right.outermost(ds, offset)
        left = self._left.outermost(ds, offset)
        return min(right, left, offset), max(right, left, offset)

    def lane_at(self, s: float, t: float, offset: float) -> LaneBounds | None:
        ds = s - self.s
        side = self._left if t > offset else self._right
        found, _ = side.find(ds, offset, t)
        if found is None and t == offset:
            found, _ = self._left.find(ds, offset, t)
        return found


class RoadLayout:
    """Lane offset and sections of one road."""

    __slots__ = ("_offset", "_starts", "sections")

    def __init__(self, road: models.Road) -> None:
        self._offset = Piecewise(road.lane_offsets)
        self.sections = [SectionLayout(section) for section in road.lane_sections]
        self._starts = [section.s for section in road.lane_sections]

    def section_index(self, s: float) -> int:
        return max(bisect.bisect_right(self._starts, s) - 1, 0)

    def section_at(self, s: float) -> SectionLayout:
        return self.sections[self.section_index(s)]

    def offset(self, s: float) -> tuple[float, float]:
        """The centre lane's t and dt/ds at ``s``."""
        return self._offset.value_slope(s)

    def lane_bounds(self, s: float, lane_id: int) -> LaneBounds | None:
        offset, slope = self._offset.value_slope(s)
        return self.section_at(s).lane_bounds(s, lane_id, offset, slope)

    def all_bounds(self, s: float) -> list[LaneBounds]:
        offset, slope = self._offset.value_slope(s)
        return self.section_at(s).all_bounds(s, offset, slope)

    def lane_at(self, s: float, t: float) -> LaneBounds | None:
        """The lane whose lateral extent contains ``t`` (None if outside every lane)."""
        return self.section_at(s).lane_at(s, t, self._offset.value_slope(s)[0])

    def extent(self, s: float) -> tuple[float, float]:
        """Lateral extent (t_min, t_max) of all lanes at ``s``; the reference line at least."""
        return self.section_at(s).extent(s, self._offset.value_slope(s)[0])
