"""Safe parsing of OpenDRIVE 1.4-1.8 (``.xodr``) into :mod:`~simtest_operator.opendrive.models`.

Road files come from users (scenario repositories, uploads), so the XML is untrusted: no DTDs, no
entity expansion, no network access, a size limit, and lxml's huge-tree protection stays on. The
document is streamed one top-level element at a time (a whole lxml tree costs about 12x the file
size), and every number is checked against :class:`~simtest_operator.opendrive.limits.Limits` so
geometry work stays bounded. Bad files raise :class:`~simtest_operator.errors.ScenarioError` naming
the element and its line.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TypeVar

from lxml import etree

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import limits, models

MAX_BYTES = limits.DEFAULT.max_bytes
"""Largest accepted .xodr by default (real HD maps reach tens of MB; anything bigger is refused)."""

_T = TypeVar("_T")
_WIDTH_ROUNDING = -1e-6
"""Exporters write rounding noise like ``a="-1e-12"``; a truly negative width is refused."""


def load(
    path: Path, *, max_bytes: int | None = None, bounds: limits.Limits = limits.DEFAULT
) -> models.OpenDrive:
    """Parse the OpenDRIVE file at ``path``."""
    size = bounds.max_bytes if max_bytes is None else max_bytes
    return parse(
        xmlsafe.read_bytes(path, max_bytes=size), source=str(path), max_bytes=size, bounds=bounds
    )


def parse(
    data: bytes,
    *,
    source: str = "<xodr>",
    max_bytes: int | None = None,
    bounds: limits.Limits = limits.DEFAULT,
) -> models.OpenDrive:
    """Parse OpenDRIVE XML given as bytes (``source`` names it in error messages)."""
    size = bounds.max_bytes if max_bytes is None else max_bytes
    elements = xmlsafe.stream_children(data, source=source, max_bytes=size, what="OpenDRIVE")
    return _Reader(source, bounds).document(elements)


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


_SPEED_UNITS = {"m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704}
"""OpenDRIVE's speed units in m/s (m/s when absent)."""


def _children(element: etree._Element, name: str) -> list[etree._Element]:
    return [child for child in element if _local(child) == name]


def _child(element: etree._Element, name: str) -> etree._Element | None:
    for child in element:
        if _local(child) == name:
            return child
    return None


class _Reader:
    """Converts elements, remembering the source for error messages."""

    __slots__ = ("_lane_count", "_limits", "_signal_count", "_source", "_total_length")

    def __init__(self, source: str, bounds: limits.Limits) -> None:
        self._source = source
        self._limits = bounds
        self._total_length = 0.0
        self._signal_count = 0
        self._lane_count = 0

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
        except (ValueError, OverflowError) as exc:
            raise self._error(element, f"attribute {name}={raw!r} is invalid") from exc

    def _float(self, element: etree._Element, name: str, default: float | None = None) -> float:
        value = self._attr(element, name, float, default)
        if not math.isfinite(value):
            raise self._error(element, f"attribute {name}={element.get(name)!r} is not finite")
        return value

    def _bounded(
        self, element: etree._Element, name: str, limit: float, *, low: float | None = None
    ) -> float:
        """A finite attribute within ``[low, limit]`` (``[-limit, limit]`` without ``low``)."""
        value = self._float(element, name)
        floor = -limit if low is None else low
        if not floor <= value <= limit:
            raise self._error(
                element, f"{name} {element.get(name)} is outside [{floor:g}, {limit:g}]"
            )
        return value

    def _check_peak(
        self, element: etree._Element, poly: models.Poly3, span: float, limit: float, what: str
    ) -> None:
        """Refuse a cubic record whose value leaves ``[-limit, limit]`` over its ``span``."""
        peak = limits.cubic_peak(poly, span)
        if not peak <= limit:
            raise self._error(
                element, f"{what} reaches {peak:.3g} m within {span:g} m (limit {limit:g} m)"
            )

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

    def document(self, elements: Iterator[etree._Element]) -> models.OpenDrive:
        """The document from a stream: the root, then its children one at a time."""
        root = next(elements, None)
        if root is None or _local(root) != "OpenDRIVE":
            name = _local(root) if root is not None else ""
            raise ScenarioError(
                f"root element is <{name}>, expected <OpenDRIVE>", file=self._source
            )
        rev_major, rev_minor, name = 1, 4, ""
        offset: models.HeaderOffset | None = None
        roads: list[models.Road] = []
        junctions: list[models.Junction] = []
        seen: set[str] = set()
        for element in elements:
            kind = _local(element)
            if kind == "header":
                rev_major, rev_minor = (
                    self._int(element, "revMajor"),
                    self._int(element, "revMinor"),
                )
                name = element.get("name") or ""
                offset = self.header_offset(element)
            elif kind == "road":
                if len(roads) >= self._limits.max_roads:
                    raise self._error(
                        element, f"more than {self._limits.max_roads} roads (the document limit)"
                    )
                road = self.road(element)
                if road.id in seen:
                    raise self._error(element, f"duplicate road id {road.id!r}")
                seen.add(road.id)
                roads.append(road)
            elif kind == "junction":
                junctions.append(self.junction(element))
        return models.OpenDrive(
            rev_major=rev_major,
            rev_minor=rev_minor,
            name=name,
            roads=tuple(roads),
            junctions=tuple(junctions),
            offset=offset,
        )

    def header_offset(self, header: etree._Element) -> models.HeaderOffset | None:
        """The header's ``<offset>``: finite, within the coordinate limit, None if the identity."""
        element = _child(header, "offset")
        if element is None:
            return None
        limit = self._limits.max_coordinate
        offset = models.HeaderOffset(
            x=self._bounded(element, "x", limit),
            y=self._bounded(element, "y", limit),
            z=self._bounded(element, "z", limit),
            heading=self._bounded(element, "hdg", limit),
        )
        return None if offset == models.HeaderOffset(x=0.0, y=0.0, z=0.0, heading=0.0) else offset

    def road(self, element: etree._Element) -> models.Road:
        road_id = self._attr(element, "id", str)
        rule_raw = (element.get("rule") or "RHT").strip().upper()
        if rule_raw not in ("RHT", "LHT"):
            raise self._error(element, f"rule={rule_raw!r} is not RHT or LHT")
        link = _child(element, "link")
        plan_view = _child(element, "planView")
        if plan_view is None:
            raise self._error(element, f"road {road_id!r} has no <planView>")
        length = self._bounded(element, "length", self._limits.max_length, low=0.0)
        if length < self._limits.min_road_length:
            raise self._error(element, f"road {road_id!r} has length {length:g} m: no position")
        self._total_length += length
        if self._total_length > self._limits.max_total_length:
            raise self._error(
                element,
                f"roads add up to more than {self._limits.max_total_length / 1000:g} km "
                "(the road network limit)",
            )
        geometries = tuple(self.geometry(child) for child in _children(plan_view, "geometry"))
        if not geometries:
            raise self._error(plan_view, f"road {road_id!r} has no <geometry>")
        self._check_coverage(plan_view, road_id, geometries)
        elevation = _child(element, "elevationProfile")
        lateral = _child(element, "lateralProfile")
        lanes = _child(element, "lanes")
        if lanes is None:
            raise self._error(element, f"road {road_id!r} has no <lanes>")
        section_elements = _children(lanes, "laneSection")
        if not section_elements:
            raise self._error(lanes, f"road {road_id!r} has no <laneSection>")
        starts = sorted(self._float(child, "s") for child in section_elements)
        spans = [self._section_span(child, starts, length) for child in section_elements]
        sections = tuple(
            self.lane_section(child, span)
            for child, span in zip(section_elements, spans, strict=True)
        )
        widest = max(
            (
                limits.widest(lane, span)
                for section, span in zip(sections, spans, strict=True)
                for lane in (*section.left, *section.right)
            ),
            default=0.0,
        )
        if widest < self._limits.min_road_width:
            raise self._error(
                lanes,
                f"road {road_id!r} has no lane wider than {widest:g} m "
                f"(at least {self._limits.min_road_width:g} m): it has no surface",
            )
        signals = _child(element, "signals")
        signal_elements = _children(signals, "signal") if signals is not None else []
        reference_elements = _children(signals, "signalReference") if signals is not None else []
        self._count_signals(signals, len(signal_elements) + len(reference_elements))
        return models.Road(
            id=road_id,
            name=element.get("name") or "",
            length=length,
            junction=(element.get("junction") or "-1").strip(),
            rule=models.TrafficRule(rule_raw),
            predecessor=self.road_link(link, "predecessor"),
            successor=self.road_link(link, "successor"),
            geometries=tuple(sorted(geometries, key=lambda geometry: geometry.s)),
            elevations=self._records(
                _children(elevation, "elevation") if elevation is not None else [],
                "s",
                length,
                self._limits.max_coordinate,
                "elevation",
            ),
            superelevations=self._records(
                _children(lateral, "superelevation") if lateral is not None else [],
                "s",
                length,
                math.pi / 2.0,
                "superelevation",
            ),
            lane_offsets=self._records(
                _children(lanes, "laneOffset"), "s", length, self._limits.max_lane_width, "offset"
            ),
            lane_sections=tuple(sorted(sections, key=lambda section: section.s)),
            signals=tuple(self.signal(child, road_id, length) for child in signal_elements),
            signal_references=tuple(
                self.signal_reference(child, road_id, length) for child in reference_elements
            ),
            speed_limits=self.speed_limits(element, length),
        )

    def speed_limits(self, road: etree._Element, length: float) -> tuple[models.SpeedLimit, ...]:
        """The ``<type><speed>`` limits of a road. A limit the simulator cannot use (``no
        limit``, an unknown unit, not a positive finite number) is left out rather than refusing
        the map: drivers then fall back to their own speed."""
        found = []
        for record in _children(road, "type"):
            speed = _child(record, "speed")
            if speed is None:
                continue
            factor = _SPEED_UNITS.get((speed.get("unit") or "m/s").strip())
            try:
                value = float((speed.get("max") or "").strip())
            except ValueError:
                continue
            if factor is not None and 0.0 < value < math.inf:
                found.append(
                    models.SpeedLimit(s=self._along(record, length), max_speed=value * factor)
                )
        return tuple(sorted(found, key=lambda limit: limit.s))

    def _check_coverage(
        self, plan_view: etree._Element, road_id: str, geometries: tuple[models.Geometry, ...]
    ) -> None:
        """Refuse a reference line with a hole: from s=0, each element must start where the
        line so far ends (a zero-length element is fine; a jump after it is not)."""
        covered = 0.0
        for geometry, child in sorted(
            zip(geometries, _children(plan_view, "geometry"), strict=True),
            key=lambda pair: pair[0].s,
        ):
            if geometry.s - covered > self._limits.max_plan_view_gap:
                raise self._error(
                    child,
                    f"road {road_id!r} has no geometry from s={covered:g} to s={geometry.s:g}",
                )
            covered = max(covered, geometry.s + geometry.length)
        if covered == 0.0:
            raise self._error(plan_view, f"road {road_id!r} has no geometry of positive length")

    def _count_signals(self, signals: etree._Element | None, count: int) -> None:
        self._signal_count += count
        if signals is not None and self._signal_count > self._limits.max_signals:
            raise self._error(
                signals,
                f"more than {self._limits.max_signals} signals and signal references "
                "(the document limit)",
            )

    def signal(self, element: etree._Element, road_id: str, length: float) -> models.Signal:
        dynamic = (element.get("dynamic") or "no").strip().lower()
        if dynamic not in ("yes", "no", "true", "false"):
            raise self._error(element, f"dynamic={element.get('dynamic')!r} is not yes or no")
        return models.Signal(
            id=self._attr(element, "id", str),
            name=(element.get("name") or "").strip(),
            dynamic=dynamic in ("yes", "true"),
            country=(element.get("country") or "").strip(),
            type=(element.get("type") or "").strip(),
            subtype=(element.get("subtype") or "").strip(),
            placement=self._placement(element, road_id, length),
        )

    def signal_reference(
        self, element: etree._Element, road_id: str, length: float
    ) -> models.SignalReference:
        return models.SignalReference(
            signal_id=self._attr(element, "id", str),
            placement=self._placement(element, road_id, length),
        )

    def _placement(self, element: etree._Element, road_id: str, length: float) -> models.Placement:
        return models.Placement(
            road_id=road_id,
            s=self._along(element, length),
            t=self._bounded(element, "t", self._limits.max_coordinate),
            orientation=self._orientation(element),
            validities=self._validities(element),
        )

    def _along(self, element: etree._Element, length: float) -> float:
        """A signal's ``s``, clamped onto its road: real exports place some past the end (Town06
        has a reference 0.9 m beyond its 39.4 m road), and the signal still governs that end."""
        s = self._bounded(element, "s", self._limits.max_length)
        return min(max(s, 0.0), length)

    def _orientation(self, element: etree._Element) -> str:
        raw = (element.get("orientation") or "none").strip()
        if raw not in ("+", "-", "none"):
            raise self._error(element, f"orientation={raw!r} is not +, - or none")
        return raw

    def _validities(self, element: etree._Element) -> tuple[models.Validity, ...]:
        """The ``<validity>`` lane ranges, each bounded by the lanes a section may have."""
        result = []
        for child in _children(element, "validity"):
            lanes = (self._int(child, "fromLane"), self._int(child, "toLane"))
            if max(abs(lane) for lane in lanes) > self._limits.max_lanes:
                raise self._error(
                    child, f"validity lanes {lanes} beyond {self._limits.max_lanes} lanes"
                )
            result.append(models.Validity(from_lane=lanes[0], to_lane=lanes[1]))
        return tuple(result)

    def _section_span(self, element: etree._Element, starts: list[float], length: float) -> float:
        """Length of the lane section ``element`` (up to the next section or the road's end)."""
        start = self._float(element, "s")
        later = [value for value in starts if value > start]
        return max((later[0] if later else length) - start, 0.0)

    def _records(
        self,
        elements: list[etree._Element],
        s_name: str,
        end: float,
        limit: float,
        what: str,
    ) -> tuple[models.Poly3, ...]:
        """Cubic records sorted by start, each bounded by ``limit`` up to the next (or ``end``)."""
        pairs = sorted(
            ((self._poly(child, s_name), child) for child in elements),
            key=lambda pair: pair[0].s,
        )
        for (poly, child), span in zip(
            pairs, limits.spans([poly.s for poly, _ in pairs], end), strict=True
        ):
            self._check_peak(child, poly, span, limit, what)
        return tuple(poly for poly, _ in pairs)

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
        bounds = self._limits
        base = models.Geometry(
            kind=models.GeometryKind.LINE,
            s=self._float(element, "s"),
            x=self._bounded(element, "x", bounds.max_coordinate),
            y=self._bounded(element, "y", bounds.max_coordinate),
            heading=self._float(element, "hdg"),
            length=self._bounded(element, "length", bounds.max_length, low=0.0),
        )
        shape = next((child for child in element if _local(child)), None)
        kind = _local(shape) if shape is not None else "line"
        if shape is None or kind == "line":
            return base
        if kind == "arc":
            return dataclasses.replace(
                base,
                kind=models.GeometryKind.ARC,
                curvature=self._bounded(shape, "curvature", bounds.max_curvature),
            )
        if kind == "spiral":
            return self._spiral(shape, base)
        if kind == "poly3":
            return self._polynomial(
                shape,
                dataclasses.replace(
                    base, kind=models.GeometryKind.POLY3, v=self._coefficients(shape, "")
                ),
            )
        if kind == "paramPoly3":
            p_range = (shape.get("pRange") or "normalized").strip()
            if p_range not in ("arcLength", "normalized"):
                raise self._error(shape, f"pRange={p_range!r} is not arcLength or normalized")
            return self._polynomial(
                shape,
                dataclasses.replace(
                    base,
                    kind=models.GeometryKind.PARAM_POLY3,
                    u=self._coefficients(shape, "U"),
                    v=self._coefficients(shape, "V"),
                    normalized=p_range == "normalized",
                ),
            )
        raise self._error(shape, f"unsupported planView geometry <{kind}>")

    def _spiral(self, shape: etree._Element, base: models.Geometry) -> models.Geometry:
        """A clothoid whose total turn, and so its quadrature work per query, is bounded."""
        bounds = self._limits
        start = self._bounded(shape, "curvStart", bounds.max_curvature)
        end = self._bounded(shape, "curvEnd", bounds.max_curvature)
        turn = limits.spiral_turn(start, end, base.length)
        if turn > bounds.max_spiral_turn:
            raise self._error(
                shape,
                f"curvStart {shape.get('curvStart')} to curvEnd {shape.get('curvEnd')} over "
                f"{base.length:g} m turns {turn:.3g} rad (limit {bounds.max_spiral_turn:g} rad)",
            )
        return dataclasses.replace(
            base, kind=models.GeometryKind.SPIRAL, curv_start=start, curv_end=end
        )

    def _polynomial(self, shape: etree._Element, geometry: models.Geometry) -> models.Geometry:
        """Refuse (param)poly3 coefficients that carry the curve beyond the coordinate limit
        (or overflow) within the element: each term and coefficient is bounded."""
        p_end = 1.0 if geometry.normalized else geometry.length
        limit = self._limits.max_coordinate
        param = geometry.kind is models.GeometryKind.PARAM_POLY3
        for axis, coefficients in (("U", geometry.u), ("V", geometry.v)):
            for power, value in enumerate(coefficients):
                # Absolute too: a tiny element must not carry huge derivatives (overflow).
                if max(abs(value), abs(value) * p_end**power) > limit:
                    name = "abcd"[power] + (axis if param else "")
                    raise self._error(
                        shape,
                        f"{name} {value:g} moves the curve more than {limit:g} m "
                        f"within the element",
                    )
        if param and not any((*geometry.u[1:], *geometry.v[1:])):
            raise self._error(shape, "every b, c and d coefficient is 0: the curve is one point")
        return geometry

    def _coefficients(
        self, element: etree._Element, suffix: str
    ) -> tuple[float, float, float, float]:
        a, b, c, d = (self._float(element, f"{name}{suffix}", 0.0) for name in "abcd")
        return (a, b, c, d)

    def lane_section(self, element: etree._Element, span: float) -> models.LaneSection:
        def lanes(side: str, sign: int) -> tuple[models.Lane, ...]:
            container = _child(element, side)
            if container is None:
                return ()
            children = _children(container, "lane")
            if len(children) > self._limits.max_lanes:
                raise self._error(
                    container,
                    f"{len(children)} lanes in <{side}>, more than {self._limits.max_lanes}",
                )
            self._lane_count += len(children)
            if self._lane_count > self._limits.max_total_lanes:
                raise self._error(
                    container,
                    f"more than {self._limits.max_total_lanes:,} lanes in all lane sections "
                    "(the road network limit)",
                )
            result = [self.lane(child, span) for child in children]
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

    def lane(self, element: etree._Element, span: float) -> models.Lane:
        link = _child(element, "link")

        def linked(which: str) -> tuple[int, ...]:
            if link is None:
                return ()
            return tuple(self._int(child, "id") for child in _children(link, which))

        return models.Lane(
            id=self._int(element, "id"),
            type=(element.get("type") or "none").strip(),
            widths=self._widths(element, span),
            borders=self._records(
                _children(element, "border"), "sOffset", span, self._limits.max_lane_width, "border"
            ),
            predecessors=linked("predecessor"),
            successors=linked("successor"),
        )

    def _widths(self, element: etree._Element, span: float) -> tuple[models.Poly3, ...]:
        """Width records: non-negative where they start and bounded over the lane section."""
        children = _children(element, "width")
        for child in children:
            if self._float(child, "a", 0.0) < _WIDTH_ROUNDING:
                raise self._error(child, f"lane width a={child.get('a')} is negative")
        return self._records(children, "sOffset", span, self._limits.max_lane_width, "width")

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
