"""An entity without a route takes the connector that turns least at a junction (esmini picks at
random unless given a selector angle; straight on is its angle 0): the esmini unit test scenario
of the junction selector then follows the reference player, and a scenario is reproducible."""

from __future__ import annotations

from pathlib import Path

from simtest_operator.evaluation import reference as references
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"
SCENARIO = (
    CORPUS / "esmini" / "EnvironmentSimulator" / "Unittest" / "xosc" / "junction-selector.xosc"
)


def test_unrouted_car_goes_straight_through_the_junction_as_the_reference(tmp_path: Path) -> None:
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )
    ref = references.load(CORPUS / "esmini-unittest-reference.json")
    key = references.find(ref, SCENARIO)
    assert key is not None
    comparison = references.compare(
        key, ref[key], samples=report.samples, end_time=report.outcome.simulated_seconds
    )
    assert comparison.match, comparison
