"""Traffic vehicle types: OpenSCENARIO vehicle categories -> SUMO vehicle classes and sizes.

Traffic created by TrafficActions is anonymous: the file names a category (``car``, ``truck``,
...), not a vehicle. Each category gets one SUMO vType with typical European dimensions and
driving limits, so lane permissions (SUMO vClass) and car following behave plausibly. The values
are typical figures (passenger car about 4.5 m, rigid truck 12 m, articulated 16.5 m), not a
vehicle catalog; scenario entities keep their own boxes.
"""

from __future__ import annotations

import dataclasses

from simtest_operator.errors import ScenarioError


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class VehicleType:
    """One traffic vehicle type."""

    category: str
    vclass: str
    """SUMO vehicle class (decides which lanes it may use)."""
    length: float
    width: float
    height: float
    max_speed: float
    accel: float
    decel: float


_TYPES = {
    t.category: t
    for t in (
        VehicleType(category="car", vclass="passenger", length=4.5, width=1.8, height=1.5,
                    max_speed=55.0, accel=2.6, decel=4.5),
        VehicleType(category="van", vclass="delivery", length=5.2, width=2.0, height=2.4,
                    max_speed=44.0, accel=2.0, decel=4.0),
        VehicleType(category="truck", vclass="truck", length=12.0, width=2.5, height=3.5,
                    max_speed=25.0, accel=1.2, decel=4.0),
        VehicleType(category="semitrailer", vclass="trailer", length=16.5, width=2.55, height=4.0,
                    max_speed=25.0, accel=1.0, decel=4.0),
        VehicleType(category="trailer", vclass="trailer", length=16.5, width=2.55, height=4.0,
                    max_speed=25.0, accel=1.0, decel=4.0),
        VehicleType(category="bus", vclass="bus", length=12.0, width=2.55, height=3.2,
                    max_speed=28.0, accel=1.2, decel=4.0),
        VehicleType(category="motorbike", vclass="motorcycle", length=2.2, width=0.8, height=1.4,
                    max_speed=55.0, accel=4.0, decel=7.0),
        VehicleType(category="bicycle", vclass="bicycle", length=1.8, width=0.65, height=1.7,
                    max_speed=8.0, accel=1.2, decel=3.0),
        VehicleType(category="tram", vclass="tram", length=30.0, width=2.65, height=3.4,
                    max_speed=22.0, accel=1.0, decel=3.0),
        VehicleType(category="train", vclass="rail", length=100.0, width=3.0, height=4.0,
                    max_speed=44.0, accel=0.8, decel=1.0),
    )
}  # fmt: skip

CATEGORIES = tuple(_TYPES)


def vehicle_type(category: str) -> VehicleType:
    """The traffic vehicle type of an OpenSCENARIO vehicle category (ScenarioError if unknown)."""
    found = _TYPES.get(category)
    if found is None:
        raise ScenarioError(
            f"unknown vehicle category {category!r} in a traffic definition",
            element="VehicleCategoryDistributionEntry",
        )
    return found
