"""References stay in the scenario's source tree (issue 12, item 5).

Covers: a LogicFile ``../../etc/passwd`` (the carla/ test file) and an absolute ``/etc/passwd``
are refused with the reason and never opened; a symlink inside the tree that points out is
refused; ``../`` inside the tree keeps working; CatalogLocations outside the root are not read
(the error says refused); a catalog file symlinked out of its folder is skipped; with no root
given, system folders are still refused; the scenario size limit is configurable.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import LoadOptions, load_scenario
from tests.openscenario.conftest import ScenarioWriter

CARLA_DIR = Path(__file__).resolve().parent / "carla"


def test_passwd_through_dotdot_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError) as caught:
        load_scenario(CARLA_DIR / "escape_passwd.xosc", options=LoadOptions(source_root=CARLA_DIR))
    message = str(caught.value)
    assert f"refused: /etc/passwd is outside the scenario's source root {CARLA_DIR}" in message
    assert caught.value.element == "LogicFile" and caught.value.line == 7
    # No root given and no git work tree around: system folders are still refused.
    copy = tmp_path / "escape.xosc"
    copy.write_bytes((CARLA_DIR / "escape_passwd.xosc").read_bytes())
    with pytest.raises(ScenarioError, match="refused: /etc/passwd is in a system folder"):
        load_scenario(copy)


def test_absolute_and_symlinked_escapes_are_refused(
    tmp_path: Path, write_scenario: ScenarioWriter
) -> None:
    secret = tmp_path.parent / f"{tmp_path.name}-secret.xodr"
    secret.write_text("<OpenDRIVE/>", encoding="utf-8")
    (tmp_path / "road.xodr").symlink_to(secret)
    options = LoadOptions(source_root=tmp_path)
    for road in (f'<LogicFile filepath="{secret}"/>', '<LogicFile filepath="road.xodr"/>'):
        path = write_scenario(road=road)
        with pytest.raises(ScenarioError, match=f"refused: {secret} is outside"):
            load_scenario(path, options=options)
    proc = write_scenario(road='<LogicFile filepath="/proc/self/environ"/>')
    with pytest.raises(ScenarioError, match=r"refused: /proc/[0-9]+/environ is in a system folder"):
        load_scenario(proc)


def test_dotdot_inside_the_tree_still_works(tmp_path: Path, write_scenario: ScenarioWriter) -> None:
    roads = tmp_path / "roads"
    roads.mkdir()
    (roads / "r.xodr").write_text("<OpenDRIVE/>", encoding="utf-8")
    (tmp_path / "suite").mkdir()
    path = write_scenario(name="suite/s.xosc", road='<LogicFile filepath="../roads/r.xodr"/>')
    scenario = load_scenario(path, options=LoadOptions(source_root=tmp_path))
    assert scenario.road_network.logic_file == roads / "r.xodr"
    with pytest.raises(ScenarioError, match="outside the scenario's source root"):
        load_scenario(path, options=LoadOptions(source_root=tmp_path / "suite"))


def test_catalogs_outside_the_root_are_not_read(
    tmp_path: Path, write_scenario: ScenarioWriter
) -> None:
    (tmp_path / "suite").mkdir()
    entities = """<ScenarioObject name="Ego">
    <CatalogReference catalogName="c" entryName="car"/></ScenarioObject>"""
    path = write_scenario(
        name="suite/s.xosc",
        catalogs='<VehicleCatalog><Directory path="../../../../etc"/></VehicleCatalog>',
        entities=entities,
    )
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path, options=LoadOptions(source_root=tmp_path / "suite"))
    assert "refused (outside the scenario's source root" in str(caught.value)
    assert "/etc" in str(caught.value)


def test_catalog_symlinked_out_of_its_folder_is_skipped(
    tmp_path: Path, write_scenario: ScenarioWriter
) -> None:
    outside = tmp_path.parent / f"{tmp_path.name}-cat.xosc"
    outside.write_text("<not-read/>", encoding="utf-8")
    folder = tmp_path / "Vehicles"
    folder.mkdir()
    (folder / "evil.xosc").symlink_to(outside)
    entities = """<ScenarioObject name="Ego">
    <CatalogReference catalogName="c" entryName="car"/></ScenarioObject>"""
    path = write_scenario(
        catalogs='<VehicleCatalog><Directory path="Vehicles"/></VehicleCatalog>', entities=entities
    )
    with pytest.raises(ScenarioError, match="has no Vehicle/Pedestrian/MiscObject entry 'car'"):
        load_scenario(path, options=LoadOptions(source_root=tmp_path))


def test_scenario_size_limit(write_scenario: ScenarioWriter) -> None:
    path = write_scenario()
    size = path.stat().st_size
    assert load_scenario(path, options=LoadOptions(max_bytes=size)).entities
    with pytest.raises(ScenarioError, match="larger than"):
        load_scenario(path, options=LoadOptions(max_bytes=size - 1))
