"""Traffic actions of the scenario model: swarms, sources, sinks and stopping them.

OpenSCENARIO's TrafficAction does not script what the traffic does: it creates (or removes)
anonymous vehicles whose behaviour belongs to a traffic simulation (SUMO here). The model keeps
what the file says; :mod:`simtest_operator.sim.traffic` decides what that means per step.

Version notes: 1.0 reads ``velocity``; 1.1 adds ``trafficName`` and TrafficStopAction; 1.2 adds
the swarm's ``SpeedRange`` and ``DirectionOfTravelDistribution``; 1.3 renames the range to
``InitialSpeedRange``, the source's ``velocity`` to ``speed`` and makes TrafficDefinition
optional (superseded by TrafficDistribution, which is unsupported here).
"""

from __future__ import annotations

import dataclasses

from simtest_operator.openscenario.model.positions import Position


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class CategoryWeight:
    """One entry of a VehicleCategoryDistribution: a vehicle category and its relative weight."""

    category: str
    """OpenSCENARIO VehicleCategory, e.g. ``car``, ``truck``, ``motorbike``."""
    weight: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ControllerWeight:
    """One entry of a ControllerDistribution (the controller is named, not simulated)."""

    controller: str
    weight: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficDefinition:
    """What kind of vehicles traffic consists of."""

    name: str
    categories: tuple[CategoryWeight, ...]
    controllers: tuple[ControllerWeight, ...] = ()
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SpeedRange:
    """Initial speeds drawn uniformly from [lower, upper] m/s."""

    lower: float
    upper: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class DirectionOfTravel:
    """Relative weights of traffic driving the central entity's way and the opposite way."""

    same: float
    opposite: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSwarmAction:
    """Keep up to ``number_of_vehicles`` vehicles around a central entity.

    The swarm area is an ellipse centred ``offset`` metres ahead of the central entity along its
    heading (major axis along the heading), minus a circle of ``inner_radius`` around it.
    """

    central_entity: str
    inner_radius: float
    semi_major_axis: float
    semi_minor_axis: float
    offset: float
    number_of_vehicles: int
    velocity: float | None = None
    """Initial speed (m/s), the 1.0/1.1 attribute."""
    speed_range: SpeedRange | None = None
    direction: DirectionOfTravel | None = None
    definition: TrafficDefinition | None = None
    traffic_name: str | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSourceAction:
    """Create vehicles at ``rate`` per second within ``radius`` of ``position``."""

    position: Position
    radius: float
    rate: float
    speed: float | None = None
    """Initial speed (m/s): 1.3 ``speed``, earlier ``velocity``."""
    definition: TrafficDefinition | None = None
    traffic_name: str | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSinkAction:
    """Remove traffic within ``radius`` of ``position`` at ``rate`` per second (None: at once)."""

    position: Position
    radius: float
    rate: float | None = None
    definition: TrafficDefinition | None = None
    traffic_name: str | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficStopAction:
    """Stop the traffic action called ``traffic_name`` (1.1+)."""

    traffic_name: str | None
    line: int | None = None


TrafficAction = TrafficSwarmAction | TrafficSourceAction | TrafficSinkAction | TrafficStopAction
"""The traffic actions the stand-in runs; TrafficAreaAction (1.3) is Unsupported."""
