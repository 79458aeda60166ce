"""Reading triggers, condition groups and conditions into the model."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import trigger_conditions as c
from simtest_operator.openscenario.readers import positions
from simtest_operator.xmlsafe import Element

_DISTANCE_ALIASES = {"cartesianDistance": m.RelativeDistanceType.EUCLIDEAN}
_UNSUPPORTED_ENTITY = {
    "AngleCondition": "angle conditions are not implemented",
    "RelativeAngleCondition": "relative angle conditions are not implemented",
}
_UNSUPPORTED_VALUE = {
    "TimeOfDayCondition": "time of day is not simulated",
    "UserDefinedValueCondition": "user-defined values have no source in the stand-in",
    "TrafficSignalControllerCondition": "traffic signal controllers are not simulated",
}


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
    )
}
"""ScenarioRunner's test criteria by lower-case name (its documentation writes both
``OnSideWalkTest`` and ``OnSidewalkTest``)."""


def stop_trigger(el: Element | None, ctx: reading.Context) -> c.Trigger | None:
    """Read the storyboard's StopTrigger, taking ScenarioRunner's ``criteria_<Test>`` conditions
    out as :class:`~.model.trigger_conditions.Criterion` (they are tests over the run, not stop
    conditions; their ParameterConditions name undeclared or empty parameters)."""
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
            f"ScenarioRunner criterion {test!r} is not one the stand-in knows; it is listed as "
            "not evaluated",
        )
    arguments: list[tuple[str, str]] = []
    holder = reading.child(el, "ByValueCondition")
    inner = reading.child(holder, "ParameterCondition") if holder is not None else None
    if inner is not None:
        ref = ctx.raw(inner, "parameterRef") or ""
        if ref:
            arguments.append((ref, ctx.opt_string(inner, "value") or ""))
    return c.Criterion(
        test=canonical or test,
        known=canonical is not None,
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
            triggering_entities=tuple(
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
        delay=ctx.double_or(el, "delay", 0.0),
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
    tag, line = el.tag, el.sourceline
    if tag == "EndOfRoadCondition":
        return c.EndOfRoadCondition(duration=ctx.double(el, "duration"), line=line)
    if tag == "OffroadCondition":
        return c.OffRoadCondition(duration=ctx.double(el, "duration"), line=line)
    if tag == "StandStillCondition":
        return c.StandStillCondition(duration=ctx.double(el, "duration"), line=line)
    if tag == "TraveledDistanceCondition":
        return c.TraveledDistanceCondition(value=ctx.double(el, "value"), line=line)
    if tag == "CollisionCondition":
        target = ctx.choice(el)
        if target.tag == "EntityRef":
            return c.CollisionCondition(entity_ref=ctx.string(target, "entityRef"), line=line)
        return c.CollisionCondition(by_type=ctx.string(target, "type"), line=line)
    if tag in ("AccelerationCondition", "SpeedCondition"):
        kind = c.AccelerationCondition if tag == "AccelerationCondition" else c.SpeedCondition
        return kind(
            value=ctx.double(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            direction=ctx.opt_enum(el, "direction", m.DirectionalDimension),
            line=line,
        )
    if tag == "RelativeSpeedCondition":
        return c.RelativeSpeedCondition(
            entity_ref=ctx.string(el, "entityRef"),
            value=ctx.double(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            direction=ctx.opt_enum(el, "direction", m.DirectionalDimension),
            line=line,
        )
    if tag == "ReachPositionCondition":
        return c.ReachPositionCondition(
            position=positions.position(ctx.require(el, "Position"), ctx),
            tolerance=ctx.double(el, "tolerance"),
            line=line,
        )
    if tag == "TimeHeadwayCondition":
        system, kind_, along = _distance_frame(el, ctx, m.RelativeDistanceType.LONGITUDINAL)
        return c.TimeHeadwayCondition(
            entity_ref=ctx.string(el, "entityRef"),
            value=ctx.double(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            freespace=ctx.boolean(el, "freespace"),
            coordinate_system=system,
            relative_distance_type=kind_,
            along_route=along,
            line=line,
        )
    if tag == "TimeToCollisionCondition":
        return _time_to_collision(el, ctx)
    if tag == "DistanceCondition":
        system, kind_, along = _distance_frame(el, ctx, m.RelativeDistanceType.EUCLIDEAN)
        return c.DistanceCondition(
            position=positions.position(ctx.require(el, "Position"), ctx),
            value=ctx.double(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            freespace=ctx.boolean(el, "freespace"),
            coordinate_system=system,
            relative_distance_type=kind_,
            along_route=along,
            routing_algorithm=ctx.opt_enum(el, "routingAlgorithm", m.RoutingAlgorithm),
            line=line,
        )
    if tag == "RelativeClearanceCondition":
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
            distance_forward=ctx.opt_double(el, "distanceForward"),
            distance_backward=ctx.opt_double(el, "distanceBackward"),
            line=line,
        )
    if tag == "RelativeDistanceCondition":
        system, kind_, _ = _distance_frame(el, ctx, m.RelativeDistanceType.EUCLIDEAN)
        return c.RelativeDistanceCondition(
            entity_ref=ctx.string(el, "entityRef"),
            value=ctx.double(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            freespace=ctx.boolean(el, "freespace"),
            relative_distance_type=kind_,
            coordinate_system=system,
            routing_algorithm=ctx.opt_enum(el, "routingAlgorithm", m.RoutingAlgorithm),
            line=line,
        )
    reason = _UNSUPPORTED_ENTITY.get(str(tag), f"unknown entity condition {tag}")
    return ctx.unsupported(el, reason)


def _time_to_collision(el: Element, ctx: reading.Context) -> c.TimeToCollisionCondition:
    target = ctx.choice(ctx.require(el, "TimeToCollisionConditionTarget"))
    system, kind, along = _distance_frame(el, ctx, m.RelativeDistanceType.LONGITUDINAL)
    entity_ref = ctx.string(target, "entityRef") if target.tag == "EntityRef" else None
    position = positions.position(target, ctx) if target.tag == "Position" else None
    if entity_ref is None and position is None:
        raise ctx.error(target, "expected EntityRef or Position")
    return c.TimeToCollisionCondition(
        value=ctx.double(el, "value"),
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
    tag, line = el.tag, el.sourceline
    if tag == "SimulationTimeCondition":
        return c.SimulationTimeCondition(
            value=ctx.double(el, "value"), rule=ctx.enum(el, "rule", m.Rule), line=line
        )
    if tag == "StoryboardElementStateCondition":
        return c.StoryboardElementStateCondition(
            element_type=ctx.enum(el, "storyboardElementType", c.StoryboardElementType),
            element_ref=ctx.string(el, "storyboardElementRef"),
            state=ctx.enum(el, "state", c.StoryboardElementState),
            line=line,
        )
    if tag == "ParameterCondition":
        return c.ParameterCondition(
            parameter_ref=ctx.string(el, "parameterRef"),
            value=ctx.string(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            line=line,
        )
    if tag == "VariableCondition":
        return c.VariableCondition(
            variable_ref=ctx.string(el, "variableRef"),
            value=ctx.string(el, "value"),
            rule=ctx.enum(el, "rule", m.Rule),
            line=line,
        )
    if tag == "TrafficSignalCondition":
        return c.TrafficSignalCondition(
            name=ctx.string(el, "name"), state=ctx.string(el, "state"), line=line
        )
    reason = _UNSUPPORTED_VALUE.get(str(tag), f"unknown value condition {tag}")
    return ctx.unsupported(el, reason)
