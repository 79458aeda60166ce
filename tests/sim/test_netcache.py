"""netconvert cache: miss then hit with the same path, key changes with the content, concurrent
conversions of one map, the fallbacks for the known-broken esmini maps (--ignore-errors for
soderleden, signals stripped for straight_500m_signs), a failing map raising SimulationError with
netconvert's stderr, and the origId lane mapping (normal and junction-internal lanes)."""

from __future__ import annotations

import concurrent.futures
from pathlib import Path

import pytest

from simtest_operator.errors import SimulationError
from simtest_operator.sim import netcache

XODR_DIR = (
    Path(__file__).resolve().parents[3]
    / "shared"
    / "scenarios-dev"
    / "esmini"
    / "resources"
    / "xodr"
)


def test_miss_then_hit(tmp_path: Path) -> None:
    first = netcache.ensure_net(XODR_DIR / "straight_500m.xodr", cache_dir=tmp_path)
    second = netcache.ensure_net(XODR_DIR / "straight_500m.xodr", cache_dir=tmp_path)
    assert not first.from_cache
    assert second.from_cache
    assert first.path == second.path
    assert first.path.parent == tmp_path
    assert b"origId" in first.path.read_bytes()
    assert second.seconds < first.seconds
    assert [p.name for p in tmp_path.iterdir()] == [first.path.name]


def test_key_follows_content(tmp_path: Path) -> None:
    source = (XODR_DIR / "straight_500m.xodr").read_bytes()
    copy = tmp_path / "copy.xodr"
    copy.write_bytes(source)
    a = netcache.ensure_net(copy, cache_dir=tmp_path / "nets")
    copy.write_bytes(source.replace(b'name=""', b'name="renamed"', 1))
    b = netcache.ensure_net(copy, cache_dir=tmp_path / "nets")
    assert a.path != b.path
    assert not b.from_cache


def test_concurrent_conversions_of_one_map(tmp_path: Path) -> None:
    with concurrent.futures.ThreadPoolExecutor(max_workers=3) as pool:
        results = list(
            pool.map(
                lambda _: netcache.ensure_net(XODR_DIR / "curve_r100.xodr", cache_dir=tmp_path),
                range(3),
            )
        )
    assert len({result.path for result in results}) == 1
    assert results[0].path.read_bytes().rstrip().endswith(b"</net>")
    assert [p.name for p in tmp_path.iterdir()] == [results[0].path.name]


@pytest.mark.parametrize("name", ["soderleden.xodr", "straight_500m_signs.xodr"])
def test_known_broken_maps_convert_with_fallbacks(tmp_path: Path, name: str) -> None:
    converted = netcache.ensure_net(XODR_DIR / name, cache_dir=tmp_path)
    assert b"<edge id=" in converted.path.read_bytes()


def test_failure_raises_with_stderr_tail(tmp_path: Path) -> None:
    broken = tmp_path / "broken.xodr"
    broken.write_text(
        '<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="4"/>'
        '<road id="1" length="-5" junction="-1"><planView>'
        '<geometry s="0" x="0" y="0" hdg="0" length="abc"><line/></geometry>'
        "</planView><lanes/></road></OpenDRIVE>"
    )
    with pytest.raises(SimulationError) as caught:
        netcache.ensure_net(broken, cache_dir=tmp_path / "nets")
    message = str(caught.value)
    assert "netconvert failed" in message
    assert "[without signals, --ignore-errors]" in message
    assert "rc=" in message
    assert not list((tmp_path / "nets").glob("*.net.xml"))


def test_lane_origins_map_roads_and_connecting_roads(tmp_path: Path) -> None:
    converted = netcache.ensure_net(XODR_DIR / "fabriksgatan.xodr", cache_dir=tmp_path)
    origins = netcache.lane_origins(converted.path)
    assert origins[("0", -1)] == ("-0_0",)
    assert origins[("0", 1)] == ("0_0",)
    # Road 6 is a connecting road of junction 4: it becomes an internal lane.
    assert all(lane.startswith(":4_") for lane in origins[("6", -1)])


@pytest.mark.parametrize(
    ("shape", "end"),
    [
        ('<spiral curvStart="0" curvEnd="0"/>', (200.0, -1.75)),  # a line
        ('<arc curvature="0"/>', (200.0, -1.75)),  # a line; netconvert made it -nan,-nan
        ('<spiral curvStart="0.005" curvEnd="0.005"/>', (169.76, 90.99)),  # an arc of 1 rad
    ],
)
def test_flat_curves_convert_to_their_shape(
    tmp_path: Path, shape: str, end: tuple[float, float]
) -> None:
    # netconvert cannot evaluate these (issue 29: "No edges loaded" / "-nan,-nan", an Error that
    # was retried); they reach it as the equivalent line or arc, and this reader agrees.
    import sumolib

    from simtest_operator.opendrive import RoadNetwork
    from tests.opendrive.conftest import single_road

    data = single_road(
        f'<geometry s="0" x="0" y="0" hdg="0" length="200">{shape}</geometry>', length=200
    )
    xodr = tmp_path / "flat.xodr"
    xodr.write_bytes(data)
    net = netcache.ensure_net(xodr, cache_dir=tmp_path / "nets")
    edge = sumolib.net.readNet(str(net.path)).getEdge("-r")  # lane -1, along the road
    assert edge.getShape()[-1] == pytest.approx(end, abs=0.02)
    pose = RoadNetwork.from_bytes(data).lane_pose("r", 200.0, -1)
    assert (pose.x, pose.y) == pytest.approx(end, abs=0.02)
