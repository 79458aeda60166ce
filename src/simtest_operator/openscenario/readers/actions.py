"""Reading actions (private, global, storyboard ``<Action>``) into the model."""

from __future__ import annotations

from collections.abc import Callable, Mapping

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import actions as a
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import controls as ctl
from simtest_operator.openscenario.readers import (
    controllers,
    monitors,
    positions,
    traffic,
    world_actions,
)
from simtest_operator.xmlsafe import Element


def storyboard_action(el: Element, ctx: reading.Context) -> a.Action:
    """Read a named storyboard ``<Action>``; one without a child (a placeholder some tools
    write) does nothing and is reported as a deviation."""
    chosen = reading.first_child(el)
    if chosen is None:
        ctx.deviation(el, "empty-action", "Action without a child read as doing nothing")
        return a.Action(
            name=ctx.string(el, "name"),
            body=ctl.IgnoredAction(kind="Action (empty)", line=el.sourceline),
            is_private=False,
            line=el.sourceline,
        )
    body: a.AnyAction
    if chosen.tag == "PrivateAction":
        body = private(chosen, ctx)
    elif chosen.tag == "GlobalAction":
        body = global_(chosen, ctx)
    elif chosen.tag == "UserDefinedAction":
        body = user_defined(chosen, ctx)
    else:
        body = ctx.unsupported(chosen, f"unknown action {chosen.tag}")
    return a.Action(
        name=ctx.string(el, "name"),
        body=body,
        is_private=chosen.tag == "PrivateAction",
        line=el.sourceline,
    )


def user_defined(el: Element, ctx: reading.Context) -> ctl.IgnoredAction:
    """A ``<UserDefinedAction>`` (a ``CustomCommandAction`` for the user's own tool): nothing in
    the stand-in can run it, and nothing it does is visible to the scenario, so it completes at
    once and is listed as ignored (``UserDefinedAction (type)``)."""
    command = reading.child(el, "CustomCommandAction")
    kind = ctx.opt_string(command, "type") if command is not None else None
    label = f"UserDefinedAction ({kind})" if kind else "UserDefinedAction"
    ctx.ignore(label)
    return ctl.IgnoredAction(kind=label, line=el.sourceline)


def _ignored(el: Element, ctx: reading.Context) -> ctl.IgnoredAction:
    ctx.ignore(str(el.tag))
    return ctl.IgnoredAction(kind=str(el.tag), line=el.sourceline)


def private(el: Element, ctx: reading.Context) -> a.PrivateAction:
    """Read a ``<PrivateAction>``."""
    return ctx.by_tag(
        ctx.choice(el),
        _PRIVATE_READERS,
        unknown="unknown private action",
    )


def _teleport(el: Element, ctx: reading.Context) -> a.TeleportAction:
    return a.TeleportAction(
        position=positions.position(ctx.require(el, "Position"), ctx), line=el.sourceline
    )


def _trailer(el: Element, ctx: reading.Context) -> a.TrailerAction:
    chosen = ctx.choice(el)
    if chosen.tag == "ConnectTrailerAction":
        return a.TrailerAction(trailer_ref=ctx.string(chosen, "trailerRef"), line=el.sourceline)
    if chosen.tag == "DisconnectTrailerAction":
        return a.TrailerAction(trailer_ref=None, line=el.sourceline)
    raise ctx.error(chosen, f"unknown trailer action {chosen.tag}")


def global_(el: Element, ctx: reading.Context) -> a.GlobalAction:
    """Read a ``<GlobalAction>``."""
    return ctx.by_tag(
        ctx.choice(el),
        _GLOBAL_READERS,
        unknown="unknown global action",
    )


def _value_action(el: Element, ctx: reading.Context) -> a.GlobalAction:
    """A ParameterAction or VariableAction (the same but for the reference attribute)."""
    tag = el.tag
    scope = m.ValueScope.PARAMETER if tag == "ParameterAction" else m.ValueScope.VARIABLE
    ref = ctx.string(el, "parameterRef" if tag == "ParameterAction" else "variableRef")
    inner = ctx.choice(el)
    if inner.tag == "SetAction":
        return ctl.SetValueAction(
            scope=scope, ref=ref, value=ctx.string(inner, "value"), line=el.sourceline
        )
    if inner.tag == "ModifyAction":
        rule = ctx.choice(ctx.require(inner, "Rule"))
        kind = {"AddValue": ctl.ModifyRule.ADD, "MultiplyByValue": ctl.ModifyRule.MULTIPLY}.get(
            str(rule.tag)
        )
        if kind is None:
            raise ctx.error(rule, "expected AddValue or MultiplyByValue")
        return ctl.ModifyValueAction(
            scope=scope,
            ref=ref,
            rule=kind,
            value=ctx.double(rule, "value"),
            line=el.sourceline,
        )
    raise ctx.error(inner, "expected SetAction or ModifyAction")


def _infrastructure(el: Element, ctx: reading.Context) -> a.GlobalAction:
    signal = ctx.choice(ctx.require(el, "TrafficSignalAction"))
    if signal.tag == "TrafficSignalStateAction":
        return ctl.TrafficSignalStateAction(
            name=ctx.string(signal, "name"),
            state=ctx.string(signal, "state"),
            line=signal.sourceline,
        )
    if signal.tag == "TrafficSignalControllerAction":
        return ctl.TrafficSignalControllerAction(
            controller_ref=ctx.string(signal, "trafficSignalControllerRef"),
            phase=ctx.string(signal, "phase"),
            line=signal.sourceline,
        )
    return ctx.unsupported(signal, "not a traffic signal action of OpenSCENARIO 1.x")


def _dynamics(el: Element, ctx: reading.Context) -> a.TransitionDynamics:
    # A duration or distance below 0 cannot be run (LaneChangeTime -2.5 ended Error, issue 29); a
    # negative rate is common in real files (a deceleration) and only its size counts.
    dimension = ctx.enum(el, "dynamicsDimension", a.DynamicsDimension)
    rate = dimension is a.DynamicsDimension.RATE
    return a.TransitionDynamics(
        shape=ctx.enum(el, "dynamicsShape", a.DynamicsShape),
        dimension=dimension,
        value=ctx.double(el, "value", minimum=None if rate else 0.0),
        following_mode=ctx.opt_enum(el, "followingMode", a.FollowingMode),
        line=el.sourceline,
    )


def _constraints(el: Element | None, ctx: reading.Context) -> a.DynamicConstraints | None:
    if el is None:
        return None
    return a.DynamicConstraints(
        max_acceleration=ctx.opt_double(el, "maxAcceleration", minimum=0.0),
        max_deceleration=ctx.opt_double(el, "maxDeceleration", minimum=0.0),
        max_speed=ctx.opt_double(el, "maxSpeed", minimum=0.0),
        max_acceleration_rate=ctx.opt_double(el, "maxAccelerationRate", minimum=0.0),
        max_deceleration_rate=ctx.opt_double(el, "maxDecelerationRate", minimum=0.0),
        line=el.sourceline,
    )


def _speed(el: Element, ctx: reading.Context) -> a.SpeedAction:
    target_el = ctx.choice(ctx.require(el, "SpeedActionTarget"))
    target: a.AbsoluteTargetSpeed | a.RelativeTargetSpeed
    if target_el.tag == "AbsoluteTargetSpeed":
        target = a.AbsoluteTargetSpeed(
            value=ctx.double(target_el, "value"), line=target_el.sourceline
        )
    elif target_el.tag == "RelativeTargetSpeed":
        target = a.RelativeTargetSpeed(
            entity_ref=ctx.string(target_el, "entityRef"),
            value=ctx.double(target_el, "value"),
            value_type=ctx.enum(target_el, "speedTargetValueType", a.SpeedTargetValueType),
            continuous=ctx.boolean(target_el, "continuous"),
            line=target_el.sourceline,
        )
    else:
        raise ctx.error(target_el, "expected AbsoluteTargetSpeed or RelativeTargetSpeed")
    return a.SpeedAction(
        dynamics=_dynamics(ctx.require(el, "SpeedActionDynamics"), ctx),
        target=target,
        line=el.sourceline,
    )


def _longitudinal_distance(el: Element, ctx: reading.Context) -> a.LongitudinalDistanceAction:
    return a.LongitudinalDistanceAction(
        entity_ref=ctx.string(el, "entityRef"),
        freespace=ctx.boolean(el, "freespace"),
        continuous=ctx.boolean(el, "continuous"),
        distance=ctx.opt_double(el, "distance", minimum=0.0),
        time_gap=ctx.opt_double(el, "timeGap", minimum=0.0),
        coordinate_system=ctx.opt_enum(el, "coordinateSystem", m.CoordinateSystem)
        or m.CoordinateSystem.ENTITY,
        displacement=ctx.opt_enum(el, "displacement", a.LongitudinalDisplacement)
        or a.LongitudinalDisplacement.TRAILING,
        constraints=_constraints(reading.child(el, "DynamicConstraints"), ctx),
        line=el.sourceline,
    )


def _speed_profile(el: Element, ctx: reading.Context) -> a.SpeedProfileAction:
    entries = tuple(
        a.SpeedProfileEntry(
            speed=ctx.double(entry, "speed"),
            time=ctx.opt_double(entry, "time", minimum=0.0),
            line=entry.sourceline,
        )
        for entry in reading.all_children(el, "SpeedProfileEntry")
    )
    if not entries:
        raise ctx.error(el, "a speed profile needs at least one SpeedProfileEntry")
    return a.SpeedProfileAction(
        following_mode=ctx.enum(el, "followingMode", a.FollowingMode),
        entries=entries,
        entity_ref=ctx.opt_string(el, "entityRef"),
        constraints=_constraints(reading.child(el, "DynamicConstraints"), ctx),
        line=el.sourceline,
    )


def _lane_change(el: Element, ctx: reading.Context) -> a.LaneChangeAction:
    target_el = ctx.choice(ctx.require(el, "LaneChangeTarget"))
    target: a.AbsoluteTargetLane | a.RelativeTargetLane
    if target_el.tag == "AbsoluteTargetLane":
        target = a.AbsoluteTargetLane(
            lane_id=ctx.integer(target_el, "value"), line=target_el.sourceline
        )
    elif target_el.tag == "RelativeTargetLane":
        target = a.RelativeTargetLane(
            entity_ref=ctx.string(target_el, "entityRef"),
            value=ctx.integer(target_el, "value"),
            line=target_el.sourceline,
        )
    else:
        raise ctx.error(target_el, "expected AbsoluteTargetLane or RelativeTargetLane")
    return a.LaneChangeAction(
        dynamics=_dynamics(ctx.require(el, "LaneChangeActionDynamics"), ctx),
        target=target,
        target_lane_offset=ctx.opt_double(el, "targetLaneOffset"),
        line=el.sourceline,
    )


def _lane_offset(el: Element, ctx: reading.Context) -> a.LaneOffsetAction:
    dyn = ctx.require(el, "LaneOffsetActionDynamics")
    target_el = ctx.choice(ctx.require(el, "LaneOffsetTarget"))
    offset: a.AbsoluteTargetLaneOffset | a.RelativeTargetLaneOffset
    if target_el.tag == "AbsoluteTargetLaneOffset":
        offset = a.AbsoluteTargetLaneOffset(
            value=positions.lateral(ctx, ctx.double(target_el, "value")), line=target_el.sourceline
        )
    elif target_el.tag == "RelativeTargetLaneOffset":
        offset = a.RelativeTargetLaneOffset(
            entity_ref=ctx.string(target_el, "entityRef"),
            value=positions.lateral(ctx, ctx.double(target_el, "value")),
            line=target_el.sourceline,
        )
    else:
        raise ctx.error(target_el, "expected AbsoluteTargetLaneOffset or RelativeTargetLaneOffset")
    return a.LaneOffsetAction(
        continuous=ctx.boolean(el, "continuous"),
        shape=ctx.enum(dyn, "dynamicsShape", a.DynamicsShape),
        target=offset,
        max_lateral_acc=ctx.opt_double(dyn, "maxLateralAcc", minimum=0.0),
        line=el.sourceline,
    )


def _lateral_distance(el: Element, ctx: reading.Context) -> a.LateralDistanceAction:
    return a.LateralDistanceAction(
        entity_ref=ctx.string(el, "entityRef"),
        freespace=ctx.boolean(el, "freespace"),
        continuous=ctx.boolean(el, "continuous"),
        distance=ctx.opt_double(el, "distance", minimum=0.0),
        coordinate_system=ctx.opt_enum(el, "coordinateSystem", m.CoordinateSystem)
        or m.CoordinateSystem.ENTITY,
        displacement=ctx.opt_enum(el, "displacement", a.LateralDisplacement)
        or a.LateralDisplacement.ANY,
        constraints=_constraints(reading.child(el, "DynamicConstraints"), ctx),
        line=el.sourceline,
    )


def _assign_route(el: Element, ctx: reading.Context) -> a.AssignRouteAction:
    return a.AssignRouteAction(route=positions.route_or_ref(el, ctx), line=el.sourceline)


def _acquire_position(el: Element, ctx: reading.Context) -> a.AcquirePositionAction:
    return a.AcquirePositionAction(
        position=positions.position(ctx.require(el, "Position"), ctx), line=el.sourceline
    )


def _follow_trajectory(el: Element, ctx: reading.Context) -> a.FollowTrajectoryAction:
    holder = reading.child(el, "TrajectoryRef")
    source = ctx.choice(holder) if holder is not None else None
    if source is None:
        source = reading.child(el, "Trajectory")
    if source is None:
        source = reading.child(el, "CatalogReference")
    if source is None:
        raise ctx.error(el, "missing Trajectory, TrajectoryRef or CatalogReference")
    timing: a.Timing | None = None
    time_ref = reading.child(el, "TimeReference")
    timing_el = reading.child(time_ref, "Timing") if time_ref is not None else None
    if timing_el is not None:
        timing = a.Timing(
            domain=ctx.enum(timing_el, "domainAbsoluteRelative", m.ReferenceContext),
            scale=ctx.double(timing_el, "scale"),
            offset=ctx.double(timing_el, "offset"),
            line=timing_el.sourceline,
        )
    mode_el = reading.child(el, "TrajectoryFollowingMode")
    mode = (
        ctx.enum(mode_el, "followingMode", a.FollowingMode)
        if mode_el is not None
        else a.FollowingMode.POSITION
    )
    return a.FollowTrajectoryAction(
        trajectory=positions.trajectory_or_ref(source, ctx),
        following_mode=mode,
        timing=timing,
        initial_distance_offset=ctx.opt_double(el, "initialDistanceOffset"),
        line=el.sourceline,
    )


def _synchronize(el: Element, ctx: reading.Context) -> a.SynchronizeAction:
    final_speed: a.AbsoluteFinalSpeed | a.RelativeFinalSpeed | None = None
    final_el = reading.child(el, "FinalSpeed")
    if final_el is not None:
        chosen = ctx.choice(final_el)
        steady = _steady_state(chosen, ctx)
        if chosen.tag == "AbsoluteSpeed":
            final_speed = a.AbsoluteFinalSpeed(
                value=ctx.double(chosen, "value"), steady_state=steady, line=chosen.sourceline
            )
        else:
            final_speed = a.RelativeFinalSpeed(
                value=ctx.double(chosen, "value"),
                value_type=ctx.enum(chosen, "speedTargetValueType", a.SpeedTargetValueType),
                steady_state=steady,
                line=chosen.sourceline,
            )
    return a.SynchronizeAction(
        master_entity_ref=ctx.string(el, "masterEntityRef"),
        target_position_master=positions.position(ctx.require(el, "TargetPositionMaster"), ctx),
        target_position=positions.position(ctx.require(el, "TargetPosition"), ctx),
        final_speed=final_speed,
        target_tolerance_master=ctx.opt_double(el, "targetToleranceMaster", minimum=0.0),
        target_tolerance=ctx.opt_double(el, "targetTolerance", minimum=0.0),
        line=el.sourceline,
    )


def _steady_state(el: Element, ctx: reading.Context) -> a.SteadyState | None:
    holder = reading.child(el, "SteadyState")
    candidates = reading.children(holder) if holder is not None else reading.children(el)
    for node in candidates:
        if node.tag == "TargetDistanceSteadyState":
            return a.SteadyState(
                distance=ctx.double(node, "distance", minimum=0.0), line=node.sourceline
            )
        if node.tag == "TargetTimeSteadyState":
            return a.SteadyState(time=ctx.double(node, "time", minimum=0.0), line=node.sourceline)
    return None


_PrivateReader = Callable[[Element, reading.Context], a.PrivateAction]


def _one_of(
    readers: Mapping[str, _PrivateReader], *, unknown: str, reasons: Mapping[str, str] | None = None
) -> _PrivateReader:
    """A reader of a category element (LongitudinalAction, ...): its one child, by tag."""
    return lambda el, ctx: ctx.by_tag(ctx.choice(el), readers, unknown=unknown, reasons=reasons)


_LONGITUDINAL_READERS: Mapping[str, _PrivateReader] = {
    "SpeedAction": _speed,
    "LongitudinalDistanceAction": _longitudinal_distance,
    "SpeedProfileAction": _speed_profile,
}

_LATERAL_READERS: Mapping[str, _PrivateReader] = {
    "LaneChangeAction": _lane_change,
    "LaneOffsetAction": _lane_offset,
    "LateralDistanceAction": _lateral_distance,
}

_ROUTING_READERS: Mapping[str, _PrivateReader] = {
    "AssignRouteAction": _assign_route,
    "AcquirePositionAction": _acquire_position,
    "FollowTrajectoryAction": _follow_trajectory,
    "RandomRouteAction": lambda el, ctx: a.RandomRouteAction(line=el.sourceline),
}

_PRIVATE_READERS: Mapping[str, _PrivateReader] = {
    "LongitudinalAction": _one_of(_LONGITUDINAL_READERS, unknown="unknown longitudinal action"),
    "LateralAction": _one_of(_LATERAL_READERS, unknown="unknown lateral action"),
    "TeleportAction": _teleport,
    "TrailerAction": _trailer,
    "RoutingAction": _one_of(
        _ROUTING_READERS,
        unknown="unknown routing action",
    ),
    "SynchronizeAction": _synchronize,
    "ActivateControllerAction": controllers.activate,
    "ControllerAction": controllers.controller_action,
    "VisibilityAction": _ignored,
    "AppearanceAction": lambda el, ctx: _ignored(ctx.choice(el), ctx),
}
"""Supported ``<PrivateAction>`` children by tag."""

_GLOBAL_READERS: Mapping[str, Callable[[Element, reading.Context], a.GlobalAction]] = {
    "EnvironmentAction": world_actions.environment_action,
    "EntityAction": world_actions.entity_action,
    "ParameterAction": _value_action,
    "VariableAction": _value_action,
    "TrafficAction": traffic.traffic_action,
    "InfrastructureAction": _infrastructure,
    "SetMonitorAction": monitors.set_monitor,
}
"""Supported ``<GlobalAction>`` children by tag (any other is unsupported)."""
