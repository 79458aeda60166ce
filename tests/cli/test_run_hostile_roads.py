"""A campaign whose scenarios use hostile road files (issue 12, item 4), run by ``simtest run`` with
the real simulator engine: each scenario ends ``Invalid`` at once with the element and line, tried
once. Before, the 1e12 spiral hung the geometry evaluator until the campaign's timeout (a
``Timeout`` verdict, blaming the system under test) and NaN lengths reached netconvert (``Error``,
retried, with SUMO's stderr); so did degenerate roads (issue 29), while a spiral of constant
curvature, which netconvert could not evaluate, is a line and runs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from tests.opendrive.conftest import road_grid
from tests.runner.support import campaign_manifest

ROOT = Path(__file__).resolve().parents[2]
HOSTILE = ROOT / "tests" / "opendrive" / "hostile"
SCENARIO = ROOT / "scenarios" / "smoke" / "hard-braking_rural_v15_thw2_d4.xosc"
ROADS = {
    "spiral_extreme_curvend": "<spiral>, line 7",
    "length_nan": "<road>, line 4",
    "width_negative": "<width>, line 14",
    "parampoly3_point": "<paramPoly3>, line 7",  # issue 29: degenerate roads
    "width_zero": "<lanes>, line 10",
}

FLAT_PLAN_VIEW = (
    '<planView><geometry s="0" x="0" y="0" hdg="0" length="1200">'
    '<spiral curvStart="0" curvEnd="0"/></geometry>'
)


@pytest.mark.timeout(180)
def test_hostile_roads_are_invalid_not_timeout_or_error(tmp_path: Path) -> None:
    suite = tmp_path / "suite"
    suite.mkdir()
    text = SCENARIO.read_text()
    for name in ROADS:
        (suite / f"{name}.xodr").write_bytes((HOSTILE / f"{name}.xodr").read_bytes())
        (suite / f"{name}.xosc").write_text(
            text.replace("../roads/rural_curved.xodr", f"{name}.xodr")
        )
    # A spiral of constant curvature is a valid line (or arc): it runs (it was an Error).
    road = (ROOT / "scenarios" / "roads" / "rural_curved.xodr").read_text()
    plan_view = road[road.index("<planView>") : road.index("</planView>")]
    (suite / "flat_spiral.xodr").write_text(road.replace(plan_view, FLAT_PLAN_VIEW))
    (suite / "flat_spiral.xosc").write_text(
        text.replace("../roads/rural_curved.xodr", "flat_spiral.xodr")
    )
    manifest = tmp_path / "campaign.yaml"
    manifest.write_text(campaign_manifest(timeout=60, retries=2))
    started = time.monotonic()
    result = CliRunner().invoke(
        cli,
        ["run", str(manifest), "-o", str(tmp_path / "out"), "-j", "1", "--plain"],
        env={"SIMTEST_CACHE_DIR": str(tmp_path / "cache")},
    )
    assert result.exit_code == 2, result.output
    assert time.monotonic() - started < 60, "a hostile road must not run into the timeout"
    assert "retry" not in result.output
    results = {
        json.loads(path.read_text())["scenarioId"]: json.loads(path.read_text())
        for path in (tmp_path / "out" / "scenarios").glob("*/result.json")
    }
    assert len(results) == len(ROADS) + 1
    assert results["flat_spiral.xosc"]["verdict"] == "Passed", results["flat_spiral.xosc"]
    for name, where in ROADS.items():
        outcome = results[f"{name}.xosc"]
        assert outcome["verdict"] == "Invalid", outcome
        assert where in outcome["reason"] and "\n" not in outcome["reason"], outcome["reason"]


MEASURE = """import resource, subprocess, sys
subprocess.run(sys.argv[1:], check=False)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"""
"""Runs a command and prints the peak RSS (KiB) of it and every process it waited for."""


@pytest.mark.timeout(180)
def test_a_road_network_at_the_limits_runs_within_a_pods_memory(tmp_path: Path) -> None:
    # 21,000 roads (84,000 lanes) peaked at 1.1-1.5 GB, above a simulator pod's 1 GiB request
    # (issue 29), now refused (tests/opendrive). At the limits (20,000 lanes, 500 km of roads,
    # all arcs) the whole run, netconvert included, stays well inside: measured 407 MB.
    (tmp_path / "grid.xodr").write_bytes(
        road_grid(5_000, length=100.0, shape='<arc curvature="0.01"/>')
    )
    text = SCENARIO.read_text().replace("../roads/rural_curved.xodr", "grid.xodr")
    text = text.replace('roadId="1" laneId="-1" s="$EgoS"', 'roadId="0" laneId="-1" s="2"')
    text = text.replace('s="${$EgoS + $Gap + 4.5}"', 's="9"')
    text = text.replace('SimulationTimeCondition value="10"', 'SimulationTimeCondition value="1"')
    (tmp_path / "grid.xosc").write_text(text)
    simtest = Path(sys.executable).with_name("simtest")
    command = [sys.executable, "-c", MEASURE, str(simtest), "scenario", "run",
               str(tmp_path / "grid.xosc"), "--no-record"]  # fmt: skip
    result = subprocess.run(
        command,
        capture_output=True,
        text=True,
        env={**os.environ, "SIMTEST_CACHE_DIR": str(tmp_path / "cache")},
        check=True,
    )
    assert "verdict: Passed" in result.stdout, result.stdout + result.stderr
    peak_mib = int(result.stdout.split()[-1]) / 1024
    assert peak_mib < 700, f"peak RSS {peak_mib:.0f} MiB"
