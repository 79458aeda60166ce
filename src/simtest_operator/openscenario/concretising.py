"""Writing a concrete scenario: a logical one with its global parameters' values replaced.

A search proposes parameter values; the regression suite it feeds wants plain ``.xosc`` files
that any OpenSCENARIO player runs without overrides. The file is parsed with the hardened parser,
only the ``value`` attributes of the global ParameterDeclarations change, and relative file
references (road network, scene graph, catalog directories) are rewritten so they still point at
the same files from the folder the concrete file is written to.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from lxml import etree

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import headers, loading

_REFERENCES = (
    ("RoadNetwork/LogicFile", "filepath"),
    ("RoadNetwork/SceneGraphFile", "filepath"),
    ("CatalogLocations/*/Directory", "path"),
)
"""Elements below the root whose path attribute the reader resolves against the file's folder."""


def concretise(scenario: Path, values: Mapping[str, str], *, destination: Path) -> bytes:
    """The scenario at ``scenario`` with the global parameters in ``values`` set, as a document
    to be written into the folder ``destination``.

    Raises ScenarioError when the file is not a scenario or declares no parameter of that name.
    """
    scenario = scenario.resolve()
    file = str(scenario)
    root = xmlsafe.parse_file(scenario)
    if loading.file_kind_of(root, file=file) is not headers.FileKind.SCENARIO:
        raise ScenarioError("only a scenario file can be made concrete", file=file)
    tree: etree._Element = root
    decls = {
        str(decl.get("name")): decl
        for decl in tree.iterfind("ParameterDeclarations/ParameterDeclaration")
    }
    unknown = sorted(set(values) - set(decls))
    if unknown:
        raise ScenarioError(
            f"the scenario declares no parameter(s) {', '.join(unknown)}", file=file
        )
    for name, value in values.items():
        decls[name].set("value", value)
    for xpath, attribute in _REFERENCES:
        for element in tree.iterfind(xpath):
            raw = element.get(attribute) or ""
            if raw and not raw.startswith("$") and not Path(raw).is_absolute():
                target = (scenario.parent / raw).resolve()
                if not target.exists():
                    continue  # a map library name ("Town01"): found by name, not by path
                element.set(attribute, os.path.relpath(target, destination.resolve()))
    data: bytes = etree.tostring(tree, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    return data
