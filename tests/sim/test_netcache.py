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
