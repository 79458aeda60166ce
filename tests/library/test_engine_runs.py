"""The library runs on the project's own engine with sensible verdicts.

Covers: the smoke set gives the verdicts scenarios/README.md promises under the default SUT and
default criteria (the close cut-in fails on a collision, the other five pass); one scenario of
every category runs to a final verdict (never Invalid or Error) and the ego is the SUT; a
weaker SUT (adaptive cruise control off, AEB only) fails a hard-braking scenario that the
default SUT passes.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.runner.scenario_execution import RunRequest, run_scenario
from simtest_operator.sim import SutConfig
from simtest_operator.verdicts import Verdict
from tests.library.conftest import LIBRARY_ROOT

pytestmark = pytest.mark.slow

SMOKE_FAILING = {"cut-in_highway_v30_gap8_dv12"}
"""Smoke scenarios the default SUT is meant to fail (README: 'one close cut-in')."""


@pytest.fixture(scope="module")
def nets(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("nets")


def _run(path: Path, nets: Path, sut: SutConfig | None = None) -> Verdict:
    request = RunRequest(scenario=path, nets_dir=nets, record=False, sut=sut or SutConfig())
    report = run_scenario(request)
    assert report.ego == "Ego"
    return report.outcome.verdict


@pytest.mark.parametrize("path", sorted(LIBRARY_ROOT.glob("smoke/*.xosc")), ids=lambda p: p.stem)
def test_smoke_verdicts(path: Path, nets: Path) -> None:
    expected = Verdict.FAILED if path.stem in SMOKE_FAILING else Verdict.PASSED
    assert _run(path, nets) is expected


@pytest.mark.parametrize("category", sorted(p.name for p in (LIBRARY_ROOT / "library").iterdir()))
def test_every_category_runs(category: str, nets: Path) -> None:
    first = sorted((LIBRARY_ROOT / "library" / category).glob("*.xosc"))[0]
    assert _run(first, nets) in (Verdict.PASSED, Verdict.FAILED)


def test_sut_configuration_changes_the_verdict(nets: Path) -> None:
    path = LIBRARY_ROOT / "library" / "hard-braking" / "hard-braking_highway_v30_thw1.5_d9.xosc"
    assert _run(path, nets) is Verdict.PASSED
    assert _run(path, nets, SutConfig(acc=False)) is Verdict.FAILED
