"""esmini's FollowRouteController, imitated on a scripted ego (``--takeover never``): it changes
to the lane the route needs before the road ends, stops in test mode when the route is done or
has no path, and takes the planned roads at forks. Under a takeover the SUT model drives."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.opendrive import RoadNetwork
from simtest_operator.openscenario import LoadOptions
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig, Takeover, open_simulation
from simtest_operator.sim.esmini_route import Waypoint, plan_leg

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini"
UNITTEST = CORPUS / "EnvironmentSimulator" / "Unittest"
LOADING = LoadOptions(source_root=CORPUS)


State = tuple[float, str | None, int | None, float, float, float]
"""(time, road, lane, speed, x, y) of the ego after a step."""


def _drive(
    name: str, takeover: Takeover, tmp_path: Path, until: float
) -> tuple[list[State], tuple[str, ...]]:
    opened = open_simulation(
        UNITTEST / "xosc" / name,
        sut=SutConfig(takeover=takeover),
        settings=SimulationSettings(),
        nets_dir=tmp_path,
        backend=BackendChoice.MEMORY,
        loading=LOADING,
    )
    simulation = opened.simulation
    simulation.start()
    states: list[State] = []
    while not simulation.complete and simulation.time < until:
        (ego,) = (e for e in simulation.step().entities if e.name == "Ego")
        states.append((simulation.time, ego.road_id, ego.lane_id, ego.speed, ego.x, ego.y))
    labels = simulation.intended_differences
    simulation.close()
    return states, labels


def test_the_ego_changes_to_the_route_lane_and_stops_at_its_end(tmp_path: Path) -> None:
    # Road 0 lane -1 to road 3 lane -2: esmini changes lanes on road 0 (lane -2 runs straight
    # on into road 3's lane -2), then stops (test mode) just past the target at s = 20.
    states, labels = _drive("perform_single_lane_change.xosc", Takeover.NEVER, tmp_path, 10.0)
    assert not any("followRoute" in label for label in labels)
    on_road_0 = [lane for _, road, lane, *_ in states if road == "0"]
    assert on_road_0[0] == -1 and on_road_0[-1] == -2
    _, road, lane, speed, x, y = states[-1]
    assert (road, lane, speed) == ("3", -2, 0.0)
    # esmini's reference: the ego stands at (221.4, -17.9)
    assert abs(x - 221.4) < 0.5 and abs(y + 17.9) < 0.5


def test_a_route_without_path_stops_the_ego_in_test_mode(tmp_path: Path) -> None:
    # The target is a lane of the other carriageway, never reached driving its way.
    states, _ = _drive("follow_route_no_path.xosc", Takeover.NEVER, tmp_path, 3.0)
    assert states[-1][3] == 0.0
    assert abs(states[-1][4] - 22.9) < 0.5  # esmini stops one step after the route came


def test_under_a_takeover_the_sut_model_drives(tmp_path: Path) -> None:
    states, labels = _drive("follow_route_no_path.xosc", Takeover.ON_CONTROLLER, tmp_path, 3.0)
    assert states[-1][3] > 20.0
    assert "Ego driven by the SUT model" in labels


def test_the_lane_plan_prefers_lanes_leading_straight_into_the_target_lane() -> None:
    roads = RoadNetwork.from_file(UNITTEST / "xodr" / "highway_example_with_merge_and_split.xodr")
    waypoints = plan_leg(roads, Waypoint("0", -1, 10.0), 1, Waypoint("3", -2, 20.0))
    assert waypoints is not None
    assert [(w.road_id, w.lane_id) for w in waypoints] == [("0", -2), ("3", -2)]
    # the waypoint on road 0 is the middle of the stretch where lane -2 reaches the exit
    assert 0.0 < waypoints[0].s < roads.road_length("0")


@pytest.mark.parametrize("lane", [-1, -3])
def test_no_plan_from_the_target_lane_itself(lane: int) -> None:
    roads = RoadNetwork.from_file(UNITTEST / "xodr" / "highway_example_with_merge_and_split.xodr")
    assert plan_leg(roads, Waypoint("3", lane, 10.0), 1, Waypoint("3", lane, 40.0)) is None
