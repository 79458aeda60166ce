"""Off road means off every road of the network, not just off the one the actor is bound to: in
a junction the connectors overlap, so a lane-bound car's reference point can lie beside its own
one-lane connector yet on the next one (route_lane_change.xosc ends a lane change as it enters
such a connector); that is road surface, and the offRoad criterion must not fail the run."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.openscenario import model
from tests.sim.worlds import Bench, speed, teleport

FABRIKSGATAN = (
    Path(__file__).resolve().parents[3]
    / "shared"
    / "scenarios-dev"
    / "esmini"
    / "resources"
    / "xodr"
    / "fabriksgatan.xodr"
)


@pytest.mark.skipif(not FABRIKSGATAN.exists(), reason="dev corpus not present")
@pytest.mark.parametrize(
    ("offset", "off_road"),
    [
        (0.0, False),  # the connector's own lane
        (3.35, False),  # beside connector 6 (edge at 1.75 m) but on a neighbouring connector
        (15.0, True),  # beside every road: off road
    ],
)
def test_a_point_beside_its_connector_on_another_one_is_on_the_road(
    offset: float, off_road: bool
) -> None:
    bench = Bench("Car", road=str(FABRIKSGATAN))
    position = model.LanePosition(road_id="6", lane_id=-1, s=9.2, offset=offset)
    bench.start("Car", teleport(position))
    bench.start("Car", speed(1.0))
    bench.step(2)
    car = bench.actor("Car")
    roads = bench.world.roads
    assert roads is not None
    t = bench.world.lane_t("6", car.s, -1) + car.offset
    beside = not any(b.t_min <= t <= b.t_max for b in roads.lanes_at("6", car.s) if b.lane_id)
    assert (car.road_id, beside) == ("6", offset > 0.0)  # the premise: beside its own road
    assert (car.offroad_time > 0.0) is off_road
