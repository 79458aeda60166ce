"""Bounds on the numbers of an untrusted OpenDRIVE file, so that the work per element is bounded.

Geometry evaluation, lane layout and the search index cost time in proportion to a road's length,
a spiral's total turn and a road's lateral extent; a file that sets any of them absurdly high (or
to NaN/inf) would hang or exhaust a simulator instead of being refused. Every limit is one to two
orders of magnitude above what real maps use (CARLA Town01-10HD and the esmini corpus: roads up to
3 km, 10.8 km per map, |curvature| <= 1 /m, spirals turning <= 5 rad, lanes up to 50 m wide,
coordinates within 1.5 km, 277 roads, 15 lanes per section; geo-referenced maps reach UTM
northings of ~1e7 m).
"""

from __future__ import annotations

import dataclasses
import math

from simtest_operator.opendrive import models


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Limits:
    """What one OpenDRIVE document may contain; the defaults fit a simulator pod's 1 GiB."""

    max_bytes: int = 128 * 1024 * 1024
    """Largest accepted file (128 MiB): streamed parsing peaks at about 3x the file size."""
    max_length: float = 100_000.0
    """One road or geometry element, metres (100 km)."""
    max_total_length: float = 500_000.0
    """All roads together, metres (500 km): bounds the search index, one segment per 2 m (1000 km
    of roads in a 5 KB file cost 2.4 s and 304 MB to index)."""
    max_coordinate: float = 1.0e8
    """|x|, |y| of any geometry point, metres."""
    max_curvature: float = 1_000.0
    """|curvature| of arcs and spirals, 1/m (a 1 mm radius)."""
    max_spiral_turn: float = 64.0
    """Total heading change of one spiral, radians (about 10 full turns); bounds its quadrature."""
    max_roads: int = 50_000
    """Roads per document: each adds at least one search-index segment, whatever its length."""
    max_lanes: int = 100
    """Lanes per side of a lane section: lane queries walk them on every simulation step."""
    max_total_lanes: int = 20_000
    """Lanes of all lane sections together (CARLA's largest town: 1,052). SUMO holds about
    10 KB per lane: 84,000 lanes (21,000 roads) took a run to 1.1 GB, above a simulator pod's
    1 GiB memory request (issue 29); at this limit a run stays near 600 MB."""
    max_signals: int = 50_000
    """Signals and signal references per document (CARLA's towns: at most 180): each becomes
    stop lines the evaluation checks on every step."""
    max_lane_width: float = 1_000.0
    """Width of one lane (or |border|, |laneOffset|) anywhere along its record, metres."""
    min_road_length: float = 0.001
    """Shortest road, metres (1 mm): a zero-length road holds no position."""
    min_road_width: float = 0.01
    """Widest lane of a road must reach this, metres (1 cm): a road whose lanes are all zero
    width has no surface, and netconvert drops it ("No edges loaded")."""
    max_plan_view_gap: float = 1.0
    """Largest stretch of a road's reference line without a geometry, metres (real maps: 1e-13
    of rounding; a zero-length element followed by a jump leaves no line to place entities on)."""


DEFAULT = Limits()


def spiral_turn(curv_start: float, curv_end: float, length: float) -> float:
    """Upper bound of a spiral's heading change: the quantity that sets its quadrature cost."""
    return abs(curv_start) * length + 0.5 * abs(curv_end - curv_start) * length


def cubic_peak(poly: models.Poly3, span: float) -> float:
    """max |a + b x + c x^2 + d x^3| for 0 <= x <= span (ends and interior extrema)."""
    points = [0.0, max(span, 0.0)]
    a3, b2, c1 = 3.0 * poly.d, 2.0 * poly.c, poly.b
    if a3 != 0.0:
        discriminant = b2 * b2 - 4.0 * a3 * c1
        if discriminant >= 0.0:
            root = math.sqrt(discriminant)
            points += [(-b2 + root) / (2.0 * a3), (-b2 - root) / (2.0 * a3)]
    elif b2 != 0.0:
        points.append(-c1 / b2)
    start = poly.s
    return max(abs(poly.value(start + x)) for x in points if 0.0 <= x <= points[1])


def widest(lane: models.Lane, span: float) -> float:
    """A lane's greatest width over a lane section of length ``span`` (inf for border lanes)."""
    if lane.borders and not lane.widths:
        return math.inf
    parts = spans([poly.s for poly in lane.widths], span)
    return max(
        (cubic_peak(poly, part) for poly, part in zip(lane.widths, parts, strict=True)),
        default=0.0,
    )


def spans(starts: list[float], end: float) -> list[float]:
    """Length of each record of a piecewise sequence (``starts`` sorted) up to ``end``."""
    ends = [*starts[1:], end][: len(starts)]
    return [max(stop - start, 0.0) for start, stop in zip(starts, ends, strict=True)]
