"""A cheap, safe look at an OpenSCENARIO file's header, for selecting scenarios before running them.

Resolving a campaign reads every candidate file's ``FileHeader`` (description, author and the
``Properties/Property`` name/value pairs that carry ``simtest:tags``, ``simtest:category``,
``simtest:road``) and the kind of document that follows it (a scenario, a catalog or a
ParameterValueDistribution), without building the storyboard model. Files are untrusted: they are
size-limited, DOCTYPE and ENTITY declarations are refused before parsing, the parser never
resolves entities or touches the network, and parsing stops right after the document kind is
known.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from pathlib import Path

from lxml import etree

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.xmlsafe import MAX_BYTES


class FileKind(enum.StrEnum):
    """What an OpenSCENARIO file contains (what follows its FileHeader)."""

    SCENARIO = "scenario"
    """A scenario definition (has a Storyboard): runnable."""
    CATALOG = "catalog"
    """A catalog of vehicles, controllers, maneuvers, ...: not runnable on its own."""
    DISTRIBUTION = "distribution"
    """A parameter variation of another scenario file: expands into several runs."""
    UNKNOWN = "unknown"
    """Something else (not OpenSCENARIO, or cut short)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FileHeader:
    """The header fields selection and reports use."""

    kind: FileKind
    description: str = ""
    author: str = ""
    rev_major: int | None = None
    rev_minor: int | None = None
    properties: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """``Properties/Property`` name -> value; the last one wins for a repeated name."""
    road_file: str = ""
    """``RoadNetwork/LogicFile/@filepath`` as written (may be a ``$parameter``); empty if none."""


def read_header(path: Path, *, max_bytes: int = MAX_BYTES) -> FileHeader:
    """Read the header of the file at ``path``; ScenarioError when unreadable or unsafe."""
    return parse_header(
        xmlsafe.read_bytes(path, max_bytes=max_bytes), source=str(path), max_bytes=max_bytes
    )


def parse_header(data: bytes, *, source: str, max_bytes: int = MAX_BYTES) -> FileHeader:
    """The header of the document ``data`` (named ``source`` in errors)."""
    if len(data) > max_bytes:
        raise ScenarioError(f"file is larger than the {max_bytes} byte limit", file=source)
    xmlsafe.reject_declarations(data, source)
    events = xmlsafe.iterparse(data)
    header: etree._Element | None = None
    kind = FileKind.UNKNOWN
    road_file = ""
    depth = 0
    try:
        for event, element in events:
            name = etree.QName(element).localname if isinstance(element.tag, str) else ""
            if event == "start":
                depth += 1
                if depth == 1 and name != "OpenSCENARIO":
                    raise ScenarioError(
                        f"root element is <{name}>, not <OpenSCENARIO>", file=source
                    )
                if depth == 2 and kind is FileKind.UNKNOWN:
                    kind = _kind_of(name)
                if depth == 2 and name in _AFTER_ROAD:
                    break
                if depth == 3 and name == "LogicFile":
                    road_file = element.get("filepath", "")
                if depth == 2 and kind in (FileKind.CATALOG, FileKind.DISTRIBUTION):
                    break
            else:
                depth -= 1
                if depth == 1 and name == "FileHeader":
                    header = element
                elif depth == 1 and name == "RoadNetwork":
                    break
    except etree.XMLSyntaxError as exc:
        raise ScenarioError(f"malformed XML: {exc.msg}", file=source, line=exc.lineno) from exc
    if header is None:
        raise ScenarioError("no <FileHeader> element", file=source, element="OpenSCENARIO")
    return dataclasses.replace(_header(header, kind), road_file=road_file)


_AFTER_ROAD = frozenset({"Entities", "Storyboard"})
"""Scenario sections after the RoadNetwork: reading stops there."""


def _kind_of(name: str) -> FileKind:
    if name in ("Storyboard", "RoadNetwork", "Entities", "CatalogLocations"):
        return FileKind.SCENARIO
    if name == "Catalog":
        return FileKind.CATALOG
    if name == "ParameterValueDistribution":
        return FileKind.DISTRIBUTION
    return FileKind.UNKNOWN


def _header(element: etree._Element, kind: FileKind) -> FileHeader:
    properties: dict[str, str] = {}
    for child in element:
        if not isinstance(child.tag, str) or etree.QName(child).localname != "Properties":
            continue
        for prop in child:
            if isinstance(prop.tag, str) and etree.QName(prop).localname == "Property":
                name = prop.get("name")
                if name is not None:
                    properties[name] = prop.get("value", "")
    return FileHeader(
        kind=kind,
        description=element.get("description", ""),
        author=element.get("author", ""),
        rev_major=_int(element.get("revMajor")),
        rev_minor=_int(element.get("revMinor")),
        properties=properties,
    )


def _int(text: str | None) -> int | None:
    try:
        return int(text) if text is not None else None
    except ValueError:
        return None
