"""RoutePosition placements as the reference player (esmini 3.6) makes them.

pathS picks the road and its s along the route's legs; lane id, lane offset and t are that
road's own, whichever way the route runs along it (esmini's ``Position::SetRouteLanePosition``),
and the entity faces the lane's driving direction, turned by a relative Orientation. An
Orientation written after InRoutePosition (out of schema order, as in the Euro NCAP far-side
crossings) is ignored with a deviation: esmini places the entity before it reads it. The
scenario is written for these tests: an X junction with 60 m arms, the cyclist's route from the
north, the oncoming route from the south that leaves the junction against the north arm's s,
and a westbound route that starts against the east arm's s.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest

from simtest_operator.runner import scenario_execution
from simtest_operator.sim import SutConfig, Takeover
from tests.sim.carla_scenarios import run

SCENARIO = Path(__file__).parent / "data" / "ncap_junction" / "far_side_placements.xosc"
ARM_X = 71.5
"""x of the north and south arms' reference lines (60 m arm + 11.5 m to the junction centre)."""
NORTH, SOUTH = math.pi / 2, -math.pi / 2
Start = dict[str, tuple[float, float, float]]
"""Each entity's pose (x, y, heading) at t=0."""


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> scenario_execution.RunReport:
    folder = shutil.copytree(SCENARIO.parent, tmp_path_factory.mktemp("routes") / "junction")
    result = run(folder / SCENARIO.name, sut=SutConfig(takeover=Takeover.NEVER))
    assert result.storyboard_complete, result.outcome.reason
    return result


@pytest.fixture(scope="module")
def start(report: scenario_execution.RunReport) -> Start:
    return {name: tuple(samples[0][1:4]) for name, samples in report.samples.items()}  # type: ignore[misc]


def _at(start: Start, name: str) -> tuple[float, float, float]:
    x, y, heading = start[name]
    return x, y, math.remainder(heading, 2 * math.pi)


def test_a_forward_leg_places_by_the_roads_lanes(start: Start) -> None:
    # Southbound starts at the north arm's s=0: pathS 40 is its s 40, lane -1 west of the centre
    assert _at(start, "Cyclist") == pytest.approx((ARM_X - 1.75, 71.5 - 40.0, SOUTH), abs=1e-3)
    assert _at(start, "Ego") == pytest.approx((20.0, -1.75, 0.0), abs=1e-3)


def test_lanes_and_offsets_on_a_reversed_leg_are_the_roads_own(start: Start) -> None:
    # Northbound: south arm (60 m) + straight connector (23 m), then the north arm against its
    # s; pathS 103 is 20 m into it (s 40, y 31.5). Lane -1 is the north arm's lane -1 (west,
    # southbound), facing its driving direction; +0.5 m is left of the road's s (east).
    assert _at(start, "Oncoming") == pytest.approx((ARM_X - 1.75 + 0.5, 31.5, SOUTH), abs=1e-3)
    # FromRoadCoordinates t=-1.0: 1 m right of the road's s (west), heading replaced by absolute 0
    assert _at(start, "Turned") == pytest.approx((ARM_X - 1.0, 41.5, 0.0), abs=1e-3)


def test_a_relative_orientation_turns_the_entity_from_its_lanes_direction(start: Start) -> None:
    # laneOffset -2 m: 2 m right of the southbound lane (west); h=pi relative faces it north
    assert _at(start, "ParkedLarge") == pytest.approx((ARM_X - 3.75, 21.5, NORTH), abs=1e-3)
    # placed dx=5 m along ParkedLarge's heading: further north
    assert _at(start, "ParkedSmall") == pytest.approx((ARM_X - 3.75, 26.5, NORTH), abs=1e-3)


def test_an_orientation_after_the_in_route_position_is_ignored_with_a_deviation(
    report: scenario_execution.RunReport, start: Start
) -> None:
    assert _at(start, "ParkedLate") == pytest.approx((ARM_X - 3.75, 61.5, SOUTH), abs=1e-3)
    codes = [d.code for d in report.deviations]
    assert codes == ["route-orientation-after-position"]


def test_a_route_that_starts_against_a_roads_s_keeps_the_lane_ids_of_that_road(
    start: Start,
) -> None:
    # Westbound starts in lane 1 of the east arm (against its s) and stays against s on the
    # west arm: lane 1 is the roads' own lane 1 (north side) on both, facing west
    for name, x in (("Westbound", 83.0 + 40.0), ("WestboundLater", 50.0)):
        x_at, y_at, heading = _at(start, name)
        assert (x_at, y_at) == pytest.approx((x, 1.75), abs=1e-3)
        assert math.cos(heading) == pytest.approx(-1.0, abs=1e-6)
