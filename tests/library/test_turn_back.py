"""The search benchmark's pedestrian-turn-back scenario has two separate failure regions.

Covers: the scenario runs on the project's engine with the default SUT; a point where the ego
meets the pedestrian stepping out fails; a point where it meets the pedestrian coming back
fails while the same point of the plain junction crossing (no turn back) passes, so the second
region is the turn back's; a point between the regions passes.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.runner.scenario_execution import RunRequest, run_scenario
from simtest_operator.verdicts import Verdict
from tests.library.conftest import LIBRARY_ROOT

pytestmark = pytest.mark.slow

TURN_BACK = (
    LIBRARY_ROOT / "library/pedestrian-turn-back/pedestrian-turn-back_junction_v8_tta7_walk2.5.xosc"
)
CROSSING = (
    LIBRARY_ROOT
    / "library/pedestrian-crossing/pedestrian-crossing_junction_v11_tta2.5_walk1.4.xosc"
)


@pytest.fixture(scope="module")
def nets(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("nets")


def _verdict(path: Path, nets: Path, ego: float, trigger: float, walk: float) -> Verdict:
    overrides = {"EgoSpeed": str(ego), "TriggerDistance": str(trigger), "WalkSpeed": str(walk)}
    report = run_scenario(
        RunRequest(scenario=path, nets_dir=nets, overrides=overrides, record=False)
    )
    return report.outcome.verdict


def test_the_scenario_runs_as_generated(nets: Path) -> None:
    report = run_scenario(RunRequest(scenario=TURN_BACK, nets_dir=nets, record=False))
    assert report.ego == "Ego"
    assert report.outcome.verdict in (Verdict.PASSED, Verdict.FAILED)


@pytest.mark.parametrize(
    ("ego", "trigger", "walk"),
    [(12.0, 30.0, 1.4), (8.0, 55.0, 2.6)],
    ids=["stepping-out", "coming-back"],
)
def test_each_region_fails(nets: Path, ego: float, trigger: float, walk: float) -> None:
    assert _verdict(TURN_BACK, nets, ego, trigger, walk) is Verdict.FAILED


def test_the_second_region_is_the_turn_back(nets: Path) -> None:
    assert _verdict(CROSSING, nets, 8.0, 55.0, 2.6) is Verdict.PASSED


def test_between_the_regions_it_passes(nets: Path) -> None:
    assert _verdict(TURN_BACK, nets, 8.0, 50.0, 2.0) is Verdict.PASSED
