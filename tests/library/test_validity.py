"""Every generated file is valid for the tools that consume it.

Covers: each .xosc (suite and smoke set) validates against the OpenSCENARIO 1.2 XSD; each
.xodr validates against the OpenDRIVE 1.6 XSD and converts with SUMO's netconvert (the flags
the simulator uses) without errors or warnings, into a network with the expected edges.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
import sumo
from lxml import etree

from tests.library.conftest import LIBRARY_ROOT

SCENARIOS = sorted(LIBRARY_ROOT.glob("library/*/*.xosc")) + sorted(
    LIBRARY_ROOT.glob("smoke/*.xosc")
)
ROADS = sorted(LIBRARY_ROOT.glob("roads/*.xodr"))


def _errors(schema: etree.XMLSchema, path: Path) -> list[str]:
    schema.validate(etree.parse(str(path)))
    return [f"{error.line}: {error.message}" for error in schema.error_log]


def test_every_scenario_validates(openscenario_schema: etree.XMLSchema) -> None:
    assert len(SCENARIOS) > 200
    failures = {p.name: _errors(openscenario_schema, p)[:3] for p in SCENARIOS}
    assert {name: errs for name, errs in failures.items() if errs} == {}


@pytest.mark.parametrize("road", ROADS, ids=lambda p: p.stem)
def test_road_validates_against_opendrive(road: Path, opendrive_schema: etree.XMLSchema) -> None:
    assert _errors(opendrive_schema, road) == []


@pytest.mark.parametrize("road", ROADS, ids=lambda p: p.stem)
def test_road_converts_with_netconvert(road: Path, tmp_path: Path) -> None:
    net = tmp_path / f"{road.stem}.net.xml"
    result = subprocess.run(
        [
            str(Path(sumo.SUMO_HOME) / "bin" / "netconvert"),
            "--opendrive-files",
            str(road),
            "-o",
            str(net),
            "--offset.disable-normalization",
            "true",
            "--output.original-names",
            "true",
            "--opendrive.internal-shapes",
            "true",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert "Warning" not in result.stderr and "Error" not in result.stderr, result.stderr
    edges = [e for e in etree.parse(str(net)).iter("edge") if e.get("function") != "internal"]
    assert len(edges) >= 2
