"""RandomRouteAction: the entity drives a route drawn from the world's seeded generator: the same
seed takes the same way, other seeds other ways through the junction; the drawn route runs on
to a dead end; an entity not on a road cannot be given one."""

from __future__ import annotations

import random
import shutil
from pathlib import Path

import pytest

from simtest_operator.opendrive import RoadNetwork
from simtest_operator.sim import random_routes
from tests.sim import osc_scenarios as osc

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"
FABRIKSGATAN = CORPUS / "esmini" / "resources" / "xodr" / "fabriksgatan.xodr"
RANDOM = "<PrivateAction><RoutingAction><RandomRouteAction/></RoutingAction></PrivateAction>"


@pytest.fixture
def junction_scenario(tmp_path: Path) -> Path:
    if not FABRIKSGATAN.is_file():
        pytest.skip(f"development corpus not found at {FABRIKSGATAN}")
    place = osc.place("Car", lane=1, s=20.0, speed=50 / 3.6).replace('roadId="1"', 'roadId="0"')
    text = osc.scenario(
        entities=osc.CAR.format(name="Car"),
        init=place.replace("</Private>", RANDOM + "</Private>"),
        stop=osc.at_time(12.0, name="end"),
    ).replace("straight.xodr", "fabriksgatan.xodr")
    path = osc.write(tmp_path, text)
    shutil.copy(FABRIKSGATAN, tmp_path / "fabriksgatan.xodr")
    return path


def _end(path: Path, tmp_path: Path, seed: int) -> tuple[float, float]:
    report = osc.run(path, tmp_path, seed=seed)
    assert report.outcome.verdict.value == "Passed", report.outcome.reason
    sample = report.samples["Car"][-1]
    return round(sample[1], 1), round(sample[2], 1)


def test_the_seed_decides_the_way(junction_scenario: Path, tmp_path: Path) -> None:
    ends = {seed: _end(junction_scenario, tmp_path, seed) for seed in range(6)}
    assert _end(junction_scenario, tmp_path, 3) == ends[3]
    assert len(set(ends.values())) > 1, ends


def test_a_drawn_route_runs_on_through_the_network() -> None:
    if not FABRIKSGATAN.is_file():
        pytest.skip(f"development corpus not found at {FABRIKSGATAN}")
    roads = RoadNetwork.from_file(FABRIKSGATAN)
    route = random_routes.draw(roads, ("0", -1), random.Random(1))
    # Through the junction onto an arm that ends there: road, connector, arm.
    assert route[0] == "0" and len(route) == 3
    assert roads.road(route[1]).junction not in (None, "-1")
    again = random_routes.draw(roads, ("0", -1), random.Random(1))
    assert route == again


def test_a_random_route_needs_the_entity_on_a_road(tmp_path: Path) -> None:
    text = osc.scenario(
        entities=osc.CAR.format(name="Car"),
        init=(
            '<Private entityRef="Car"><PrivateAction><TeleportAction><Position>'
            '<WorldPosition x="0" y="500"/></Position></TeleportAction></PrivateAction>'
            f"{RANDOM}</Private>"
        ),
        stop=osc.at_time(1.0),
    )
    outcome = osc.run(osc.write(tmp_path, text), tmp_path).outcome
    assert outcome.verdict.value == "Invalid"
    assert "random route needs Car on a road" in outcome.reason
