"""Judging OpenSCENARIO 1.3 monitors: a scenario's own pass criteria.

A monitor is a boolean the scenario declares with an initial value and sets with
``SetMonitorAction`` as it observes what it checks; each monitor still false when the run ends
fails the run. Every monitor is reported as the metric ``monitor.<name>`` (1 true, 0 false).
"""

from __future__ import annotations

from collections.abc import Mapping

PREFIX = "monitor."
"""Metric name prefix of a monitor's final value."""


def metrics(final: Mapping[str, bool]) -> dict[str, float]:
    """``monitor.<name>`` = 1.0 (true) / 0.0 (false) for each monitor."""
    return {f"{PREFIX}{name}": 1.0 if value else 0.0 for name, value in final.items()}


def failures(final: Mapping[str, bool], end: float) -> list[tuple[float, str, str]]:
    """(time, name, message) of each monitor false at ``end``, as judging lists failures."""
    return [
        (end, f"{PREFIX}{name}", f"monitor {name} is false at the end (t={end:.2f} s)")
        for name, value in final.items()
        if not value
    ]
