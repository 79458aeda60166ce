"""Sanity check against the reference player: entity positions that esmini 3.6 produced for the
development scenarios (1 Hz samples) project onto our roads, lie on the road surface (within the
0.01 m rounding of the reference file) and, while moving, head along the road in either
direction. Scenarios whose entities leave the road on purpose are excluded."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from simtest_operator.opendrive import RoadNetwork

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"
LEAVE_THE_ROAD = {"controller_test.xosc", "cut-in_sloppy.xosc", "acc-toggle.xosc",
                  "parking_demo.xosc", "trajectory-test.xosc", "velodrome.xosc"}  # fmt: skip


def scenarios() -> list[tuple[str, Path, list[list[float]]]]:
    reference = json.loads((CORPUS / "esmini-reference.json").read_text())["scenarios"]
    cases = []
    for key, result in sorted(reference.items()):
        scenario = CORPUS / key
        match = re.search(r'<LogicFile\s+filepath="([^"]+)"', scenario.read_text())
        if match is None or scenario.name in LEAVE_THE_ROAD:
            continue
        maps = sorted(CORPUS.glob(f"esmini/resources/**/{Path(match.group(1)).name}"))
        samples = [s for entity in (result.get("samples_1hz") or {}).values() for s in entity[::3]]
        if maps and samples:
            cases.append((scenario.name, maps[0], samples))
    return cases


def test_reference_positions_lie_on_roads() -> None:
    cases = scenarios()
    assert len(cases) >= 50
    networks: dict[Path, RoadNetwork] = {}
    total = on_road = moving = aligned = 0
    for _, road_file, samples in cases:
        network = networks.setdefault(road_file, RoadNetwork.from_file(road_file))
        for _, x, y, heading, speed in samples:
            coord = network.to_road(x, y, heading=heading)
            assert coord is not None
            total += 1
            on_road += coord.distance <= 0.01
            if speed > 1.0 and coord.on_road:
                moving += 1
                aligned += abs(math.remainder(heading - coord.heading_of_road, math.pi)) < 0.35
    assert on_road / total >= 0.99, f"{on_road}/{total} on the road"
    assert aligned / moving >= 0.97, f"{aligned}/{moving} aligned with the road"


@pytest.mark.parametrize(
    "name", ["scenario_nurb_curved_road.xodr", "scenario_runner_with_acts.xodr"]
)
def test_generated_maps_parse(name: str) -> None:
    (path,) = CORPUS.glob(f"esmini/resources/**/{name}")
    network = RoadNetwork.from_file(path)
    assert network.roads
