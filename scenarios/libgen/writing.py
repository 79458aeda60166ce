"""Turn blueprints and road networks into files, byte for byte the same on every run.

Layout under the output folder:
    roads/<road>.xodr                 OpenDRIVE networks
    library/<category>/<stem>.xosc    the 200-scenario suite and the search cases
    smoke/<stem>.xosc                 the short quick-start set

Scenario files reference their road relative to themselves, so a copy of the whole folder
(or a git checkout) runs anywhere. Stale .xosc/.xodr files from an earlier grid are removed.
"""

from __future__ import annotations

import datetime as dt
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from scenariogeneration import xosc

from libgen import roads
from libgen.blueprints import Blueprint, number

AUTHOR = "simtest-operator scenario library"
CREATED = dt.datetime(2026, 1, 1, 0, 0, 0)
"""Fixed creation date: the files must not change when nothing else did."""

_FLOAT = re.compile(r"^-?\d+\.\d+(e-?\d+)?$")


def _tidy_numbers(root: ET.Element) -> None:
    """scenariogeneration writes 30 as '30.0' and angles with 16 digits; shorten them."""
    for element in root.iter():
        for key, value in element.attrib.items():
            if _FLOAT.match(value):
                as_float = float(value)
                text = "0" if abs(as_float) < 1e-9 else format(as_float, ".10g")
                element.set(key, text)


def _to_bytes(root: ET.Element) -> bytes:
    ET.indent(root, space="  ")
    text: bytes = ET.tostring(root, encoding="utf-8", xml_declaration=True)
    return text + b"\n"


def scenario_bytes(blueprint: Blueprint, road_path: str) -> bytes:
    """The .xosc text of one blueprint; `road_path` is the .xodr path relative to the file."""
    declarations = xosc.ParameterDeclarations()
    for name, value in blueprint.parameters:
        declarations.add_parameter(xosc.Parameter(name, xosc.ParameterType.double, number(value)))
    stop = xosc.ValueTrigger(
        "ScenarioEnd",
        0,
        xosc.ConditionEdge.none,
        xosc.SimulationTimeCondition(blueprint.duration, xosc.Rule.greaterThan),
        "stop",
    )
    storyboard = xosc.StoryBoard(blueprint.init, stop)
    for story in blueprint.stories:
        storyboard.add_story(story)
    properties = xosc.Properties()
    properties.add_property("simtest:tags", ",".join(blueprint.tags))
    properties.add_property("simtest:category", blueprint.category)
    properties.add_property("simtest:road", blueprint.road.name)
    scenario = xosc.Scenario(
        blueprint.description,
        AUTHOR,
        declarations,
        blueprint.entities,
        storyboard,
        xosc.RoadNetwork(roadfile=road_path),
        xosc.Catalog(),
        osc_minor_version=2,
        creation_date=CREATED,
        header_properties=properties,
    )
    root: ET.Element = scenario.get_element()
    _tidy_numbers(root)
    return _to_bytes(root)


def road_bytes(net: roads.RoadNet) -> bytes:
    """The .xodr text of one road network."""
    return _to_bytes(roads.render(net))


def _write(path: Path, data: bytes, written: set[Path]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_bytes() != data:
        path.write_bytes(data)
    written.add(path)


def write_all(
    out: Path, suite: list[Blueprint], smoke: list[Blueprint], search: list[Blueprint]
) -> list[Path]:
    """Write roads, suite, search cases and smoke set under `out`; return the files, sorted."""
    written: set[Path] = set()
    for net in roads.ALL:
        _write(out / "roads" / f"{net.name}.xodr", road_bytes(net), written)
    for blueprint in suite + search:
        road = f"../../roads/{blueprint.road.name}.xodr"
        target = out / "library" / blueprint.category / f"{blueprint.stem}.xosc"
        _write(target, scenario_bytes(blueprint, road), written)
    for blueprint in smoke:
        road = f"../roads/{blueprint.road.name}.xodr"
        _write(out / "smoke" / f"{blueprint.stem}.xosc", scenario_bytes(blueprint, road), written)
    for folder, pattern in (("roads", "*.xodr"), ("library", "**/*.xosc"), ("smoke", "*.xosc")):
        for stale in (out / folder).glob(pattern):
            if stale not in written:
                stale.unlink()
    return sorted(written)
