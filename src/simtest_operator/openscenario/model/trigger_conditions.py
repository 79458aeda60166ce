"""Triggers and conditions of the scenario model.

A :class:`Trigger` is an OR over condition groups, a :class:`ConditionGroup` an AND over conditions,
exactly as the standard defines them. Each condition is either :class:`ByEntity` (evaluated for the
triggering entities, combined with rule any/all) or :class:`ByValue`.
"""

from __future__ import annotations

import dataclasses
import enum

from simtest_operator.openscenario.model import value_conditions
from simtest_operator.openscenario.model.common import (
    AngleType,
    CoordinateSystem,
    DirectionalDimension,
    RelativeDistanceType,
    RoutingAlgorithm,
    Rule,
    Unsupported,
)
from simtest_operator.openscenario.model.positions import Position


class ConditionEdge(enum.StrEnum):
    """When a condition fires relative to its underlying truth value."""

    RISING = "rising"
    FALLING = "falling"
    RISING_OR_FALLING = "risingOrFalling"
    NONE = "none"


class TriggeringEntitiesRule(enum.StrEnum):
    """Whether any or all triggering entities must satisfy an entity condition."""

    ANY = "any"
    ALL = "all"


class StoryboardElementType(enum.StrEnum):
    """Kinds of storyboard elements a StoryboardElementStateCondition may watch."""

    STORY = "story"
    ACT = "act"
    MANEUVER_GROUP = "maneuverGroup"
    MANEUVER = "maneuver"
    EVENT = "event"
    ACTION = "action"


class StoryboardElementState(enum.StrEnum):
    """States and transitions of the storyboard state machine."""

    START_TRANSITION = "startTransition"
    END_TRANSITION = "endTransition"
    STOP_TRANSITION = "stopTransition"
    SKIP_TRANSITION = "skipTransition"
    COMPLETE_STATE = "completeState"
    RUNNING_STATE = "runningState"
    STANDBY_STATE = "standbyState"


# --- entity conditions ------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EndOfRoadCondition:
    """Entity has been at the end of a road for ``duration`` seconds."""

    duration: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class OffRoadCondition:
    """Entity has been off road for ``duration`` seconds."""

    duration: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class CollisionCondition:
    """Entity collides with ``entity_ref``, or with any object of type ``by_type``."""

    entity_ref: str | None = None
    by_type: str | None = None
    """ObjectType (vehicle, pedestrian, miscellaneous, external) when ByType is used."""
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TimeHeadwayCondition:
    """Time headway from the triggering entity to ``entity_ref``."""

    entity_ref: str
    value: float
    rule: Rule
    freespace: bool
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    relative_distance_type: RelativeDistanceType = RelativeDistanceType.LONGITUDINAL
    along_route: bool | None = None
    """1.0 ``alongRoute`` (deprecated later), kept when present."""
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TimeToCollisionCondition:
    """Time to collision with an entity (``entity_ref``) or a position (``position``)."""

    value: float
    rule: Rule
    freespace: bool
    entity_ref: str | None = None
    position: Position | None = None
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    relative_distance_type: RelativeDistanceType = RelativeDistanceType.LONGITUDINAL
    along_route: bool | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AccelerationCondition:
    """Acceleration of the triggering entity."""

    value: float
    rule: Rule
    direction: DirectionalDimension | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StandStillCondition:
    """Entity has stood still for ``duration`` seconds."""

    duration: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SpeedCondition:
    """Speed of the triggering entity."""

    value: float
    rule: Rule
    direction: DirectionalDimension | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeSpeedCondition:
    """Speed of the triggering entity minus the speed of ``entity_ref``."""

    entity_ref: str
    value: float
    rule: Rule
    direction: DirectionalDimension | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TraveledDistanceCondition:
    """Entity has travelled at least ``value`` metres since the scenario start."""

    value: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ReachPositionCondition:
    """Entity is within ``tolerance`` metres of ``position`` (facing its ``Orientation`` when
    the position is written with one, as esmini checks)."""

    position: Position
    tolerance: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class DistanceCondition:
    """Distance from the triggering entity to ``position``."""

    position: Position
    value: float
    rule: Rule
    freespace: bool
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    relative_distance_type: RelativeDistanceType = RelativeDistanceType.EUCLIDEAN
    along_route: bool | None = None
    routing_algorithm: RoutingAlgorithm | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeDistanceCondition:
    """Distance from the triggering entity to ``entity_ref``."""

    entity_ref: str
    value: float
    rule: Rule
    freespace: bool
    relative_distance_type: RelativeDistanceType
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    routing_algorithm: RoutingAlgorithm | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeClearanceCondition:
    """No entity (of ``entity_refs``, when given) in the lanes ``lane_ranges`` relative to the
    triggering entity's lane (positive: to its left), from ``distance_backward`` behind to
    ``distance_forward`` ahead (1.2+)."""

    lane_ranges: tuple[tuple[int, int], ...]
    """(from, to) relative lane ranges; empty: every lane."""
    entity_refs: tuple[str, ...]
    opposite_lanes: bool
    freespace: bool
    distance_forward: float | None = None
    distance_backward: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AngleCondition:
    """The triggering entity's heading, pitch or roll is within ``tolerance`` of ``angle``
    (radians, 1.3); ``road``/``lane`` measure the heading from the road's or lane's direction
    of increasing s at the entity, ``entity``/``world`` the world angle."""

    angle_type: AngleType
    angle: float
    tolerance: float
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeAngleCondition:
    """The triggering entity's angle minus that of ``entity_ref`` is within ``tolerance`` of
    ``angle`` (1.3), both measured as in :class:`AngleCondition`."""

    entity_ref: str
    angle_type: AngleType
    angle: float
    tolerance: float
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    line: int | None = None


EntityCondition = (
    EndOfRoadCondition
    | OffRoadCondition
    | CollisionCondition
    | TimeHeadwayCondition
    | TimeToCollisionCondition
    | AccelerationCondition
    | StandStillCondition
    | SpeedCondition
    | RelativeSpeedCondition
    | TraveledDistanceCondition
    | ReachPositionCondition
    | DistanceCondition
    | RelativeDistanceCondition
    | RelativeClearanceCondition
    | AngleCondition
    | RelativeAngleCondition
    | Unsupported
)
"""Conditions the engine cannot evaluate arrive as :class:`Unsupported`."""


# --- value conditions -------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SimulationTimeCondition:
    """Simulated time since the scenario start, in seconds."""

    value: float
    rule: Rule
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StoryboardElementStateCondition:
    """A storyboard element (by name) is in a state or passes a transition."""

    element_type: StoryboardElementType
    element_ref: str
    state: StoryboardElementState
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ParameterCondition:
    """A parameter's current value compared with ``value`` (text, typed by the parameter)."""

    parameter_ref: str
    value: str
    rule: Rule
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class VariableCondition:
    """A variable's current value compared with ``value`` (text, typed by the variable)."""

    variable_ref: str
    value: str
    rule: Rule
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSignalCondition:
    """The traffic signal ``name`` shows ``state``."""

    name: str
    state: str
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSignalControllerCondition:
    """The RoadNetwork's controller ``controller_ref`` is in its phase ``phase``."""

    controller_ref: str
    phase: str
    line: int | None = None


ValueCondition = (
    SimulationTimeCondition
    | StoryboardElementStateCondition
    | ParameterCondition
    | VariableCondition
    | TrafficSignalCondition
    | TrafficSignalControllerCondition
    | value_conditions.TimeOfDayCondition
    | value_conditions.UserDefinedValueCondition
    | Unsupported
)


# --- triggers ---------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ByEntity:
    """An entity condition evaluated for the triggering entities."""

    triggering_entities: tuple[str, ...]
    rule: TriggeringEntitiesRule
    condition: EntityCondition
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ByValue:
    """A condition on values (time, parameters, storyboard states)."""

    condition: ValueCondition
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Condition:
    """A named condition with a delay (seconds) and an edge."""

    name: str
    delay: float
    edge: ConditionEdge
    body: ByEntity | ByValue
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ConditionGroup:
    """True when all its conditions are true (AND)."""

    conditions: tuple[Condition, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Criterion:
    """A CARLA ScenarioRunner test criterion: a condition named ``criteria_<Test>`` in the
    storyboard's StopTrigger.

    ScenarioRunner reads those as pass/fail tests over the whole run, not as stop conditions
    (OpenSCENARIO 1.0 has no other place for them); the ParameterCondition inside only carries
    the test's argument (``parameterRef="distance_success" value="100"``) or nothing
    (``parameterRef=""``).
    """

    test: str
    """The name after ``criteria_`` as written (``CollisionTest``, ``DrivenDistanceTest``, ...)."""
    known: bool
    """False for a name that is not one of ScenarioRunner's tests the stand-in judges, spelled
    as ScenarioRunner spells it: ScenarioRunner cannot build it (the run is Invalid)."""
    arguments: tuple[tuple[str, str], ...] = ()
    """(parameterRef, value) of the inner ParameterCondition when parameterRef is not empty."""
    line: int | None = None

    def argument(self, name: str) -> str | None:
        """The value given for argument ``name``, or None."""
        return next((value for key, value in self.arguments if key == name), None)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Trigger:
    """True when any of its condition groups is true (OR); empty means never."""

    condition_groups: tuple[ConditionGroup, ...]
    criteria: tuple[Criterion, ...] = ()
    """Only on StopTriggers: the ``criteria_<Test>`` conditions taken out of its groups (groups
    left empty by that are dropped)."""
    line: int | None = None
