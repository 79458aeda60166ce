"""The Euro NCAP suite as the reference player runs it: the 23 base scenarios of
``scenarios/ncap`` (Vector Informatik's OpenSCENARIO implementation of the Euro NCAP protocols,
see its PROVENANCE.md) against what esmini 3.6.0 produced for them (``data/ncap-reference.json``,
the development corpus's ``ncap-reference.json``), compared as ``simtest scenario check
--reference`` compares them; and their ``Variations/`` parameter sweeps: every file expands into
its concrete runs (1,183 in all), and a sample of them runs to a verdict.

The ego is scripted in these files (no controller hands it to the SUT), as in esmini's runs, so
the collisions the protocols set up happen in both."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pytest

from simtest_operator.evaluation import reference as references
from simtest_operator.openscenario import (
    ConcreteRun,
    FileKind,
    LoadOptions,
    expand_distribution,
    file_kind,
)
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig
from simtest_operator.verdicts import Verdict

NCAP = Path(__file__).resolve().parents[2] / "scenarios" / "ncap"
SCENARIOS = NCAP / "OpenSCENARIO" / "NCAP"
REFERENCE = Path(__file__).parent / "data" / "ncap-reference.json"
BASE = sorted(SCENARIOS.glob("*/*.xosc"))
VARIATIONS = sorted(SCENARIOS.glob("*/Variations/**/*.xosc"))
MUST_MATCH = {path.relative_to(SCENARIOS).as_posix() for path in BASE}
"""Base scenarios that match the reference (end time within 0.5 s, every entity's median
position error within 1 m): all 23."""
SAMPLE_STRIDE = 40
"""Every 40th concrete run of the sweeps, in file and expansion order (30 of 1,183)."""


def _run(
    scenario: Path, nets: Path, overrides: Mapping[str, str] | None = None
) -> scenario_execution.RunReport:
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=scenario,
            overrides=dict(overrides or {}),
            nets_dir=nets,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(),
            loading=LoadOptions(source_root=NCAP),
        )
    )


@pytest.fixture(scope="module")
def reference() -> Mapping[str, Any]:
    return references.load(REFERENCE)


def test_the_suite_has_its_23_base_scenarios() -> None:
    assert len(BASE) == 23


@pytest.mark.parametrize("scenario", BASE, ids=lambda p: p.stem)
def test_base_scenario_matches_the_reference_player(
    scenario: Path, reference: Mapping[str, Any], tmp_path: Path
) -> None:
    report = _run(scenario, tmp_path)
    assert report.outcome.verdict.counts_as_ran, report.outcome.reason
    key = references.find(reference, scenario)
    assert key is not None
    end = report.outcome.simulated_seconds if report.storyboard_complete else None
    comparison = references.compare(
        key, reference[key], samples=report.samples, end_time=end, intended=report.intended
    )
    assert not comparison.intended
    if scenario.relative_to(SCENARIOS).as_posix() in MUST_MATCH:
        assert comparison.match, comparison


def test_every_variation_expands() -> None:
    counts: dict[str, int] = {}
    for path in VARIATIONS:
        assert file_kind(path) is FileKind.DISTRIBUTION, path
        counts[path.relative_to(SCENARIOS).as_posix()] = len(expand_distribution(path))
    assert len(counts) == 109
    assert all(count >= 1 for count in counts.values())
    assert sum(counts.values()) == 1183
    assert counts["CA-FC_2026/Variations/StandardRange/CCRm.xosc"] == 55


SAMPLE = [run for path in VARIATIONS for run in expand_distribution(path)][::SAMPLE_STRIDE]


@pytest.mark.parametrize("run", SAMPLE, ids=lambda run: run.id)
def test_a_sample_of_the_variations_runs_to_a_verdict(run: ConcreteRun, tmp_path: Path) -> None:
    report = _run(run.scenario, tmp_path, run.overrides)
    assert report.outcome.verdict in (Verdict.PASSED, Verdict.FAILED), report.outcome.reason
    assert report.storyboard_complete, report.outcome.reason
