"""Reading actions (private, global, storyboard ``<Action>``) into the model."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import actions as a
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import controls as ctl
from simtest_operator.openscenario.readers import (
    controllers,
    positions,
    traffic,
    world_actions,
)
from simtest_operator.xmlsafe import Element

_PRIVATE_UNSUPPORTED = {
    "TrailerAction": "trailers are not simulated",
}
_GLOBAL_UNSUPPORTED = {
    "SetMonitorAction": "monitors are not supported",
}


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
    else:
        body = ctx.unsupported(chosen, "user-defined actions are not supported")
    return a.Action(
        name=ctx.string(el, "name"),
        body=body,
        is_private=chosen.tag == "PrivateAction",
        line=el.sourceline,
    )


def _ignored(el: Element, ctx: reading.Context) -> ctl.IgnoredAction:
    ctx.ignore(str(el.tag))
    return ctl.IgnoredAction(kind=str(el.tag), line=el.sourceline)


def private(el: Element, ctx: reading.Context) -> a.PrivateAction:
    """Read a ``<PrivateAction>``."""
    chosen = ctx.choice(el)
    tag = chosen.tag
    if tag == "LongitudinalAction":
        return _longitudinal(ctx.choice(chosen), ctx)
    if tag == "LateralAction":
        return _lateral(ctx.choice(chosen), ctx)
    if tag == "TeleportAction":
        return a.TeleportAction(
            position=positions.position(ctx.require(chosen, "Position"), ctx),
            line=chosen.sourceline,
        )
    if tag == "RoutingAction":
        return _routing(ctx.choice(chosen), ctx)
    if tag == "SynchronizeAction":
        return _synchronize(chosen, ctx)
    if tag == "ActivateControllerAction":
        return controllers.activate(chosen, ctx)
    if tag == "ControllerAction":
        return controllers.controller_action(chosen, ctx)
    if tag == "VisibilityAction":
        return _ignored(chosen, ctx)
    if tag == "AppearanceAction":
        return _ignored(ctx.choice(chosen), ctx)
    reason = _PRIVATE_UNSUPPORTED.get(str(tag), f"unknown private action {tag}")
    return ctx.unsupported(chosen, reason)


def global_(el: Element, ctx: reading.Context) -> a.GlobalAction:
    """Read a ``<GlobalAction>``."""
    chosen = ctx.choice(el)
    tag = chosen.tag
    if tag == "EnvironmentAction":
        return world_actions.environment_action(chosen, ctx)
    if tag == "EntityAction":
        return world_actions.entity_action(chosen, ctx)
    if tag in ("ParameterAction", "VariableAction"):
        scope = m.ValueScope.PARAMETER if tag == "ParameterAction" else m.ValueScope.VARIABLE
        ref = ctx.string(chosen, "parameterRef" if tag == "ParameterAction" else "variableRef")
        inner = ctx.choice(chosen)
        if inner.tag == "SetAction":
            return ctl.SetValueAction(
                scope=scope, ref=ref, value=ctx.string(inner, "value"), line=chosen.sourceline
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
                line=chosen.sourceline,
            )
        raise ctx.error(inner, "expected SetAction or ModifyAction")
    if tag == "TrafficAction":
        return traffic.traffic_action(chosen, ctx)
    if tag == "InfrastructureAction":
        signal = ctx.choice(ctx.require(chosen, "TrafficSignalAction"))
        if signal.tag == "TrafficSignalStateAction":
            return ctl.TrafficSignalStateAction(
                name=ctx.string(signal, "name"),
                state=ctx.string(signal, "state"),
                line=signal.sourceline,
            )
        return ctx.unsupported(signal, "traffic signal controllers are not simulated")
    reason = _GLOBAL_UNSUPPORTED.get(str(tag), f"unknown global action {tag}")
    return ctx.unsupported(chosen, reason)


def _dynamics(el: Element, ctx: reading.Context) -> a.TransitionDynamics:
    return a.TransitionDynamics(
        shape=ctx.enum(el, "dynamicsShape", a.DynamicsShape),
        dimension=ctx.enum(el, "dynamicsDimension", a.DynamicsDimension),
        value=ctx.double(el, "value"),
        following_mode=ctx.opt_enum(el, "followingMode", a.FollowingMode),
        line=el.sourceline,
    )


def _constraints(el: Element | None, ctx: reading.Context) -> a.DynamicConstraints | None:
    if el is None:
        return None
    return a.DynamicConstraints(
        max_acceleration=ctx.opt_double(el, "maxAcceleration"),
        max_deceleration=ctx.opt_double(el, "maxDeceleration"),
        max_speed=ctx.opt_double(el, "maxSpeed"),
        max_acceleration_rate=ctx.opt_double(el, "maxAccelerationRate"),
        max_deceleration_rate=ctx.opt_double(el, "maxDecelerationRate"),
        line=el.sourceline,
    )


def _longitudinal(el: Element, ctx: reading.Context) -> a.PrivateAction:
    tag, line = el.tag, el.sourceline
    if tag == "SpeedAction":
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
            line=line,
        )
    if tag == "LongitudinalDistanceAction":
        return a.LongitudinalDistanceAction(
            entity_ref=ctx.string(el, "entityRef"),
            freespace=ctx.boolean(el, "freespace"),
            continuous=ctx.boolean(el, "continuous"),
            distance=ctx.opt_double(el, "distance"),
            time_gap=ctx.opt_double(el, "timeGap"),
            coordinate_system=ctx.opt_enum(el, "coordinateSystem", m.CoordinateSystem)
            or m.CoordinateSystem.ENTITY,
            displacement=ctx.opt_enum(el, "displacement", a.LongitudinalDisplacement)
            or a.LongitudinalDisplacement.TRAILING,
            constraints=_constraints(reading.child(el, "DynamicConstraints"), ctx),
            line=line,
        )
    if tag == "SpeedProfileAction":
        entries = tuple(
            a.SpeedProfileEntry(
                speed=ctx.double(entry, "speed"),
                time=ctx.opt_double(entry, "time"),
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
            line=line,
        )
    return ctx.unsupported(el, f"unknown longitudinal action {tag}")


def _lateral(el: Element, ctx: reading.Context) -> a.PrivateAction:
    tag, line = el.tag, el.sourceline
    if tag == "LaneChangeAction":
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
            line=line,
        )
    if tag == "LaneOffsetAction":
        dyn = ctx.require(el, "LaneOffsetActionDynamics")
        target_el = ctx.choice(ctx.require(el, "LaneOffsetTarget"))
        offset: a.AbsoluteTargetLaneOffset | a.RelativeTargetLaneOffset
        if target_el.tag == "AbsoluteTargetLaneOffset":
            offset = a.AbsoluteTargetLaneOffset(
                value=ctx.double(target_el, "value"), line=target_el.sourceline
            )
        elif target_el.tag == "RelativeTargetLaneOffset":
            offset = a.RelativeTargetLaneOffset(
                entity_ref=ctx.string(target_el, "entityRef"),
                value=ctx.double(target_el, "value"),
                line=target_el.sourceline,
            )
        else:
            raise ctx.error(
                target_el, "expected AbsoluteTargetLaneOffset or RelativeTargetLaneOffset"
            )
        return a.LaneOffsetAction(
            continuous=ctx.boolean(el, "continuous"),
            shape=ctx.enum(dyn, "dynamicsShape", a.DynamicsShape),
            target=offset,
            max_lateral_acc=ctx.opt_double(dyn, "maxLateralAcc"),
            line=line,
        )
    if tag == "LateralDistanceAction":
        return a.LateralDistanceAction(
            entity_ref=ctx.string(el, "entityRef"),
            freespace=ctx.boolean(el, "freespace"),
            continuous=ctx.boolean(el, "continuous"),
            distance=ctx.opt_double(el, "distance"),
            coordinate_system=ctx.opt_enum(el, "coordinateSystem", m.CoordinateSystem)
            or m.CoordinateSystem.ENTITY,
            displacement=ctx.opt_enum(el, "displacement", a.LateralDisplacement)
            or a.LateralDisplacement.ANY,
            constraints=_constraints(reading.child(el, "DynamicConstraints"), ctx),
            line=line,
        )
    return ctx.unsupported(el, f"unknown lateral action {tag}")


def _routing(el: Element, ctx: reading.Context) -> a.PrivateAction:
    tag, line = el.tag, el.sourceline
    if tag == "AssignRouteAction":
        return a.AssignRouteAction(route=positions.route_or_ref(el, ctx), line=line)
    if tag == "AcquirePositionAction":
        return a.AcquirePositionAction(
            position=positions.position(ctx.require(el, "Position"), ctx), line=line
        )
    if tag == "FollowTrajectoryAction":
        return _follow_trajectory(el, ctx)
    if tag == "RandomRouteAction":
        return ctx.unsupported(el, "random routes are not supported")
    return ctx.unsupported(el, f"unknown routing action {tag}")


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
        target_tolerance_master=ctx.opt_double(el, "targetToleranceMaster"),
        target_tolerance=ctx.opt_double(el, "targetTolerance"),
        line=el.sourceline,
    )


def _steady_state(el: Element, ctx: reading.Context) -> a.SteadyState | None:
    holder = reading.child(el, "SteadyState")
    candidates = reading.children(holder) if holder is not None else reading.children(el)
    for node in candidates:
        if node.tag == "TargetDistanceSteadyState":
            return a.SteadyState(distance=ctx.double(node, "distance"), line=node.sourceline)
        if node.tag == "TargetTimeSteadyState":
            return a.SteadyState(time=ctx.double(node, "time"), line=node.sourceline)
    return None
