"""OpenDRIVE road networks: safe parsing and geometry evaluation.

Public entry point: :class:`RoadNetwork` (``RoadNetwork.from_file(path)``), which answers
(road, s, lane, offset) -> pose, world point -> road coordinates, lane widths and the lane graph;
:func:`traffic_controls` gives its traffic lights and stop signs with their stop lines.
"""

from simtest_operator.opendrive.lanes import LaneBounds
from simtest_operator.opendrive.models import (
    ContactPoint,
    HeaderOffset,
    OpenDrive,
    Road,
    TrafficRule,
)
from simtest_operator.opendrive.network import (
    DRIVABLE_LANE_TYPES,
    LaneLocation,
    LaneStretch,
    Pose,
    RoadCoord,
    RoadNetwork,
)
from simtest_operator.opendrive.parsing import load, parse, without_signals
from simtest_operator.opendrive.rewriting import flat_curves_rewritten
from simtest_operator.opendrive.signals import (
    Control,
    SignalIndex,
    StopLine,
    TrafficControl,
    aspect_of,
    light_named,
    traffic_controls,
)
from simtest_operator.opendrive.topology import LaneEntry

__all__ = [
    "DRIVABLE_LANE_TYPES",
    "ContactPoint",
    "Control",
    "HeaderOffset",
    "LaneBounds",
    "LaneEntry",
    "LaneLocation",
    "LaneStretch",
    "OpenDrive",
    "Pose",
    "Road",
    "RoadCoord",
    "RoadNetwork",
    "SignalIndex",
    "StopLine",
    "TrafficControl",
    "TrafficRule",
    "aspect_of",
    "flat_curves_rewritten",
    "light_named",
    "load",
    "parse",
    "traffic_controls",
    "without_signals",
]
