"""The library has the promised shape and every scenario is a self-contained SUT test case.

Covers: 200 suite scenarios in the eight category folders, on at least three road networks,
plus the search benchmark's folders (SEARCH_CATEGORIES, outside the 200, which the seed campaign
excludes);
the smoke set has 5-6 scenarios of at most 10 s; FileHeader properties simtest:tags /
simtest:category / simtest:road agree with the folder and the referenced road, and tags use
the documented vocabulary; the ego is called Ego, carries the simtest:sut controller, gets its
speed from a SpeedAction and both domains activated at init; the storyboard stops on
SimulationTime within 10-35 s; every $parameter used is declared; road files resolve.
"""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest
import yaml
from lxml import etree

from simtest_operator.api import v1alpha1
from simtest_operator.scenarios import selecting
from tests.library.conftest import LIBRARY_ROOT

CATEGORIES = {
    "following",
    "cut-in",
    "cut-out",
    "hard-braking",
    "lane-change",
    "merge",
    "ltap",
    "pedestrian-crossing",
}
SEARCH_CATEGORIES = {"pedestrian-turn-back"}
"""Logical scenarios for bench/search.py, generated into library/ but not part of the suite."""
LIBRARY = sorted(LIBRARY_ROOT.glob("library/*/*.xosc"))
SUITE = [path for path in LIBRARY if path.parent.name not in SEARCH_CATEGORIES]
SEARCH = [path for path in LIBRARY if path.parent.name in SEARCH_CATEGORIES]
SMOKE = sorted(LIBRARY_ROOT.glob("smoke/*.xosc"))
PARAMETER_REF = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


def _vocabulary() -> set[str]:
    """Tags documented in scenarios/README.md (the backticked words of its tag table)."""
    text = (LIBRARY_ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Tags", 1)[1].split("\n## ", 1)[0]
    return set(re.findall(r"`([a-z][a-z-]*)`", section))


def _properties(tree: etree._ElementTree) -> dict[str, str]:
    return {p.get("name"): p.get("value") for p in tree.findall("FileHeader/Properties/Property")}


def test_suite_size_categories_and_roads() -> None:
    assert len(SUITE) == 200
    per_category = Counter(path.parent.name for path in SUITE)
    assert set(per_category) == CATEGORIES
    assert min(per_category.values()) >= 10
    roads = {_properties(etree.parse(str(path)))["simtest:road"] for path in SUITE}
    assert len(roads) >= 3
    assert {path.parent.name for path in SEARCH} == SEARCH_CATEGORIES


def test_the_seed_campaign_runs_exactly_the_suite() -> None:
    document = yaml.safe_load((LIBRARY_ROOT / "seed-experiment-campaign.yaml").read_text())
    scenarios = v1alpha1.parse_campaign(document).spec.scenarios
    library = LIBRARY_ROOT / "library"
    chosen = selecting.by_globs(
        [path.relative_to(library).as_posix() for path in LIBRARY],
        include=tuple(scenarios.include),
        exclude=tuple(scenarios.exclude),
    )
    assert chosen == sorted(path.relative_to(library).as_posix() for path in SUITE)


def test_smoke_set_is_small_and_short() -> None:
    assert 5 <= len(SMOKE) <= 6
    for path in SMOKE:
        end = etree.parse(str(path)).find(
            "Storyboard/StopTrigger/ConditionGroup/Condition/ByValueCondition/SimulationTimeCondition"
        )
        assert end is not None and float(end.get("value")) <= 10.0, path.name


@pytest.mark.parametrize("path", LIBRARY + SMOKE, ids=lambda p: p.stem)
def test_scenario_is_a_self_contained_sut_case(path: Path) -> None:
    tree = etree.parse(str(path))
    props = _properties(tree)
    assert set(props) == {"simtest:tags", "simtest:category", "simtest:road"}
    tags = props["simtest:tags"].split(",")
    assert props["simtest:category"] in CATEGORIES | SEARCH_CATEGORIES
    assert tags[0] == props["simtest:category"]
    assert set(tags) <= _vocabulary(), set(tags) - _vocabulary()
    if path.parent.parent.name == "library":
        assert path.parent.name == props["simtest:category"]
    assert path.stem.startswith(props["simtest:category"] + "_")

    logic = tree.find("RoadNetwork/LogicFile")
    assert logic is not None
    road = (path.parent / logic.get("filepath")).resolve()
    assert road.is_file() and road.stem == props["simtest:road"]

    ego = tree.find("Entities/ScenarioObject[@name='Ego']")
    assert ego is not None
    sut = ego.find("ObjectController/Controller/Properties/Property[@name='simtest:sut']")
    assert sut is not None and sut.get("value") == "true"
    init = tree.find("Storyboard/Init/Actions/Private[@entityRef='Ego']")
    assert init is not None
    assert init.find(".//TeleportAction/Position/LanePosition") is not None
    assert init.find(".//SpeedAction/SpeedActionTarget/AbsoluteTargetSpeed") is not None
    activate = init.find(".//ActivateControllerAction")
    assert activate is not None
    assert (activate.get("longitudinal"), activate.get("lateral")) == ("true", "true")

    stop = tree.find(
        "Storyboard/StopTrigger/ConditionGroup/Condition/ByValueCondition/SimulationTimeCondition"
    )
    assert stop is not None and 10.0 <= float(stop.get("value")) <= 35.0

    declared = {d.get("name") for d in tree.iter("ParameterDeclaration")}
    used = {
        name
        for element in tree.iter()
        for value in element.attrib.values()
        for name in PARAMETER_REF.findall(value)
    }
    assert used <= declared, used - declared
    assert used, "the scenario is not parameterised"


def test_names_are_unique_across_the_library() -> None:
    stems = [path.stem for path in LIBRARY]
    assert len(stems) == len(set(stems))
