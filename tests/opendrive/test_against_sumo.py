"""Lane centres against SUMO: every esmini road converted by netconvert (x/y kept, ``origId`` on
each lane), points along each SUMO lane shape projected onto our road, our lane centre at that s
compared with the SUMO polyline (< 0.2 m). Compared where SUMO's own approximation is exact
enough to be a reference: flat cross-sections (netconvert draws banked lanes flat) that do not
change within +-5 m (netconvert draws width and lane-offset transitions as straight chords
between section boundaries, e.g. 1.3 m off on two_plus_one), no zero-width inner lanes
(netconvert drops them), and junction-internal lanes only where their radius is not below
netconvert's curve resolution (parking_demo's 5 m turns are excluded)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sumolib

from simtest_operator.opendrive import RoadNetwork
from simtest_operator.sim import netcache

MAPS = [
    "circle_300m", "crest-curve", "curve_r100", "curves_elevation", "e6mini", "e6mini-lht",
    "fabriksgatan", "jolengatan", "multi_intersections", "parking_demo", "soderleden",
    "straight_500m", "tunnels", "two_plus_one", "velodrome",
]  # fmt: skip
TOLERANCE = 0.2


def polyline_distance(point: tuple[float, float], shape: np.ndarray) -> float:
    start, end = shape[:-1], shape[1:]
    direction = end - start
    length2 = np.maximum((direction * direction).sum(axis=1), 1e-12)
    u = np.clip(((np.asarray(point) - start) * direction).sum(axis=1) / length2, 0.0, 1.0)
    nearest = start + u[:, None] * direction
    return float(np.min(np.hypot(*(np.asarray(point) - nearest).T)))


def steady(net: RoadNetwork, road_id: str, s: float, lane_id: int) -> bool:
    """Cross-section constant around s and no narrow lane between the centre and ``lane_id``."""
    length = net.road_length(road_id)
    if net.lane_section_index(road_id, max(s - 5, 0)) != net.lane_section_index(
        road_id, min(s + 5, length)
    ):
        return False
    for probe in (max(s - 5, 0), s, min(s + 5, length)):
        if abs(net.roll(road_id, probe)) > 1e-9:
            return False  # netconvert draws banked lanes flat; OpenDRIVE's t rolls with the road
        lanes = net.lanes_at(road_id, probe)
        if any(abs(b.slope_inner) > 1e-9 or abs(b.slope_outer) > 1e-9 for b in lanes):
            return False
        inner = [
            b for b in lanes if (b.lane_id > 0) == (lane_id > 0) and abs(b.lane_id) <= abs(lane_id)
        ]
        if len(inner) != abs(lane_id) or any(b.width < 0.5 for b in inner):
            return False
    return True


def lane_errors(net: RoadNetwork, net_file: Path, *, internal: bool) -> list[float]:
    sumo_net = sumolib.net.readNet(str(net_file), withInternal=True)
    errors: list[float] = []
    for edge in sumo_net.getEdges(withInternal=True):
        if (edge.getFunction() == "internal") != internal:
            continue
        for lane in edge.getLanes():
            origin = lane.getParam("origId") or ""
            road_id, _, lane_text = origin.rpartition("_")
            if road_id not in net.roads:
                continue
            lane_id = int(lane_text)
            shape = np.array([point[:2] for point in lane.getShape()])
            for x, y in (shape[:-1] + shape[1:]) / 2:
                coord = net.to_road(float(x), float(y), road_id)
                if coord is None or coord.road_id != road_id:
                    continue
                if not 0.5 < coord.s < net.road_length(road_id) - 0.5:
                    continue
                if not steady(net, road_id, coord.s, lane_id):
                    continue
                pose = net.lane_pose(road_id, coord.s, lane_id)
                errors.append(polyline_distance((pose.x, pose.y), shape))
    return errors


@pytest.fixture(scope="module")
def nets_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("nets")


@pytest.mark.parametrize("name", MAPS)
def test_lane_centres_match_sumo(name: str, xodr_dir: Path, nets_dir: Path) -> None:
    path = xodr_dir / f"{name}.xodr"
    net = RoadNetwork.from_file(path)
    converted = netcache.ensure_net(path, cache_dir=nets_dir)
    errors = lane_errors(net, converted.path, internal=False)
    assert len(errors) >= 2, "nothing compared"
    assert max(errors) < TOLERANCE, f"median {np.median(errors):.3f} max {max(errors):.3f}"


@pytest.mark.parametrize("name", ["fabriksgatan", "multi_intersections"])
def test_junction_lane_centres_match_sumo(name: str, xodr_dir: Path, nets_dir: Path) -> None:
    path = xodr_dir / f"{name}.xodr"
    net = RoadNetwork.from_file(path)
    errors = lane_errors(net, netcache.ensure_net(path, cache_dir=nets_dir).path, internal=True)
    assert len(errors) >= 20
    assert max(errors) < TOLERANCE


def test_a_map_with_a_header_offset_keeps_sumos_frame(xodr_dir: Path, nets_dir: Path) -> None:
    # netconvert keeps x/y in the file's frame whatever the header <offset> says, and so do our
    # roads (the offset moves only reported paths): SUMO traffic drives on our lanes
    path = xodr_dir.parents[1] / "EnvironmentSimulator" / "Unittest" / "xodr" / "offset.xodr"
    net = RoadNetwork.from_file(path)
    assert net.document.offset is not None
    errors = lane_errors(net, netcache.ensure_net(path, cache_dir=nets_dir).path, internal=False)
    assert len(errors) >= 2, "nothing compared"
    assert max(errors) < TOLERANCE
