"""Pass/fail per parameter pair with the estimated boundary, as PNG images for report and UI.

Each plot is one pair of dimensions: every judged run as a dot coloured by its verdict, and the
boundary classifier's 0.5 contour on the slice through the other dimensions at the centre of the
largest failure region (the middle of the space without failures) -- the slice where a reader
most wants to see the boundary. Figures are built without pyplot's global state.
"""

from __future__ import annotations

import io
import itertools

import numpy as np

from simtest_operator.results.plots import VERDICT_COLOURS
from simtest_operator.search import analysis
from simtest_operator.search.analysis import Records, SearchSummary
from simtest_operator.search.spaces import SearchSpace

RESOLUTION = 80
"""Mesh cells per axis of the boundary contour."""


def plot_pairs(
    space: SearchSpace, records: Records, summary: SearchSummary
) -> list[tuple[str, str, bytes]]:
    """``(x parameter, y parameter, PNG)`` for every pair of dimensions (one plot for a single
    dimension, against nothing)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    boundary = analysis.fit_boundary(space, records)
    judged = [(p, o) for p, o in records if o.judged]
    points = space.encode_all([p.values for p, _ in judged])
    colours = [VERDICT_COLOURS.get(o.verdict.value, "#000000") for _, o in judged]
    if summary.regions:
        anchor = np.array(space.encode(summary.regions[0].centre))
    else:
        anchor = np.full(space.size, 0.5)
    pairs = list(itertools.combinations(range(space.size), 2)) or [(0, 0)]
    plots = []
    for i, j in pairs:
        figure = Figure(figsize=(4.2, 3.6), dpi=100)
        axes = figure.add_subplot()
        xs = points[:, i]
        ys = points[:, j] if i != j else np.zeros(len(points))
        axes.scatter(xs, ys, c=colours, s=12, linewidths=0)
        if boundary is not None and boundary.model is not None and i != j:
            grid = np.linspace(0.0, 1.0, RESOLUTION)
            gx, gy = np.meshgrid(grid, grid)
            mesh = np.tile(anchor, (gx.size, 1))
            mesh[:, i], mesh[:, j] = gx.ravel(), gy.ravel()
            probability = boundary.failure_probability(mesh).reshape(gx.shape)
            if probability.min() < 0.5 < probability.max():
                axes.contour(gx, gy, probability, levels=[0.5], colors="#333333")
        axes.set_xlabel(space.names[i])
        axes.set_xticks(*_ticks(space, i))
        if i != j:
            axes.set_ylabel(space.names[j])
            axes.set_yticks(*_ticks(space, j))
        else:
            axes.set_yticks([])
        axes.set_xlim(-0.03, 1.03)
        axes.set_ylim(-0.03, 1.03)
        axes.set_title(f"{summary.failures} failures / {summary.runs} runs", fontsize=9)
        figure.tight_layout()
        buffer = io.BytesIO()
        FigureCanvasAgg(figure)
        figure.savefig(buffer, format="png")
        plots.append((space.names[i], space.names[j], buffer.getvalue()))
    return plots


def _ticks(space: SearchSpace, axis: int) -> tuple[list[float], list[str]]:
    """Tick positions in the unit cube and their labels in parameter values."""
    dimension = space.dimensions[axis]
    if dimension.choices is not None:
        ticks = [dimension.encode(c) for c in dimension.choices]
    else:
        ticks = [float(t) for t in np.linspace(0.0, 1.0, 5)]
    return ticks, [dimension.text(dimension.decode(t)) for t in ticks]
