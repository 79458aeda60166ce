"""Writing a concrete scenario: a logical one with its global parameters' values replaced.

A search proposes parameter values; the regression suite it feeds wants plain ``.xosc`` files
that any OpenSCENARIO player runs without overrides. The file is parsed with the hardened parser,
only the ``value`` attributes of the global ParameterDeclarations change. The files the scenario
references by relative path (road network, scene graph, catalog directories) are copied next to
the concrete files (:func:`bundle`) and the references point at the copies, so the folder is
self-contained: it runs, moves and goes into version control without the logical scenario's tree.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from lxml import etree

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import headers, loading
from simtest_operator.openscenario.confinement import Confinement

_REFERENCES = (
    ("RoadNetwork/LogicFile", "filepath"),
    ("RoadNetwork/SceneGraphFile", "filepath"),
    ("CatalogLocations/*/Directory", "path"),
)
"""Elements below the root whose path attribute the reader resolves against the file's folder."""


def concretise(
    scenario: Path, values: Mapping[str, str], *, references: Mapping[str, str] | None = None
) -> bytes:
    """The scenario at ``scenario`` with the global parameters in ``values`` set, its file
    references replaced as ``references`` maps them (as written -> new path; from
    :func:`bundle`).

    Raises ScenarioError when the file is not a scenario or declares no parameter of that name.
    """
    file = str(scenario)
    root = _scenario_root(scenario)
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
    for element, attribute, raw in _references(tree):
        if raw in (references or {}):
            element.set(attribute, (references or {})[raw])
    data: bytes = etree.tostring(tree, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    return data


def bundle(scenario: Path, destination: Path, *, confinement: Confinement) -> dict[str, str]:
    """Copy the files ``scenario`` references by relative path into ``destination`` (created
    when missing) and say where: reference as written -> the copy's path relative to
    ``destination``.

    A road network or scene graph is copied as ``<its folder's name>/<file>``, a catalog
    directory's ``.xosc`` files (what the reader reads) as ``<directory's name>/``; a name
    another export already holds with other content gets a ``-2``, ``-3``, ... suffix. A
    reference that does not exist is left alone (a map library name: found by name); one that
    resolves outside ``confinement`` is refused (ScenarioError): the copy must not carry files
    the scenario itself may not read.
    """
    scenario = scenario.resolve()
    copied: dict[str, str] = {}
    for _, attribute, raw in _references(_scenario_root(scenario)):
        if raw in copied:
            continue
        target = (scenario.parent / raw).resolve()
        if not target.exists():
            continue
        if not confinement.allows(target):
            raise ScenarioError(
                f"{attribute}={raw!r} resolves {confinement.describe()}; not copied",
                file=str(scenario),
            )
        if target.is_dir():
            files = {p.name: p.read_bytes() for p in sorted(target.glob("*.xosc")) if p.is_file()}
        else:
            files = {target.name: target.read_bytes()}
        folder = _free_folder(destination, target if target.is_dir() else target.parent, files)
        for name, data in files.items():
            (folder / name).write_bytes(data)
        copy = folder if target.is_dir() else folder / target.name
        copied[raw] = copy.relative_to(destination).as_posix()
    return copied


def _free_folder(destination: Path, original: Path, files: Mapping[str, bytes]) -> Path:
    """A folder in ``destination`` named after ``original`` that holds nothing but ``files``
    (or nothing yet)."""
    stem = original.name or "references"
    for number in range(1, 1000):
        folder = destination / (stem if number == 1 else f"{stem}-{number}")
        clash = any(
            (folder / name).exists() and (folder / name).read_bytes() != data
            for name, data in files.items()
        )
        if not clash:
            folder.mkdir(parents=True, exist_ok=True)
            return folder
    raise ScenarioError(f"{destination}: no free folder for the copies of {original}")


def _scenario_root(scenario: Path) -> etree._Element:
    file = str(scenario)
    root: etree._Element = xmlsafe.parse_file(scenario)
    if loading.file_kind_of(root, file=file) is not headers.FileKind.SCENARIO:
        raise ScenarioError("only a scenario file can be made concrete", file=file)
    return root


def _references(tree: etree._Element) -> list[tuple[etree._Element, str, str]]:
    """(element, attribute, value) of every relative file reference (not a ``$parameter``)."""
    found = []
    for xpath, attribute in _REFERENCES:
        for element in tree.iterfind(xpath):
            raw = element.get(attribute) or ""
            if raw and not raw.startswith("$") and not Path(raw).is_absolute():
                found.append((element, attribute, raw))
    return found
