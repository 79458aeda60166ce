"""The library's OpenDRIVE road networks, built with scenariogeneration.

Four networks cover the templates: a straight three-lane motorway, a curved two-lane rural road
(lines, clothoids and arcs), a motorway with an on-ramp acceleration lane that ends, and a
four-way junction of two-lane roads. Each is one function so the geometry the templates rely
on (road ids, lane ids, lengths, where the junction is) sits next to the code that makes it.

scenariogeneration writes junction connecting roads as clothoids whose curvatures are almost
zero or constant; SUMO's netconvert crashes (std::bad_alloc) or warns on those, so
`normalise` rewrites them as the lines and arcs they are, and rounds coordinates, which also
keeps the output bytes stable.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass

from scenariogeneration import xodr

LANE_WIDTH = 3.5
"""Width of every lane in the library, in metres."""

JUNCTION_RADIUS = 15.0
"""Distance from the junction centre (the origin) to where each arm starts, in metres."""

ARM_LENGTH = 200.0
"""Length of each junction arm, in metres."""

MERGE_TAPER = (300.0, 380.0)
"""Where the on-ramp acceleration lane (lane -3) narrows to nothing, as (start s, end s)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RoadNet:
    """One road network of the library."""

    name: str
    """File stem under `roads/` and the value of the `simtest:road` property."""
    kind: str
    """Road-type tag: highway, rural or urban."""
    length: float
    """Usable length of the main road in metres (for the junction: one arm)."""
    build: Callable[[], xodr.OpenDrive]
    """Builds the network."""


def _highway() -> xodr.OpenDrive:
    odr = xodr.OpenDrive("highway_straight", revMinor="6")
    road = xodr.create_road(xodr.Line(1200.0), 1, 3, 3, lane_width=LANE_WIDTH)
    odr.add_road(road)
    return odr


def _rural() -> xodr.OpenDrive:
    curvature = 1.0 / 250.0
    geometry = [
        xodr.Line(150.0),
        xodr.Spiral(0.0, curvature, length=60.0),
        xodr.Arc(curvature, length=180.0),
        xodr.Spiral(curvature, 0.0, length=60.0),
        xodr.Line(150.0),
        xodr.Spiral(0.0, -curvature, length=60.0),
        xodr.Arc(-curvature, length=180.0),
        xodr.Spiral(-curvature, 0.0, length=60.0),
        xodr.Line(300.0),
    ]
    odr = xodr.OpenDrive("rural_curved", revMinor="6")
    odr.add_road(xodr.create_road(geometry, 1, 1, 1, lane_width=LANE_WIDTH))
    return odr


def _merge() -> xodr.OpenDrive:
    taper_start, taper_end = MERGE_TAPER
    right = [xodr.LaneDef(taper_start, taper_end, 3, 2, -3)]
    odr = xodr.OpenDrive("highway_merge", revMinor="6")
    odr.add_road(xodr.create_road(xodr.Line(1000.0), 1, 2, right, lane_width=LANE_WIDTH))
    return odr


def _junction() -> xodr.OpenDrive:
    """Arms: 1 south (runs north into the junction), 2 east, 3 north, 4 west (run outwards
    from the junction except 4, which runs in). Lane -1 of road 1 leads straight on to lane -1
    of road 3; lane 1 of road 3 comes south into the junction."""
    creator = xodr.CommonJunctionCreator(id=100, name="junction_4way", startnum=100)
    arms = [
        (1, 3 * math.pi / 2, "successor"),
        (2, 0.0, "predecessor"),
        (3, math.pi / 2, "predecessor"),
        (4, math.pi, "successor"),
    ]
    odr = xodr.OpenDrive("junction_4way", revMinor="6")
    for road_id, angle, contact in arms:
        road = xodr.create_road(xodr.Line(ARM_LENGTH), road_id, 1, 1, lane_width=LANE_WIDTH)
        if road_id == 1:
            start = -(JUNCTION_RADIUS + ARM_LENGTH)
            road.planview.set_start_point(0.0, start, math.pi / 2)
        odr.add_road(road)
        creator.add_incoming_road_circular_geometry(road, JUNCTION_RADIUS, angle, contact)
    for first, second in [(1, 2), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4)]:
        creator.add_connection(first, second)
    odr.add_junction_creator(creator)
    return odr


HIGHWAY = RoadNet(name="highway_straight", kind="highway", length=1200.0, build=_highway)
RURAL = RoadNet(name="rural_curved", kind="rural", length=1200.0, build=_rural)
MERGE = RoadNet(name="highway_merge", kind="highway", length=1000.0, build=_merge)
JUNCTION = RoadNet(name="junction_4way", kind="urban", length=ARM_LENGTH, build=_junction)
ALL = (HIGHWAY, RURAL, MERGE, JUNCTION)


_GEOMETRY_ATTRIBUTES = frozenset(
    (
        "s",
        "x",
        "y",
        "hdg",
        "length",
        "curvature",
        "curvStart",
        "curvEnd",
        "a",
        "b",
        "c",
        "d",
        "sOffset",
        "tOffset",
        "space",
        "width",
    )
)


def _number(value: float) -> str:
    return "0" if abs(value) < 1e-9 else format(value, ".12g")


def normalise(root: ET.Element) -> None:
    """Make a generated OpenDRIVE tree stable and digestible for netconvert (in place)."""
    header = root.find("header")
    if header is not None:
        header.set("date", "2026-01-01T00:00:00")
    for geometry in root.iter("geometry"):
        spiral = geometry.find("spiral")
        if spiral is None:
            continue
        start, end = float(spiral.get("curvStart", "0")), float(spiral.get("curvEnd", "0"))
        if abs(start - end) > 1e-9:
            continue
        geometry.remove(spiral)
        if abs(start) < 1e-6:
            ET.SubElement(geometry, "line")
        else:
            ET.SubElement(geometry, "arc", curvature=_number((start + end) / 2))
    for element in root.iter():
        for key, value in element.attrib.items():
            if key in _GEOMETRY_ATTRIBUTES:
                element.set(key, _number(float(value)))


def render(net: RoadNet) -> ET.Element:
    """Build a network and return its normalised XML tree."""
    odr = net.build()
    odr.adjust_roads_and_lanes()
    root: ET.Element = odr.get_element()
    normalise(root)
    return root
