"""Constant-curvature spirals and straight arcs rewritten as the primitive netconvert can evaluate.

A ``<spiral>`` with ``curvStart == curvEnd`` is an arc (a line at curvature 0) and an ``<arc>`` of
curvature 0 is a line: valid OpenDRIVE that real maps use (esmini's parking_demo and mixed_roads)
and that :mod:`~simtest_operator.opendrive.planview` evaluates exactly. netconvert cannot: it
computes a spiral from its curvature rate and an arc from its radius, so the first collapses to one
point ("No edges loaded") and the second becomes ``-nan,-nan``. Those runs ended ``Error`` and were
retried as if the infrastructure had failed (issue 29); netconvert now gets the equivalent shape.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from typing import cast

from lxml import etree

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive.limits import DEFAULT

FLAT = 1e-12
"""Curvatures (1/m) closer than this are equal: a 1e12 m radius is a line to netconvert."""


def flat_curves_rewritten(data: bytes, *, source: str) -> bytes | None:
    """``data`` with every constant-curvature spiral and straight arc rewritten, or None if it
    has none. Streamed one top-level element at a time, like the parser; a first pass stops at
    the first flat curve, so a map without one costs no copy."""
    if not any(_rewrite(shape) for element in _stream(data, source)[1] for shape in element.iter()):
        return None
    output = io.BytesIO()
    root, elements = _stream(data, source)
    with etree.xmlfile(output, encoding="UTF-8") as document:
        document.write_declaration()
        with document.element(root.tag, dict(root.attrib), nsmap=root.nsmap):
            for element in elements:
                for shape in element.iter():
                    _rewrite(shape)
                document.write(element)
    return output.getvalue()


def _stream(data: bytes, source: str) -> tuple[etree._Element, Iterator[etree._Element]]:
    """The root (attributes only) and an iterator over its children, each freed after use."""
    elements = cast(  # the streamed elements are lxml's own
        Iterator[etree._Element],
        xmlsafe.stream_children(data, source=source, max_bytes=DEFAULT.max_bytes, what="OpenDRIVE"),
    )
    root = next(elements, None)
    if root is None:  # stream_children raises first; kept total for mypy
        raise ScenarioError("empty OpenDRIVE document", file=source)
    return root, elements


def _rewrite(shape: etree._Element) -> bool:
    """Turn ``shape`` into the equivalent arc or line; False if it is not a flat curve."""
    tag = shape.tag
    if not isinstance(tag, str):
        return False
    name = tag.rsplit("}", 1)[-1]
    if name == "spiral":
        start, end = _number(shape.get("curvStart")), _number(shape.get("curvEnd"))
        if start is None or end is None or abs(end - start) >= FLAT:
            return False
        curvature = 0.5 * (start + end)
    elif name == "arc":
        value = _number(shape.get("curvature"))
        if value is None or abs(value) >= FLAT:
            return False
        curvature = 0.0
    else:
        return False
    namespace = tag[: -len(name)]
    shape.attrib.clear()
    if abs(curvature) < FLAT:
        shape.tag = namespace + "line"
    else:
        shape.tag = namespace + "arc"
        shape.set("curvature", repr(curvature))
    return True


def _number(raw: str | None) -> float | None:
    try:
        value = float(raw) if raw is not None else None
    except ValueError:
        return None
    return value if value is not None and math.isfinite(value) else None
