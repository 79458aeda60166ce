"""Exported concrete scenarios load with the project's reader, with the values applied."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario
from simtest_operator.search import Proposal
from simtest_operator.search.exporting import export_scenarios


def test_export_writes_loadable_concrete_files(cut_in: Path, tmp_path: Path) -> None:
    proposals = [
        Proposal(index=3, values={"EgoSpeed": 31.5, "CutInGap": 8.0}, basis=0),
        Proposal(index=7, values={"EgoSpeed": 18.25, "LaneChangeTime": 1.5}, basis=2),
    ]
    out = tmp_path / "suite" / "nested"
    written = export_scenarios(cut_in, proposals, out)
    assert [p.name for p in written] == [
        "cut-in_highway_v25_gap15_dv10_search-3_EgoSpeed-31.5_CutInGap-8.xosc",
        "cut-in_highway_v25_gap15_dv10_search-7_EgoSpeed-18.25_LaneChangeTime-1.5.xosc",
    ]
    first = load_scenario(written[0])
    declared = {d.name: d.value for d in first.parameters}
    assert declared["EgoSpeed"] == 31.5 and declared["CutInGap"] == 8.0
    assert declared["TargetSpeed"] == 15.0  # untouched
    reference = load_scenario(cut_in, overrides={"EgoSpeed": "31.5", "CutInGap": "8"})
    copy = first.road_network.logic_file  # the road network is copied next to the files
    assert copy == (out / "roads/highway_straight.xodr").resolve()
    assert reference.road_network.logic_file is not None and copy is not None
    assert copy.read_bytes() == reference.road_network.logic_file.read_bytes()
    second = {d.name: d.value for d in load_scenario(written[1]).parameters}
    assert second["LaneChangeTime"] == 1.5


def test_export_refuses_undeclared_parameters(cut_in: Path, tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="declares no parameter"):
        export_scenarios(cut_in, [Proposal(index=0, values={"Nope": 1.0}, basis=0)], tmp_path)
