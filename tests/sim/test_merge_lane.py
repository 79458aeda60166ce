"""A lane that narrows to nothing under a car (the end of a merge lane) hands the car to the lane
next to it, nearer the centre, where it is: ``follow_route_ghost_starting_on_route.xosc`` drives
on lane -2 of road 209 of ``multi_intersections.xodr``, which narrows to 0 m at s = 59 and has no
successor; the car rode the 0 m lane to the road's end and snapped 1.9 m across onto the next
road (the run ended ``Error``: "jumps 1.88 m against its velocity")."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest

from simtest_operator.openscenario import LoadOptions
from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig, Takeover, open_simulation
from simtest_operator.verdicts import Verdict

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini"
SCENARIO = (
    CORPUS
    / "EnvironmentSimulator"
    / "Unittest"
    / "xosc"
    / "follow_route_ghost_starting_on_route.xosc"
)
LOADING = LoadOptions(source_root=CORPUS)


@pytest.mark.parametrize("takeover", [Takeover.NEVER, Takeover.ON_CONTROLLER])
def test_the_car_leaves_the_vanished_lane_without_a_jump(
    takeover: Takeover, tmp_path: Path
) -> None:
    opened = open_simulation(
        SCENARIO,
        sut=SutConfig(takeover=takeover),
        settings=SimulationSettings(),
        nets_dir=tmp_path,
        backend=BackendChoice.MEMORY,
        loading=LOADING,
    )
    simulation = opened.simulation
    poses = []
    simulation.start()
    while not simulation.complete and simulation.time < 20.0:
        (ego,) = (e for e in simulation.step().entities if e.name == "Ego")
        poses.append((ego.x, ego.y, ego.lane_id, ego.road_id))
    simulation.close()
    assert ("209", -1) in {(road, lane) for _, _, lane, road in poses}  # it did merge
    for (x0, y0, _, _), (x1, y1, _, _) in itertools.pairwise(poses):
        # 20 m/s, 0.05 s steps (a little more through curves); the snap added 1.9 m
        assert math.hypot(x1 - x0, y1 - y0) < 1.3, (x0, y0, x1, y1)


def test_the_corpus_file_passes_the_evidence_gate(tmp_path: Path) -> None:
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            loading=LOADING,
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason


def test_a_route_lane_still_closed_at_the_link_does_not_take_the_car(tmp_path: Path) -> None:
    # follow_route_multiple_scenario_waypoints: road 222's lane -1 links to road 202's lane 2;
    # 202's lane 1 (the route's lane, a turn pocket) is 0 m wide there and opens further on.
    # The lane graph took lane 1 by its id, then the route's lane pick did: the car jumped
    # 1.9 m sideways onto a lane border and the evidence gate refused the recording.
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO.with_name("follow_route_multiple_scenario_waypoints.xosc"),
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            loading=LOADING,
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
