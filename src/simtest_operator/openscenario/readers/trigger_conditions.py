"""Reading triggers, condition groups and conditions into the model."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Protocol

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import trigger_conditions as c
from simtest_operator.openscenario.readers import positions, value_conditions
from simtest_operator.xmlsafe import Element

_EntityReader = Callable[[Element, reading.Context], c.EntityCondition]
_ValueReader = Callable[[Element, reading.Context], c.ValueCondition]

_DISTANCE_ALIASES = {"cartesianDistance": m.RelativeDistanceType.EUCLIDEAN}


def trigger(el: Element | None, ctx: reading.Context) -> c.Trigger | None:
    """Read an optional StartTrigger/StopTrigger."""
    if el is None:
        return None
    groups = tuple(
        c.ConditionGroup(
            conditions=tuple(condition(cond, ctx) for cond in reading.all_children(g, "Condition")),
            line=g.sourceline,
        )
        for g in reading.all_children(el, "ConditionGroup")
    )
    return c.Trigger(condition_groups=groups, line=el.sourceline)


CRITERION_PREFIX = "criteria_"
KNOWN_CRITERIA = {
    name.lower(): name
    for name in (
        "CollisionTest",
        "KeepLaneTest",
        "WrongLaneTest",
        "OnSidewalkTest",
        "RunningStopTest",
        "RunningRedLightTest",
        "DrivenDistanceTest",
        "MaxVelocityTest",
        "AverageVelocityTest",
        "OffRoadTest",
        "EndofRoadTest",
    )
}
"""ScenarioRunner's test criteria by lower-case name, to name the right spelling of a wrong one
(ScenarioRunner looks ``<Test>`` up case-sensitively: ``OnSideWalkTest``, which its
documentation also writes, is no class)."""


def stop_trigger(el: Element | None, ctx: reading.Context) -> c.Trigger | None:
    """Read a StopTrigger (the storyboard's or an act's), taking ScenarioRunner's
    ``criteria_<Test>`` conditions out as :class:`~.model.trigger_conditions.Criterion` (tests
    over the run, never stop conditions: ScenarioRunner collects them from every StopTrigger; their
    ParameterConditions name undeclared or empty parameters)."""
    if el is None:
        return None
    groups: list[c.ConditionGroup] = []
    criteria: list[c.Criterion] = []
    for group in reading.all_children(el, "ConditionGroup"):
        kept: list[c.Condition] = []
        for cond in reading.all_children(group, "Condition"):
            name = ctx.raw(cond, "name") or ""
            if name.startswith(CRITERION_PREFIX):
                criteria.append(_criterion(cond, name[len(CRITERION_PREFIX) :], ctx))
            else:
                kept.append(condition(cond, ctx))
        if kept or not criteria:
            groups.append(c.ConditionGroup(conditions=tuple(kept), line=group.sourceline))
    return c.Trigger(condition_groups=tuple(groups), criteria=tuple(criteria), line=el.sourceline)


def _criterion(el: Element, test: str, ctx: reading.Context) -> c.Criterion:
    canonical = KNOWN_CRITERIA.get(test.lower())
    if canonical is None:
        ctx.deviation(
            el,
            "carla-criterion-unknown",
            f"ScenarioRunner criterion {test!r} is not one the stand-in knows; ScenarioRunner "
            "cannot build it as a test of the ego alone, so the run is Invalid",
        )
    elif canonical != test:
        ctx.deviation(
            el,
            "carla-criterion-unknown",
            f"ScenarioRunner criterion {test!r} is spelled {canonical!r} there (it looks the "
            "name up case-sensitively), so the run is Invalid",
        )
    arguments: list[tuple[str, str]] = []
    holder = reading.child(el, "ByValueCondition")
    inner = reading.child(holder, "ParameterCondition") if holder is not None else None
    if inner is not None:
        ref = ctx.raw(inner, "parameterRef") or ""
        if ref:
            arguments.append((ref, ctx.opt_string(inner, "value") or ""))
    return c.Criterion(
        test=test,
        known=canonical == test,
        arguments=tuple(arguments),
        line=el.sourceline,
    )


def condition(el: Element, ctx: reading.Context) -> c.Condition:
    """Read one ``<Condition>``."""
    chosen = ctx.choice(el)
    body: c.ByEntity | c.ByValue
    if chosen.tag == "ByEntityCondition":
        triggering = ctx.require(chosen, "TriggeringEntities")
        body = c.ByEntity(
            triggering_entities=ctx.entity_refs(
                ctx.string(ref, "entityRef")
                for ref in reading.all_children(triggering, "EntityRef")
            ),
            rule=ctx.enum(triggering, "triggeringEntitiesRule", c.TriggeringEntitiesRule),
            condition=entity_condition(ctx.choice(ctx.require(chosen, "EntityCondition")), ctx),
            line=chosen.sourceline,
        )
    elif chosen.tag == "ByValueCondition":
        body = c.ByValue(condition=value_condition(ctx.choice(chosen), ctx), line=chosen.sourceline)
    else:
        raise ctx.error(chosen, "expected ByEntityCondition or ByValueCondition")
    return c.Condition(
        name=ctx.opt_string(el, "name") or "",
        delay=ctx.double_or(el, "delay", 0.0, minimum=0.0),
        edge=ctx.enum(el, "conditionEdge", c.ConditionEdge),
        body=body,
        line=el.sourceline,
    )


def _distance_frame(
    el: Element, ctx: reading.Context, default_type: m.RelativeDistanceType
) -> tuple[m.CoordinateSystem, m.RelativeDistanceType, bool | None]:
    along_route = ctx.opt_boolean(el, "alongRoute")
    system = ctx.opt_enum(el, "coordinateSystem", m.CoordinateSystem)
    if system is None:
        system = m.CoordinateSystem.ROAD if along_route else m.CoordinateSystem.ENTITY
    kind = ctx.opt_enum(el, "relativeDistanceType", m.RelativeDistanceType, _DISTANCE_ALIASES)
    return system, kind or default_type, along_route


def entity_condition(el: Element, ctx: reading.Context) -> c.EntityCondition:
    """Read the chosen child of ``<EntityCondition>``."""
    return ctx.by_tag(el, _ENTITY_READERS, unknown="unknown entity condition")


class _DurationKind(Protocol):
    def __call__(self, *, duration: float, line: int | None) -> c.EntityCondition: ...


class _MotionKind(Protocol):
    def __call__(
        self,
        *,
        value: float,
        rule: m.Rule,
        direction: m.DirectionalDimension | None,
        line: int | None,
    ) -> c.EntityCondition: ...


def _duration(kind: _DurationKind) -> _EntityReader:
    """A reader of a condition holding only a ``duration`` (end of road, off road, standstill)."""

    def read(el: Element, ctx: reading.Context) -> c.EntityCondition:
        return kind(duration=ctx.double(el, "duration", minimum=0.0), line=el.sourceline)

    return read


def _motion(kind: _MotionKind) -> _EntityReader:
    """A reader of an acceleration or speed condition (same attributes)."""

    def read(el: Element, ctx: reading.Context) -> c.EntityCondition:
        return kind(
            value=ctx.double(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            direction=ctx.opt_enum(el, "direction", m.DirectionalDimension),
            line=el.sourceline,
        )

    return read


def _traveled_distance(el: Element, ctx: reading.Context) -> c.TraveledDistanceCondition:
    return c.TraveledDistanceCondition(
        value=ctx.double(el, "value", minimum=0.0), line=el.sourceline
    )


def _collision(el: Element, ctx: reading.Context) -> c.CollisionCondition:
    target = ctx.choice(el)
    if target.tag == "EntityRef":
        return c.CollisionCondition(entity_ref=ctx.string(target, "entityRef"), line=el.sourceline)
    return c.CollisionCondition(by_type=ctx.string(target, "type"), line=el.sourceline)


def _relative_speed(el: Element, ctx: reading.Context) -> c.RelativeSpeedCondition:
    return c.RelativeSpeedCondition(
        entity_ref=ctx.string(el, "entityRef"),
        value=ctx.double(el, "value"),
        rule=ctx.enum(el, "rule", m.Rule),
        direction=ctx.opt_enum(el, "direction", m.DirectionalDimension),
        line=el.sourceline,
    )


def _reach_position(el: Element, ctx: reading.Context) -> c.ReachPositionCondition:
    return c.ReachPositionCondition(
        position=positions.position(ctx.require(el, "Position"), ctx),
        tolerance=ctx.double(el, "tolerance", minimum=0.0),
        line=el.sourceline,
    )


def _time_headway(el: Element, ctx: reading.Context) -> c.TimeHeadwayCondition:
    system, kind, along = _distance_frame(el, ctx, m.RelativeDistanceType.LONGITUDINAL)
    return c.TimeHeadwayCondition(
        entity_ref=ctx.string(el, "entityRef"),
        value=ctx.double(el, "value", minimum=0.0),
        rule=ctx.enum(el, "rule", m.Rule),
        freespace=ctx.boolean(el, "freespace"),
        coordinate_system=system,
        relative_distance_type=kind,
        along_route=along,
        line=el.sourceline,
    )


def _distance(el: Element, ctx: reading.Context) -> c.DistanceCondition:
    system, kind, along = _distance_frame(el, ctx, m.RelativeDistanceType.EUCLIDEAN)
    return c.DistanceCondition(
        position=positions.position(ctx.require(el, "Position"), ctx),
        value=ctx.double(el, "value", minimum=0.0),
        rule=ctx.enum(el, "rule", m.Rule),
        freespace=ctx.boolean(el, "freespace"),
        coordinate_system=system,
        relative_distance_type=kind,
        along_route=along,
        routing_algorithm=ctx.opt_enum(el, "routingAlgorithm", m.RoutingAlgorithm),
        line=el.sourceline,
    )


def _relative_clearance(el: Element, ctx: reading.Context) -> c.RelativeClearanceCondition:
    return c.RelativeClearanceCondition(
        lane_ranges=tuple(
            (ctx.opt_integer(r, "from", 0) or 0, ctx.opt_integer(r, "to", 0) or 0)
            for r in reading.all_children(el, "RelativeLaneRange")
        ),
        entity_refs=tuple(
            ctx.string(ref, "entityRef") for ref in reading.all_children(el, "EntityRef")
        ),
        opposite_lanes=ctx.boolean(el, "oppositeLanes"),
        freespace=ctx.boolean(el, "freeSpace"),
        distance_forward=ctx.opt_double(el, "distanceForward", minimum=0.0),
        distance_backward=ctx.opt_double(el, "distanceBackward", minimum=0.0),
        line=el.sourceline,
    )


def _angle_frame(
    el: Element, ctx: reading.Context
) -> tuple[m.AngleType, m.CoordinateSystem] | m.Unsupported:
    """Angle type and coordinate system of an angle condition, or why they cannot be measured:
    the stand-in follows no trajectory frame and knows no road pitch or roll."""
    kind = ctx.enum(el, "angleType", m.AngleType)
    system = ctx.opt_enum(el, "coordinateSystem", m.CoordinateSystem) or m.CoordinateSystem.ENTITY
    if system is m.CoordinateSystem.TRAJECTORY:
        return ctx.unsupported(el, "angles in the trajectory coordinate system")
    road_frame = system in (m.CoordinateSystem.ROAD, m.CoordinateSystem.LANE)
    if road_frame and kind is not m.AngleType.HEADING:
        return ctx.unsupported(el, f"{kind} angles in the {system} coordinate system")
    return kind, system


def _angle(el: Element, ctx: reading.Context) -> c.AngleCondition | m.Unsupported:
    frame = _angle_frame(el, ctx)
    if isinstance(frame, m.Unsupported):
        return frame
    return c.AngleCondition(
        angle_type=frame[0],
        angle=ctx.double(el, "angle"),
        tolerance=ctx.double(el, "angleTolerance"),
        coordinate_system=frame[1],
        line=el.sourceline,
    )


def _relative_angle(el: Element, ctx: reading.Context) -> c.RelativeAngleCondition | m.Unsupported:
    frame = _angle_frame(el, ctx)
    if isinstance(frame, m.Unsupported):
        return frame
    return c.RelativeAngleCondition(
        entity_ref=ctx.string(el, "entityRef"),
        angle_type=frame[0],
        angle=ctx.double(el, "angle"),
        tolerance=ctx.double(el, "angleTolerance"),
        coordinate_system=frame[1],
        line=el.sourceline,
    )


def _relative_distance(el: Element, ctx: reading.Context) -> c.RelativeDistanceCondition:
    system, kind, _ = _distance_frame(el, ctx, m.RelativeDistanceType.EUCLIDEAN)
    return c.RelativeDistanceCondition(
        entity_ref=ctx.string(el, "entityRef"),
        value=ctx.double(el, "value", minimum=0.0),
        rule=ctx.enum(el, "rule", m.Rule),
        freespace=ctx.boolean(el, "freespace"),
        relative_distance_type=kind,
        coordinate_system=system,
        routing_algorithm=ctx.opt_enum(el, "routingAlgorithm", m.RoutingAlgorithm),
        line=el.sourceline,
    )


def _time_to_collision(el: Element, ctx: reading.Context) -> c.TimeToCollisionCondition:
    target = ctx.choice(ctx.require(el, "TimeToCollisionConditionTarget"))
    system, kind, along = _distance_frame(el, ctx, m.RelativeDistanceType.LONGITUDINAL)
    entity_ref = ctx.string(target, "entityRef") if target.tag == "EntityRef" else None
    position = positions.position(target, ctx) if target.tag == "Position" else None
    if entity_ref is None and position is None:
        raise ctx.error(target, "expected EntityRef or Position")
    return c.TimeToCollisionCondition(
        value=ctx.double(el, "value", minimum=0.0),
        rule=ctx.enum(el, "rule", m.Rule),
        freespace=ctx.boolean(el, "freespace"),
        entity_ref=entity_ref,
        position=position,
        coordinate_system=system,
        relative_distance_type=kind,
        along_route=along,
        line=el.sourceline,
    )


def value_condition(el: Element, ctx: reading.Context) -> c.ValueCondition:
    """Read the chosen child of ``<ByValueCondition>``."""
    return ctx.by_tag(el, _VALUE_READERS, unknown="unknown value condition")


def _simulation_time(el: Element, ctx: reading.Context) -> c.SimulationTimeCondition:
    return c.SimulationTimeCondition(
        value=ctx.double(el, "value"), rule=ctx.enum(el, "rule", m.Rule), line=el.sourceline
    )


def _storyboard_element_state(
    el: Element, ctx: reading.Context
) -> c.StoryboardElementStateCondition:
    return c.StoryboardElementStateCondition(
        element_type=ctx.enum(el, "storyboardElementType", c.StoryboardElementType),
        element_ref=ctx.string(el, "storyboardElementRef"),
        state=ctx.enum(el, "state", c.StoryboardElementState),
        line=el.sourceline,
    )


def _parameter(el: Element, ctx: reading.Context) -> c.ParameterCondition:
    return c.ParameterCondition(
        parameter_ref=ctx.string(el, "parameterRef"),
        value=ctx.string(el, "value"),
        rule=ctx.enum(el, "rule", m.Rule),
        line=el.sourceline,
    )


def _variable(el: Element, ctx: reading.Context) -> c.VariableCondition:
    return c.VariableCondition(
        variable_ref=ctx.string(el, "variableRef"),
        value=ctx.string(el, "value"),
        rule=ctx.enum(el, "rule", m.Rule),
        line=el.sourceline,
    )


def _traffic_signal(el: Element, ctx: reading.Context) -> c.TrafficSignalCondition:
    return c.TrafficSignalCondition(
        name=ctx.string(el, "name"), state=ctx.string(el, "state"), line=el.sourceline
    )


def _traffic_signal_controller(
    el: Element, ctx: reading.Context
) -> c.TrafficSignalControllerCondition:
    return c.TrafficSignalControllerCondition(
        controller_ref=ctx.string(el, "trafficSignalControllerRef"),
        phase=ctx.string(el, "phase"),
        line=el.sourceline,
    )


_ENTITY_READERS: Mapping[str, _EntityReader] = {
    "EndOfRoadCondition": _duration(c.EndOfRoadCondition),
    "OffroadCondition": _duration(c.OffRoadCondition),
    "StandStillCondition": _duration(c.StandStillCondition),
    "TraveledDistanceCondition": _traveled_distance,
    "CollisionCondition": _collision,
    "AccelerationCondition": _motion(c.AccelerationCondition),
    "SpeedCondition": _motion(c.SpeedCondition),
    "RelativeSpeedCondition": _relative_speed,
    "ReachPositionCondition": _reach_position,
    "TimeHeadwayCondition": _time_headway,
    "TimeToCollisionCondition": _time_to_collision,
    "DistanceCondition": _distance,
    "RelativeClearanceCondition": _relative_clearance,
    "RelativeDistanceCondition": _relative_distance,
    "AngleCondition": _angle,
    "RelativeAngleCondition": _relative_angle,
}
"""Supported ``<EntityCondition>`` children by tag (any other is unsupported)."""

_VALUE_READERS: Mapping[str, _ValueReader] = {
    "SimulationTimeCondition": _simulation_time,
    "StoryboardElementStateCondition": _storyboard_element_state,
    "ParameterCondition": _parameter,
    "VariableCondition": _variable,
    "TrafficSignalCondition": _traffic_signal,
    "TrafficSignalControllerCondition": _traffic_signal_controller,
    "TimeOfDayCondition": value_conditions.time_of_day,
    "UserDefinedValueCondition": value_conditions.user_defined_value,
}
"""Supported ``<ByValueCondition>`` children by tag (any other is unsupported)."""
