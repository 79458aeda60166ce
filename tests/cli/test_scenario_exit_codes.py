"""``simtest scenario run`` exits like ``simtest run``: 0 passed, 1 failed or timeout, 2 otherwise.

Covers: every verdict maps to the code ``simtest run`` gives a one-scenario list (the engine
replaced by a canned report, so Timeout and Error need no slow or broken simulator); a real
failing smoke cut-in exits 1 and an unparsable file exits 2 (real SUMO); a missing file is a
usage error (2); ``--help`` states the codes.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator import runner
from simtest_operator.cli.main import cli
from simtest_operator.verdicts import ScenarioOutcome, Verdict

pytestmark = pytest.mark.timeout(60)

SMOKE = Path(__file__).resolve().parents[2] / "scenarios" / "smoke"


def invoke(tmp_path: Path, *args: str) -> tuple[int, str]:
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache")}
    result = CliRunner().invoke(cli, ["scenario", "run", *args], env=env)
    return result.exit_code, result.output


@pytest.mark.parametrize(
    ("verdict", "code"),
    [
        (Verdict.PASSED, 0),
        (Verdict.FAILED, 1),
        (Verdict.TIMEOUT, 1),
        (Verdict.ERROR, 2),
        (Verdict.INVALID, 2),
        (Verdict.SKIPPED, 2),
    ],
)
def test_each_verdict_exits_as_simtest_run_does(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, verdict: Verdict, code: int
) -> None:
    def canned(request: runner.RunRequest) -> runner.RunReport:
        outcome = ScenarioOutcome(scenario_id=request.scenario.name, verdict=verdict, reason="why")
        return runner.RunReport(outcome=outcome, storyboard_complete=False)

    monkeypatch.setattr(runner, "run_scenario", canned)
    exit_code, output = invoke(tmp_path, str(SMOKE / "cut-in_highway_v25_gap30_dv5.xosc"))
    assert exit_code == code, output
    assert output.splitlines()[:2] == [f"verdict: {verdict.value}", "reason: why"]


def test_a_real_collision_exits_1(tmp_path: Path) -> None:
    scenario = SMOKE / "cut-in_highway_v30_gap8_dv12.xosc"
    exit_code, output = invoke(tmp_path, str(scenario), "--no-record")
    assert exit_code == 1, output
    assert output.startswith("verdict: Failed\nreason: Ego collided with Target")


def test_an_unparsable_file_exits_2(tmp_path: Path) -> None:
    broken = tmp_path / "broken.xosc"
    broken.write_text("<OpenSCENARIO><FileHeader/></OpenSCENARIO>")
    exit_code, output = invoke(tmp_path, str(broken), "--no-record")
    assert exit_code == 2, output
    assert output.startswith("verdict: Invalid\nreason: missing required attribute")


def test_a_missing_file_is_a_usage_error(tmp_path: Path) -> None:
    exit_code, output = invoke(tmp_path, str(tmp_path / "absent.xosc"))
    assert exit_code == 2
    assert "does not exist" in output


def test_help_states_the_exit_codes(tmp_path: Path) -> None:
    exit_code, output = invoke(tmp_path, "--help")
    assert exit_code == 0
    text = " ".join(output.split())
    assert "0 passed, 1 failed or timed out" in text
    assert "2 error or invalid input" in text
