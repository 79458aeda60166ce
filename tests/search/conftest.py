"""Shared pieces of the search tests: a small logical scenario and a synthetic system under test."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import pytest

from simtest_operator.search import Outcome
from simtest_operator.verdicts import Verdict

CUT_IN = Path(__file__).parents[2] / "scenarios/library/cut-in/cut-in_highway_v25_gap15_dv10.xosc"


@pytest.fixture
def cut_in() -> Path:
    """A library scenario declaring EgoSpeed, TargetSpeed, CutInGap, LaneChangeTime, ..."""
    return CUT_IN


def synthetic(values: Mapping[str, float | str]) -> Outcome:
    """A cheap stand-in system: fails when the gap is short while ego is much faster than the
    target (a corner of the space), and in a second, separate pocket at high target speed with a
    long gap; ``minTTC`` shrinks towards both, so TPE has a slope to follow."""
    gap, ego = float(values["CutInGap"]), float(values["EgoSpeed"])
    target = float(values["TargetSpeed"])
    corner = max(gap - 12.0, 0.0) / 5.0 + max(8.0 - (ego - target), 0.0) / 4.0
    pocket = max(abs(target - 27.0) - 2.5, 0.0) / 2.0 + max(abs(gap - 34.0) - 4.0, 0.0) / 4.0
    margin = min(corner, pocket)
    verdict = Verdict.FAILED if margin == 0.0 else Verdict.PASSED
    return Outcome(verdict, {"minTTC": margin})
