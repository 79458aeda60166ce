"""Plots as inline SVG text: stacked verdict bars, trajectory maps and metric timelines.

Hand-written SVG rather than matplotlib: the report must be one self-contained file that opens in
any browser, and a few hundred lines of vector markup per scenario are smaller and crisper than
embedded PNGs. Every function is pure (values in, markup out); labels are escaped here because
the template inserts the markup as-is.
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable, Mapping, Sequence

from simtest_operator.results import details

VERDICT_COLOURS: Mapping[str, str] = {
    "Passed": "#2e9d5b",
    "Failed": "#d33f3f",
    "Timeout": "#8e44ad",
    "Error": "#e67e22",
    "Invalid": "#8d6e63",
    "Skipped": "#9e9e9e",
    "Not run": "#90a4ae",
}
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf",
           "#bcbd22", "#ff7f0e", "#7f7f7f")  # fmt: skip


def _e(text: str) -> str:
    return html.escape(text, quote=True)


def _n(value: float) -> str:
    return f"{value:.1f}".rstrip("0").rstrip(".") if math.isfinite(value) else "0"


def nice_step(span: float, target: int = 5) -> float:
    """A 1/2/5 x 10^k step giving about ``target`` ticks over ``span``."""
    if span <= 0 or not math.isfinite(span):
        return 1.0
    raw = span / target
    magnitude = 10 ** math.floor(math.log10(raw))
    return float(next(m * magnitude for m in (1, 2, 5, 10) if m * magnitude >= raw))


def stacked_bars(rows: Sequence[tuple[str, Mapping[str, int]]], *, width: int = 640) -> str:
    """One horizontal bar per row, split by verdict, with the counts written on the segments."""
    label_w, bar_h, gap = 170, 22, 8
    height = len(rows) * (bar_h + gap) + gap
    longest = max((sum(counts.values()) for _, counts in rows), default=0) or 1
    scale = (width - label_w - 50) / longest
    parts = [
        f'<svg class="bars" role="img" viewBox="0 0 {width} {height}" width="{width}" '
        f'height="{height}"><title>Verdicts per group</title>'
    ]
    for index, (label, counts) in enumerate(rows):
        y = gap + index * (bar_h + gap)
        parts.append(
            f'<text x="{label_w - 8}" y="{y + 15}" text-anchor="end" class="label">'
            f"{_e(label)}</text>"
        )
        x = float(label_w)
        for verdict, colour in VERDICT_COLOURS.items():
            count = counts.get(verdict, 0)
            if not count:
                continue
            w = count * scale
            parts.append(
                f'<rect x="{_n(x)}" y="{y}" width="{_n(w)}" height="{bar_h}" fill="{colour}">'
                f"<title>{_e(label)}: {count} {_e(verdict)}</title></rect>"
            )
            if w >= 18:
                parts.append(
                    f'<text x="{_n(x + w / 2)}" y="{y + 15}" text-anchor="middle" '
                    f'class="count">{count}</text>'
                )
            x += w
        parts.append(
            f'<text x="{_n(x + 6)}" y="{y + 15}" class="label">{sum(counts.values())}</text>'
        )
    parts.append("</svg>")
    return "".join(parts)


def trajectories(paths: Sequence[details.Trajectory], *, width: int = 640) -> str:
    """A top-down map of every entity's path (y up), with start dots, end labels and a legend.

    Axes are equal unless the scene is long and narrow (a highway): then y is stretched so a
    lane change stays visible, and the axis label says by how much.
    """
    drawn = [(index, path) for index, path in enumerate(paths) if path.points]
    if not drawn:
        return ""
    xs = [x for _, path in drawn for _, x, _ in path.points]
    ys = [y for _, path in drawn for _, _, y in path.points]
    left, right, top, bottom = 44, 96, 30, 30
    plot_w = width - left - right
    x_mid, y_mid = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    x_span = max(max(xs) - min(xs), 20.0) * 1.08
    y_span = max(max(ys) - min(ys), 12.0) * 1.15
    scale = plot_w / x_span
    plot_h = y_span * scale
    y_scale, stretch = scale, 1.0
    if plot_h < 120:
        plot_h, y_scale = 120.0, 120.0 / y_span
        stretch = y_scale / scale
    elif plot_h > 380:
        plot_h = 380.0
        scale = y_scale = plot_h / y_span
        x_span = plot_w / scale
    height = round(plot_h + top + bottom)
    x0, y0 = x_mid - x_span / 2, y_mid - y_span / 2

    def sx(x: float) -> float:
        return left + (x - x0) * scale

    def sy(y: float) -> float:
        return top + plot_h - (y - y0) * y_scale

    parts = [
        f'<svg class="trajectories" role="img" viewBox="0 0 {width} {height}" width="{width}" '
        f'height="{height}"><title>Trajectories of {len(drawn)} entities</title>'
    ]
    parts += _grid(x0, x0 + x_span, nice_step(x_span, 6), lambda v: (sx(v), None),
                   top, top + plot_h)  # fmt: skip
    parts += _grid(y0, y0 + y_span, nice_step(y_span, 4), lambda v: (None, sy(v)),
                   left, left + plot_w)  # fmt: skip
    legend_x = float(left)
    labels: list[tuple[float, float, str, str]] = []
    # The ego last, so it is drawn on top of the others.
    for index, path in sorted(drawn, key=lambda item: item[1].is_ego):
        colour = PALETTE[index % len(PALETTE)]
        line = " ".join(f"{_n(sx(x))},{_n(sy(y))}" for _, x, y in path.points)
        t_start, x_start, y_start = path.points[0]
        t_end, x_end, y_end = path.points[-1]
        parts.append(
            f'<g class="entity" data-entity="{_e(path.entity)}">'
            f'<polyline class="path{" ego" if path.is_ego else ""}" fill="none" '
            f'stroke="{colour}" points="{line}"><title>{_e(path.entity)}: t={_n(t_start)} s to '
            f"{_n(t_end)} s</title></polyline>"
            f'<circle cx="{_n(sx(x_start))}" cy="{_n(sy(y_start))}" r="3.5" fill="{colour}"/>'
            "</g>"
        )
        labels.append((sy(y_end), sx(x_end), path.entity, colour))
    for index, path in drawn[:12]:
        colour = PALETTE[index % len(PALETTE)]
        parts.append(
            f'<rect x="{_n(legend_x)}" y="8" width="14" height="4" fill="{colour}"/>'
            f'<text class="legend" x="{_n(legend_x + 18)}" y="14">{_e(path.entity)}</text>'
        )
        legend_x += 30 + 6.5 * len(path.entity)
    previous = -math.inf
    for y, x, name, colour in sorted(labels):
        y = max(y, previous + 12)
        previous = y
        parts.append(f'<text class="entity-label" x="{_n(x + 6)}" y="{_n(y + 4)}" '
                     f'fill="{colour}">{_e(name)}</text>')  # fmt: skip
    y_label = f"y [m] (stretched &#215;{stretch:.3g})" if stretch > 1.05 else "y [m]"
    parts.append(f'<text class="tick" x="{left + plot_w}" y="{height - 4}" text-anchor="end">'
                 f'x [m]</text><text class="tick" x="4" y="{top - 4}">{y_label}</text>'
                 "</svg>")  # fmt: skip
    return "".join(parts)


def _grid(
    low: float,
    high: float,
    step: float,
    place: Callable[[float], tuple[float | None, float | None]],
    start: float,
    end: float,
) -> list[str]:
    """Grid lines with tick labels every ``step`` between ``low`` and ``high``."""
    lines = []
    value = math.ceil(low / step) * step
    while value <= high:
        x, y = place(value)
        if x is not None:
            lines.append(f'<line class="grid" x1="{_n(x)}" y1="{_n(start)}" x2="{_n(x)}" '
                         f'y2="{_n(end)}"/><text class="tick" x="{_n(x)}" y="{_n(end + 13)}" '
                         f'text-anchor="middle">{_n(value)}</text>')  # fmt: skip
        elif y is not None:
            lines.append(f'<line class="grid" x1="{_n(start)}" y1="{_n(y)}" x2="{_n(end)}" '
                         f'y2="{_n(y)}"/><text class="tick" x="{_n(start - 4)}" y="{_n(y + 4)}" '
                         f'text-anchor="end">{_n(value)}</text>')  # fmt: skip
        value += step
    return lines


def timeline(series: details.Timeline, *, width: int = 640, height: int = 150) -> str:
    """A line chart of one metric over simulated time; gaps where the value is not finite."""
    finite = [(t, v) for t, v in series.points if math.isfinite(v)]
    if not finite:
        return ""
    t0, t1 = min(t for t, _ in series.points), max(t for t, _ in series.points)
    v0, v1 = min(v for _, v in finite), max(v for _, v in finite)
    if v1 - v0 < 1e-9:
        v0, v1 = v0 - 1, v1 + 1
    left, right, top, bottom = 48, 12, 18, 24

    def sx(t: float) -> float:
        return left + (t - t0) / max(t1 - t0, 1e-9) * (width - left - right)

    def sy(v: float) -> float:
        return height - bottom - (v - v0) / (v1 - v0) * (height - top - bottom)

    segments: list[list[str]] = [[]]
    for t, v in series.points:
        if math.isfinite(v):
            segments[-1].append(f"{_n(sx(t))},{_n(sy(v))}")
        elif segments[-1]:
            segments.append([])
    label = f"{series.name} [{series.unit}]" if series.unit else series.name
    parts = [
        f'<svg class="timeline" role="img" viewBox="0 0 {width} {height}" width="{width}" '
        f'height="{height}"><title>{_e(label)} over time</title>'
        f'<text class="label" x="{left}" y="12">{_e(label)}</text>'
        f'<line class="axis" x1="{left}" y1="{height - bottom}" x2="{width - right}" '
        f'y2="{height - bottom}"/><line class="axis" x1="{left}" y1="{top}" x2="{left}" '
        f'y2="{height - bottom}"/>'
        f'<text class="tick" x="{left - 4}" y="{_n(sy(v1) + 4)}" text-anchor="end">{v1:.3g}</text>'
        f'<text class="tick" x="{left - 4}" y="{_n(sy(v0) + 4)}" text-anchor="end">{v0:.3g}</text>'
        f'<text class="tick" x="{left}" y="{height - 6}">{_n(t0)} s</text>'
        f'<text class="tick" x="{width - right}" y="{height - 6}" text-anchor="end">'
        f"{_n(t1)} s</text>"
    ]
    parts += [
        f'<polyline class="series" fill="none" points="{" ".join(segment)}"/>'
        for segment in segments
        if segment
    ]
    parts.append("</svg>")
    return "".join(parts)
