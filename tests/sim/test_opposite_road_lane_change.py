"""A lane change still running when the car drives onto a road that runs the other way (an
end-to-end link: lane ids and t flip relative to the car) goes on to the same side: no snap back
across the road, no one-frame heading flip, and the run's evidence is complete. esmini's
``test_action_dynamics.xosc`` (dev corpus) does exactly this at x=100 on
``straight_2x100m_opposite.xodr``; it ended Error ("jumps 3.64 m against its velocity") before."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

from simtest_operator.openscenario import LoadOptions
from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig, Takeover, open_simulation
from simtest_operator.verdicts import Verdict

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini"
SCENARIO = CORPUS / "EnvironmentSimulator" / "Unittest" / "xosc" / "test_action_dynamics.xosc"
SCRIPTED = SutConfig(takeover=Takeover.NEVER)


def test_the_change_goes_on_smoothly_across_the_flipped_road(tmp_path: Path) -> None:
    opened = open_simulation(
        SCENARIO,
        sut=SCRIPTED,
        settings=SimulationSettings(),
        nets_dir=tmp_path / "nets",
        backend=BackendChoice.MEMORY,
        loading=LoadOptions(source_root=CORPUS),
    )
    simulation = opened.simulation
    poses = []
    snapshot = simulation.start()
    while not simulation.complete and simulation.time < 20.0:
        snapshot = simulation.step()
        (car,) = (e for e in snapshot.entities if e.name == "Car")
        poses.append((car.x, car.y, car.heading))
    simulation.close()
    crossing = next(i for i, (x, _, _) in enumerate(poses) if x > 100.0)
    assert 1 < crossing < len(poses) - 2  # the car does cross the link during the change
    for (x0, y0, h0), (x1, y1, h1) in itertools.pairwise(poses):
        assert math.hypot(x1 - x0, y1 - y0) < 0.55, (x0, y0, x1, y1)  # 10 m/s at most
        if 95.0 < x0 < 105.0:  # (a linear change's own ends turn the car at once elsewhere)
            assert abs(math.remainder(h1 - h0, math.tau)) < 0.1, (x0, h0, h1)


def test_the_corpus_file_passes_with_complete_evidence(tmp_path: Path) -> None:
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO,
            nets_dir=tmp_path / "nets",
            sut=SCRIPTED,
            output_dir=tmp_path / "out",
            loading=LoadOptions(source_root=CORPUS),
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason


def test_a_change_into_a_junction_follows_the_lane_the_car_is_in(tmp_path: Path) -> None:
    """``route_lane_change.xosc`` changes lanes while the car enters a junction whose one-lane
    connectors overlap: past half-way the target-side lane holds the car, so it takes that
    lane's connector (as esmini, which keeps a changing car on its target lane) instead of its
    old lane's, where it would ride beside the connector and snap across; a lane change onto
    a connector lacking the target lane goes on from where the car is (no 0.8 m jump at
    t = 6.6 s). It passed neither before: "left the road" beside one connector while on
    another, then evidence Errors for the jumps."""
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO.with_name("route_lane_change.xosc"),
            nets_dir=tmp_path / "nets",
            sut=SCRIPTED,
            record=False,
            backend=BackendChoice.MEMORY,
            loading=LoadOptions(source_root=CORPUS),
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
