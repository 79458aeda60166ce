"""The engine on the in-memory backend with real files of the development corpus: a cut-in
follows the reference player's paths and end time, an open-space scenario runs, an unsupported
element makes the run Invalid naming element and line, accepted-but-ignored elements are listed,
and a distribution-free run is deterministic."""

from __future__ import annotations

import shutil
from pathlib import Path

from simtest_operator.evaluation import reference as references
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from simtest_operator.verdicts import Verdict

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"
XOSC = CORPUS / "esmini" / "resources" / "xosc"


def run(name: str, tmp_path: Path) -> scenario_execution.RunReport:
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=XOSC / name,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )


def test_cut_in_matches_the_reference_player(tmp_path: Path) -> None:
    report = run("cut-in.xosc", tmp_path)
    assert report.outcome.verdict is Verdict.FAILED  # the scripted ego runs into the cut-in car
    assert {(c.first, c.second) for c in report.collisions} == {("Ego", "OverTaker")}
    ref = references.load(CORPUS / "esmini-reference.json")
    key = references.find(ref, XOSC / "cut-in.xosc")
    assert key is not None
    comparison = references.compare(
        key, ref[key], samples=report.samples, end_time=report.outcome.simulated_seconds
    )
    assert comparison.match, comparison
    assert comparison.worst_median < 0.5


def test_open_space_scenario_runs(tmp_path: Path) -> None:
    report = run("truck_with_rotating_axle.xosc", tmp_path)
    assert report.outcome.verdict is Verdict.PASSED
    assert report.outcome.simulated_seconds > 30.0


def test_unsupported_element_is_invalid_with_element_and_line(tmp_path: Path) -> None:
    data = Path(__file__).parent / "data"
    shutil.copy(data / "straight.xodr", tmp_path / "straight.xodr")
    text = (data / "hard_braking_lead.xosc").read_text(encoding="utf-8")
    start = text.index("<PrivateAction><LongitudinalAction><SpeedAction>\n")
    end = text.index("</PrivateAction>", start) + len("</PrivateAction>")
    unsupported = (
        "<PrivateAction><RoutingAction><FancyRouteAction/></RoutingAction></PrivateAction>"
    )
    text = text[:start] + unsupported + text[end:]
    line = text[:start].count("\n") + 1
    scenario = tmp_path / "fancy_route.xosc"
    scenario.write_text(text, encoding="utf-8")
    outcome = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=scenario,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    ).outcome
    assert outcome.verdict is Verdict.INVALID
    assert "<FancyRouteAction>" in outcome.reason and f"line {line}" in outcome.reason


def test_ignored_elements_are_listed(tmp_path: Path) -> None:
    outcome = run("cut-in_environment.xosc", tmp_path).outcome
    assert "EnvironmentAction" in outcome.ignored_elements
    assert outcome.metrics["ignoredElements"] == len(outcome.ignored_elements)


def test_runs_are_deterministic(tmp_path: Path) -> None:
    first, second = run("highway_merge.xosc", tmp_path), run("highway_merge.xosc", tmp_path)
    assert first.samples == second.samples
