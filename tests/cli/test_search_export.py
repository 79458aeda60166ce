"""``simtest search export`` writes a self-contained regression suite.

Covers: the exported concrete scenarios carry copies of the road network they reference, so
``simtest scenario check`` runs them from the export folder alone (no ``--root``, the logical
scenario's tree deleted); catalog directories are copied with their ``.xosc`` files; a name
another export already holds with other content gets a suffix; a reference that resolves outside
the scenario's source root is refused, not copied.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import concretising, load_scenario
from simtest_operator.openscenario.confinement import Confinement
from simtest_operator.runner import campaigns, preparing
from simtest_operator.settings import Settings
from tests.runner import search_engine

pytestmark = pytest.mark.timeout(180)

REPO = Path(__file__).resolve().parents[2]
CUT_IN = REPO / "scenarios/library/cut-in/cut-in_highway_v25_gap15_dv10.xosc"
ROAD = REPO / "scenarios/roads/highway_straight.xodr"
MANIFEST = """apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata:
  name: search
spec:
  scenarios:
    sources:
      - path: tree
  search:
    scenario: library/cut-in/cut-in.xosc
    parameters:
      - {name: EgoSpeed, min: 15, max: 35}
      - {name: CutInGap, min: 5, max: 40}
    strategy: random
    budget: 6
    seed: 5
  execution:
    timeoutSeconds: 30
    retries: 0
"""


def _tree(folder: Path) -> Path:
    """The logical scenario in a tree of its own: ``library/cut-in/`` beside ``roads/``."""
    (folder / "tree/library/cut-in").mkdir(parents=True)
    (folder / "tree/roads").mkdir()
    shutil.copy(CUT_IN, folder / "tree/library/cut-in/cut-in.xosc")
    shutil.copy(ROAD, folder / "tree/roads/highway_straight.xodr")
    return folder / "tree/library/cut-in/cut-in.xosc"


def test_exported_scenarios_run_from_the_export_folder_alone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _tree(tmp_path)
    manifest = tmp_path / "campaign.yaml"
    manifest.write_text(MANIFEST)
    request = preparing.LocalRunRequest(
        manifest=manifest, output=tmp_path / "out",
        settings=Settings.from_env({"HOME": str(tmp_path / "home")}),
        execute=search_engine.execute, parallel=2,
    )  # fmt: skip
    assert campaigns.run(request).summary.total == 6
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), "HOME": str(tmp_path / "home")}
    monkeypatch.chdir(tmp_path)
    suite = tmp_path / "suite"
    exported = CliRunner().invoke(
        cli, ["search", "export", "out", "--out", str(suite), "--top", "2"], env=env
    )
    assert exported.exit_code == 0, exported.output
    assert sorted(p.relative_to(suite).as_posix() for p in suite.rglob("*.*")) == sorted(
        [*(p.name for p in suite.glob("*.xosc")), "roads/highway_straight.xodr"]
    )
    assert len(list(suite.glob("*.xosc"))) == 2
    shutil.rmtree(tmp_path / "tree")  # the logical scenario's tree is gone
    moved = shutil.move(suite, tmp_path / "elsewhere")
    checked = CliRunner().invoke(cli, ["scenario", "check", str(moved), "-j", "1"], env=env)
    assert checked.exit_code == 0, checked.output
    assert "2 ran, 0 invalid, 0 errors" in checked.output, checked.output


CATALOG = """<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2024-01-01T00:00:00" description="c" author="t"/>
  <Catalog name="VehicleCatalog"/>
</OpenSCENARIO>
"""


def _with_catalog(scenario: Path, directory: str) -> None:
    text = scenario.read_text().replace(
        "<CatalogLocations />",
        f'<CatalogLocations><VehicleCatalog><Directory path="{directory}"/></VehicleCatalog>'
        "</CatalogLocations>",
    )
    assert directory in text
    scenario.write_text(text)


def test_catalog_directories_are_copied_and_clashing_names_suffixed(tmp_path: Path) -> None:
    scenario = _tree(tmp_path)
    catalogs = tmp_path / "tree/catalogs/vehicles"
    catalogs.mkdir(parents=True)
    (catalogs / "VehicleCatalog.xosc").write_text(CATALOG)
    (catalogs / "notes.txt").write_text("not read by the reader, not copied")
    _with_catalog(scenario, "../../catalogs/vehicles")
    out = tmp_path / "suite"
    (out / "roads").mkdir(parents=True)
    (out / "roads/highway_straight.xodr").write_text("another export's road")
    confinement = Confinement.for_scenario(scenario, tmp_path / "tree")
    copied = concretising.bundle(scenario, out, confinement=confinement)
    assert copied == {
        "../../roads/highway_straight.xodr": "roads-2/highway_straight.xodr",
        "../../catalogs/vehicles": "vehicles",
    }
    assert (out / "roads-2/highway_straight.xodr").read_bytes() == ROAD.read_bytes()
    assert sorted(p.name for p in (out / "vehicles").iterdir()) == ["VehicleCatalog.xosc"]
    again = concretising.bundle(scenario, out, confinement=confinement)
    assert again == copied  # the same files: the copies are reused
    concrete = out / "concrete.xosc"
    concrete.write_bytes(concretising.concretise(scenario, {"EgoSpeed": "30"}, references=copied))
    loaded = load_scenario(concrete)
    assert loaded.road_network.logic_file == (out / "roads-2/highway_straight.xodr").resolve()


def test_a_reference_outside_the_source_root_is_refused(tmp_path: Path) -> None:
    scenario = _tree(tmp_path)
    secret = tmp_path / "private"
    secret.mkdir()
    (secret / "keys.xosc").write_text(CATALOG)
    _with_catalog(scenario, "../../../private")
    confinement = Confinement.for_scenario(scenario, tmp_path / "tree")
    with pytest.raises(ScenarioError, match="outside the scenario's source root"):
        concretising.bundle(scenario, tmp_path / "suite", confinement=confinement)
    assert not (tmp_path / "suite/private").exists()
