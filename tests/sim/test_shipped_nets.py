"""Converted networks shipped beside their maps (``simtest scenario nets``): a run on a fresh
cache loads the shipped network without netconvert (a read-only scenario folder, as a pod mounts
it); a shipped network for another map content is not used; the CLI ships every map under a
folder once and reports maps netconvert cannot convert."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.scenario import scenario
from simtest_operator.sim import netcache

ROADS = Path(__file__).resolve().parents[2] / "scenarios" / "roads"


@pytest.fixture
def staged(tmp_path: Path) -> Path:
    """A scenario folder with one map, as it is staged before pods mount it."""
    folder = tmp_path / "scenarios"
    folder.mkdir()
    shutil.copy(ROADS / "highway_straight.xodr", folder / "highway.xodr")
    return folder


def _files(root: Path) -> dict[Path, int]:
    return {path: path.stat().st_mtime_ns for path in root.rglob("*") if path.is_file()}


def test_a_shipped_network_is_loaded_without_netconvert(staged: Path, tmp_path: Path) -> None:
    shipped = netcache.ship_net(staged / "highway.xodr")
    assert not shipped.from_cache
    assert shipped.path.parent == staged / netcache.SHIPPED_DIR
    before = _files(staged)
    pod_cache = tmp_path / "pod-cache"  # the pod's emptyDir: empty in every new pod
    found = netcache.ensure_net(staged / "highway.xodr", cache_dir=pod_cache)
    assert _files(staged) == before, "the scenario volume is only read"
    assert found.from_cache
    assert found.path == shipped.path
    assert not pod_cache.exists(), "nothing converted into the pod's own cache"


def test_a_network_shipped_for_other_map_content_is_not_used(staged: Path, tmp_path: Path) -> None:
    xodr = staged / "highway.xodr"
    stale = netcache.ship_net(xodr)
    xodr.write_bytes(xodr.read_bytes().replace(b"<header", b"<!-- edited -->\n<header", 1))
    converted = netcache.ensure_net(xodr, cache_dir=tmp_path / "cache")
    assert not converted.from_cache
    assert converted.path.parent == tmp_path / "cache"
    assert converted.path.name != stale.path.name


def test_the_cli_ships_every_map_once_and_names_the_ones_it_cannot_convert(
    staged: Path,
) -> None:
    (staged / "sub").mkdir()
    shutil.copy(ROADS / "junction_4way.xodr", staged / "sub" / "junction.xodr")
    (staged / "broken.xodr").write_text("<OpenDRIVE><road/></OpenDRIVE>")
    runner = CliRunner()
    first = runner.invoke(scenario, ["nets", str(staged)])
    assert first.exit_code == 0, first.output
    assert "3 maps: 2 converted, 0 shipped already, 1 not convertible" in first.output
    assert f"not converted: {staged / 'broken.xodr'}" in first.output
    assert len(list((staged / netcache.SHIPPED_DIR).glob("*.net.xml"))) == 1
    assert len(list((staged / "sub" / netcache.SHIPPED_DIR).glob("*.net.xml"))) == 1
    shipped = _files(staged)
    second = runner.invoke(scenario, ["nets", str(staged)])
    assert "3 maps: 0 converted, 2 shipped already, 1 not convertible" in second.output
    assert _files(staged) == shipped
