"""World point -> road coordinates: round trips lane_pose -> to_road on every esmini map (s and t
to 1e-6 m when hinted with the road), lane id and type, off-road distance beside and beyond a
road, drivable vs any lane for is_on_road, hints and heading choosing among overlapping junction
roads, and the hinted fast path for continuous tracking."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simtest_operator.opendrive import RoadNetwork
from tests.opendrive.conftest import single_road

MAPS = sorted(
    p.name
    for p in (Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini"
              / "resources" / "xodr").glob("*.xodr")
)  # fmt: skip


@pytest.mark.parametrize("name", MAPS)
def test_lane_pose_round_trip(name: str, xodr_dir: Path) -> None:
    net = RoadNetwork.from_file(xodr_dir / name)
    checked = 0
    for road in net.document.roads:
        for k in range(1, 5):
            s = road.length * k / 5
            for bounds in net.lanes_at(road.id, s):
                if bounds.width < 1.0:
                    continue
                pose = net.lane_pose(road.id, s, bounds.lane_id, offset=0.3)
                coord = net.to_road(pose.x, pose.y, road.id)
                assert coord is not None
                assert coord.road_id == road.id
                assert coord.s == pytest.approx(s, abs=1e-6)
                assert coord.t == pytest.approx(bounds.t_center + 0.3, abs=1e-6)
                assert coord.lane_id == bounds.lane_id
                assert coord.lane_type == bounds.type
                assert coord.on_road
                checked += 1
    assert checked >= 4


def test_unhinted_projection_finds_the_lane(xodr_dir: Path) -> None:
    net = RoadNetwork.from_file(xodr_dir / "curve_r100.xodr")
    pose = net.lane_pose("0", 580.0, -1)
    coord = net.to_road(pose.x, pose.y)
    assert coord is not None
    assert (coord.road_id, coord.lane_id) == ("0", -1)
    assert coord.s == pytest.approx(580.0, abs=1e-6)
    assert coord.heading_of_road == pytest.approx(pose.heading, abs=1e-9)


def test_off_road_distances_and_lane_types() -> None:
    net = RoadNetwork.from_bytes(
        single_road(
            '<geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry>', length=100
        )
    )
    # Lanes: 1 (driving, 0..3.5), -1 (driving, -3.5..0), -2 (sidewalk, -5.5..-3.5).
    beside = net.to_road(50.0, 6.0)
    assert beside is not None
    assert beside.distance == pytest.approx(2.5)
    assert beside.lane_id == 1
    assert not beside.on_road
    beyond = net.to_road(103.0, -1.0)
    assert beyond is not None
    assert (beyond.s, beyond.distance) == (100.0, pytest.approx(3.0))
    assert net.is_on_road(50.0, -1.0)
    assert not net.is_on_road(50.0, -4.5)
    assert net.is_on_road(50.0, -4.5, drivable_only=False)
    assert not net.is_on_road(50.0, -6.0, drivable_only=False)


def test_hint_and_heading_choose_among_overlapping_roads(xodr_dir: Path) -> None:
    net = RoadNetwork.from_file(xodr_dir / "fabriksgatan.xodr")
    junction_roads = [road for road in net.document.roads if road.in_junction]
    for road in junction_roads:
        pose = net.lane_pose(road.id, road.length / 2, -1)
        hinted = net.to_road(pose.x, pose.y, road.id)
        assert hinted is not None and hinted.road_id == road.id
        by_heading = net.to_road(pose.x, pose.y, heading=pose.heading)
        assert by_heading is not None and by_heading.on_road
        difference = abs(math.remainder(pose.heading - by_heading.heading_of_road, math.pi))
        assert difference < 0.3
    assert len(junction_roads) >= 8


def test_tracking_with_previous_coordinates(xodr_dir: Path) -> None:
    net = RoadNetwork.from_file(xodr_dir / "velodrome.xodr")
    road = net.document.roads[0]
    start = net.lane_pose(road.id, 1.0, -1)
    previous = net.to_road(start.x, start.y)
    assert previous is not None
    for step in range(1, 200):
        s = 1.0 + step * 2.5
        pose = net.lane_pose(road.id, s, -1)
        coord = net.to_road(pose.x, pose.y, previous)
        assert coord is not None
        assert coord.s == pytest.approx(s, abs=1e-6)
        previous = coord


def test_lateral_offsets_roll_with_the_superelevation() -> None:
    # OpenDRIVE's t axis lies in the banked cross-section (esmini places entities so): 60 degrees
    # of superelevation halve how far a lane centre reaches sideways and lower it; the
    # projection finds the same t back.
    document = (
        '<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>'
        '<road id="r" length="100" junction="-1"><planView><geometry s="0" x="0" y="0" hdg="0" '
        'length="100"><line/></geometry></planView>'
        f'<lateralProfile><superelevation s="0" a="{math.pi / 3}" b="0" c="0" d="0"/>'
        '</lateralProfile><lanes><laneSection s="0"><center><lane id="0" type="none"/></center>'
        '<right><lane id="-1" type="driving"><width sOffset="0" a="4"/></lane></right>'
        "</laneSection></lanes></road></OpenDRIVE>"
    )
    net = RoadNetwork.from_bytes(document.encode())
    pose = net.lane_pose("r", 10.0, -1)
    assert (pose.x, pose.y, pose.z) == pytest.approx((10.0, -1.0, -math.sqrt(3.0)))
    coord = net.to_road(pose.x, pose.y, "r")
    assert coord is not None
    assert (coord.s, coord.t, coord.lane_id) == pytest.approx((10.0, -2.0, -1))
