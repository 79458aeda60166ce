"""``simtest scenario run`` and ``check`` (kept with the sim tests; they exercise the engine):
run prints verdict, reason, rule set and metrics and writes the artifacts, check has the rule set
of each file; check skips catalogs, runs a
directory and ends with exactly ``N ran, M invalid, K errors``; with --reference it adds the
comparison and the match count."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli

from . import carla_scenarios as cs

DATA = Path(__file__).parent / "data"
CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"


@pytest.fixture
def env(tmp_path: Path) -> dict[str, str]:
    return {"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), "COLUMNS": "200"}


def test_run_prints_verdict_and_writes_artifacts(tmp_path: Path, env: dict[str, str]) -> None:
    out = tmp_path / "out"
    result = CliRunner().invoke(
        cli, ["scenario", "run", str(DATA / "hard_braking_lead.xosc"), "--out", str(out)], env=env
    )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0] == "verdict: Passed"
    assert lines[1].startswith("reason: storyboard complete")
    assert lines[2] == "rules: OpenSCENARIO (esmini)"
    assert any(line.startswith("minTTC: ") for line in lines)
    assert (out / "recording.mcap").is_file() and (out / "result.json").is_file()


def test_check_directory_table_and_summary(tmp_path: Path, env: dict[str, str]) -> None:
    folder = tmp_path / "scenarios"
    folder.mkdir()
    shutil.copy(DATA / "hard_braking_lead.xosc", folder)
    shutil.copy(DATA / "straight.xodr", folder)
    (folder / "broken.xosc").write_text("<OpenSCENARIO><FileHeader/></OpenSCENARIO>")
    result = CliRunner().invoke(cli, ["scenario", "check", str(folder), "--jobs", "1"], env=env)
    assert result.exit_code == 0, result.output
    assert "hard_braking_lead.xosc" in result.output and "Invalid" in result.output
    assert "OpenSCENARIO (esmini)" in result.output
    assert result.output.splitlines()[-1] == "1 ran, 1 invalid, 0 errors"


def test_run_and_check_print_scenario_runners_rules(tmp_path: Path, env: dict[str, str]) -> None:
    folder = tmp_path / "carla"
    folder.mkdir()
    text = cs.follow_leading(description="FollowLeadingVehicle")
    path = cs.write(folder, text)
    run = CliRunner().invoke(cli, ["scenario", "run", str(path), "--no-record"], env=env)
    assert "rules: ScenarioRunner (criteria_* conditions)" in run.output.splitlines(), run.output
    check = CliRunner().invoke(cli, ["scenario", "check", str(folder), "--jobs", "1"], env=env)
    assert "ScenarioRunner (criteria_*" in check.output, check.output


def test_check_with_reference(tmp_path: Path, env: dict[str, str]) -> None:
    folder = tmp_path / "esmini" / "resources" / "xosc"
    folder.mkdir(parents=True)
    source = CORPUS / "esmini" / "resources"
    shutil.copytree(source / "xodr", tmp_path / "esmini" / "resources" / "xodr")
    shutil.copytree(source / "xosc" / "Catalogs", folder / "Catalogs")
    for name in ("cut-in.xosc", "slow-lead-vehicle.xosc"):
        shutil.copy(source / "xosc" / name, folder)
    result = CliRunner().invoke(
        cli,
        [
            "scenario",
            "check",
            str(folder),
            "--jobs",
            "2",
            "--takeover",
            "never",
            "--reference",
            str(CORPUS / "esmini-reference.json"),
            "--root",  # the roads are in a sibling of the checked folder
            str(tmp_path / "esmini"),
        ],
        env=env,
    )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[-2] == "2 of 2 compared scenarios match the reference"
    assert lines[-1] == "2 ran, 0 invalid, 0 errors"
