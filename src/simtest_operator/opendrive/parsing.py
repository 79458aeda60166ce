"""Safe parsing of OpenDRIVE 1.4-1.8 (``.xodr``) into :mod:`~simtest_operator.opendrive.models`.

Road files come from users (scenario repositories, uploads), so the XML is untrusted: no DTDs, no
entity expansion, no network access, a size limit, and lxml's huge-tree protection stays on. Bad
files raise :class:`~simtest_operator.errors.ScenarioError` naming the element and its line.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from lxml import etree

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import models

MAX_BYTES = 128 * 1024 * 1024
"""Largest accepted .xodr (real HD maps reach tens of MB; anything bigger is refused)."""

_T = TypeVar("_T")


def load(path: Path, *, max_bytes: int = MAX_BYTES) -> models.OpenDrive:
    """Parse the OpenDRIVE file at ``path``."""
    return parse(
        xmlsafe.read_bytes(path, max_bytes=max_bytes), source=str(path), max_bytes=max_bytes
    )


def parse(data: bytes, *, source: str = "<xodr>", max_bytes: int = MAX_BYTES) -> models.OpenDrive:
    """Parse OpenDRIVE XML given as bytes (``source`` names it in error messages)."""
    root = _root(data, source=source, max_bytes=max_bytes)
    if _local(root) != "OpenDRIVE":
        raise ScenarioError(f"root element is <{_local(root)}>, expected <OpenDRIVE>", file=source)
    return _Reader(source).document(root)


def _root(data: bytes, *, source: str, max_bytes: int) -> etree._Element:
    """The root element of ``data``, parsed with the project's hardened parser."""
    root: etree._Element = xmlsafe.parse_bytes(
        data, source=source, max_bytes=max_bytes, what="OpenDRIVE"
    )
    return root


def _local(element: etree._Element) -> str:
    tag = element.tag
    if not isinstance(tag, str):
        return ""
    return tag.rsplit("}", 1)[-1]


def _children(element: etree._Element, name: str) -> list[etree._Element]:
    return [child for child in element if _local(child) == name]


def _child(element: etree._Element, name: str) -> etree._Element | None:
    for child in element:
        if _local(child) == name:
            return child
    return None


class _Reader:
    """Converts elements, remembering the source for error messages."""

    __slots__ = ("_source",)

    def __init__(self, source: str) -> None:
        self._source = source

    def _error(self, element: etree._Element, message: str) -> ScenarioError:
        return ScenarioError(
            message, file=self._source, element=_local(element), line=element.sourceline
        )

    def _attr(
        self,
        element: etree._Element,
        name: str,
        convert: Callable[[str], _T],
        default: _T | None = None,
    ) -> _T:
        raw = element.get(name)
        if raw is None or raw.strip() == "":
            if default is None:
                raise self._error(element, f"attribute {name!r} is missing")
            return default
        try:
            return convert(raw.strip())
        except ValueError as exc:
            raise self._error(element, f"attribute {name}={raw!r} is invalid") from exc

    def _float(self, element: etree._Element, name: str, default: float | None = None) -> float:
        return self._attr(element, name, float, default)

    def _int(self, element: etree._Element, name: str) -> int:
        return self._attr(element, name, lambda raw: int(float(raw)))

    def _poly(self, element: etree._Element, s_name: str = "s") -> models.Poly3:
        return models.Poly3(
            s=self._float(element, s_name, 0.0),
            a=self._float(element, "a", 0.0),
            b=self._float(element, "b", 0.0),
            c=self._float(element, "c", 0.0),
            d=self._float(element, "d", 0.0),
        )

    def document(self, root: etree._Element) -> models.OpenDrive:
        header = _child(root, "header")
        rev_major = self._int(header, "revMajor") if header is not None else 1
        rev_minor = self._int(header, "revMinor") if header is not None else 4
        roads = tuple(self.road(element) for element in _children(root, "road"))
        seen: set[str] = set()
        for road in roads:
            if road.id in seen:
                raise ScenarioError(f"duplicate road id {road.id!r}", file=self._source)
            seen.add(road.id)
        junctions = tuple(self.junction(element) for element in _children(root, "junction"))
        return models.OpenDrive(
            rev_major=rev_major,
            rev_minor=rev_minor,
            name=(header.get("name") or "") if header is not None else "",
            roads=roads,
            junctions=junctions,
        )

    def road(self, element: etree._Element) -> models.Road:
        road_id = self._attr(element, "id", str)
        rule_raw = (element.get("rule") or "RHT").strip().upper()
        if rule_raw not in ("RHT", "LHT"):
            raise self._error(element, f"rule={rule_raw!r} is not RHT or LHT")
        link = _child(element, "link")
        plan_view = _child(element, "planView")
        if plan_view is None:
            raise self._error(element, f"road {road_id!r} has no <planView>")
        geometries = tuple(self.geometry(child) for child in _children(plan_view, "geometry"))
        if not geometries:
            raise self._error(plan_view, f"road {road_id!r} has no <geometry>")
        elevation = _child(element, "elevationProfile")
        lanes = _child(element, "lanes")
        if lanes is None:
            raise self._error(element, f"road {road_id!r} has no <lanes>")
        sections = tuple(self.lane_section(child) for child in _children(lanes, "laneSection"))
        if not sections:
            raise self._error(lanes, f"road {road_id!r} has no <laneSection>")
        return models.Road(
            id=road_id,
            name=element.get("name") or "",
            length=self._float(element, "length"),
            junction=(element.get("junction") or "-1").strip(),
            rule=models.TrafficRule(rule_raw),
            predecessor=self.road_link(link, "predecessor"),
            successor=self.road_link(link, "successor"),
            geometries=tuple(sorted(geometries, key=lambda geometry: geometry.s)),
            elevations=tuple(
                sorted(
                    (self._poly(child) for child in _children(elevation, "elevation")),
                    key=lambda poly: poly.s,
                )
            )
            if elevation is not None
            else (),
            lane_offsets=tuple(
                sorted(
                    (self._poly(child) for child in _children(lanes, "laneOffset")),
                    key=lambda poly: poly.s,
                )
            ),
            lane_sections=tuple(sorted(sections, key=lambda section: section.s)),
        )

    def road_link(self, link: etree._Element | None, which: str) -> models.RoadLink | None:
        element = _child(link, which) if link is not None else None
        if element is None or not element.get("elementId"):
            return None
        element_type = (element.get("elementType") or "road").strip()
        if element_type not in ("road", "junction"):
            raise self._error(element, f"elementType={element_type!r} is not road or junction")
        contact = element.get("contactPoint")
        return models.RoadLink(
            element_type=models.ElementType(element_type),
            element_id=self._attr(element, "elementId", str),
            contact_point=self._contact(element, contact) if contact else None,
        )

    def _contact(self, element: etree._Element, raw: str) -> models.ContactPoint:
        if raw.strip() not in ("start", "end"):
            raise self._error(element, f"contactPoint={raw!r} is not start or end")
        return models.ContactPoint(raw.strip())

    def geometry(self, element: etree._Element) -> models.Geometry:
        base = models.Geometry(
            kind=models.GeometryKind.LINE,
            s=self._float(element, "s"),
            x=self._float(element, "x"),
            y=self._float(element, "y"),
            heading=self._float(element, "hdg"),
            length=self._float(element, "length"),
        )
        shape = next((child for child in element if _local(child)), None)
        kind = _local(shape) if shape is not None else "line"
        if shape is None or kind == "line":
            return base
        if kind == "arc":
            return dataclasses.replace(
                base, kind=models.GeometryKind.ARC, curvature=self._float(shape, "curvature")
            )
        if kind == "spiral":
            return dataclasses.replace(
                base,
                kind=models.GeometryKind.SPIRAL,
                curv_start=self._float(shape, "curvStart"),
                curv_end=self._float(shape, "curvEnd"),
            )
        if kind == "poly3":
            return dataclasses.replace(
                base, kind=models.GeometryKind.POLY3, v=self._coefficients(shape, "")
            )
        if kind == "paramPoly3":
            p_range = (shape.get("pRange") or "normalized").strip()
            if p_range not in ("arcLength", "normalized"):
                raise self._error(shape, f"pRange={p_range!r} is not arcLength or normalized")
            return dataclasses.replace(
                base,
                kind=models.GeometryKind.PARAM_POLY3,
                u=self._coefficients(shape, "U"),
                v=self._coefficients(shape, "V"),
                normalized=p_range == "normalized",
            )
        raise self._error(shape, f"unsupported planView geometry <{kind}>")

    def _coefficients(
        self, element: etree._Element, suffix: str
    ) -> tuple[float, float, float, float]:
        a, b, c, d = (self._float(element, f"{name}{suffix}", 0.0) for name in "abcd")
        return (a, b, c, d)

    def lane_section(self, element: etree._Element) -> models.LaneSection:
        def lanes(side: str, sign: int) -> tuple[models.Lane, ...]:
            container = _child(element, side)
            if container is None:
                return ()
            result = [self.lane(child) for child in _children(container, "lane")]
            for lane in result:
                if lane.id * sign <= 0:
                    raise self._error(container, f"lane id {lane.id} does not belong in <{side}>")
            return tuple(sorted(result, key=lambda lane: abs(lane.id)))

        return models.LaneSection(
            s=self._float(element, "s"),
            left=lanes("left", 1),
            right=lanes("right", -1),
            single_side=(element.get("singleSide") or "false").strip() == "true",
        )

    def lane(self, element: etree._Element) -> models.Lane:
        link = _child(element, "link")

        def linked(which: str) -> tuple[int, ...]:
            if link is None:
                return ()
            return tuple(self._int(child, "id") for child in _children(link, which))

        return models.Lane(
            id=self._int(element, "id"),
            type=(element.get("type") or "none").strip(),
            widths=tuple(
                sorted(
                    (self._poly(child, "sOffset") for child in _children(element, "width")),
                    key=lambda poly: poly.s,
                )
            ),
            borders=tuple(
                sorted(
                    (self._poly(child, "sOffset") for child in _children(element, "border")),
                    key=lambda poly: poly.s,
                )
            ),
            predecessors=linked("predecessor"),
            successors=linked("successor"),
        )

    def junction(self, element: etree._Element) -> models.Junction:
        connections = []
        for child in _children(element, "connection"):
            connecting = child.get("connectingRoad") or child.get("linkedRoad")
            if not connecting:
                # Some real maps (virtual/direct junction drafts) omit it; such a connection
                # carries no usable topology, so it is skipped rather than failing the map.
                continue
            contact = child.get("contactPoint") or "start"
            connections.append(
                models.Connection(
                    id=(child.get("id") or "").strip(),
                    incoming_road=self._attr(child, "incomingRoad", str),
                    connecting_road=connecting.strip(),
                    contact_point=self._contact(child, contact),
                    lane_links=tuple(
                        models.LaneLink(
                            from_lane=self._int(link, "from"), to_lane=self._int(link, "to")
                        )
                        for link in _children(child, "laneLink")
                    ),
                )
            )
        return models.Junction(
            id=self._attr(element, "id", str),
            name=element.get("name") or "",
            connections=tuple(connections),
        )


def without_signals(data: bytes, *, source: str = "<xodr>") -> bytes:
    """The document with every ``<signals>``/``<signal>`` element removed.

    Some real maps carry signal definitions that netconvert rejects (for example an empty
    ``type``); the simulator does not use signals, so a copy without them is converted instead.
    """
    root = _root(data, source=source, max_bytes=MAX_BYTES)
    doomed = [
        element
        for element in root.iter()
        if _local(element) in ("signals", "signal", "signalReference")
    ]
    for element in doomed:
        parent = element.getparent()
        if parent is not None:
            parent.remove(element)
    return bytes(etree.tostring(root, xml_declaration=True, encoding="UTF-8"))
