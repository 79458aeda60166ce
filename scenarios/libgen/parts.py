"""Building blocks shared by every scenario template.

The templates only combine these parts, so every file in the library uses the same small,
mainstream subset of OpenSCENARIO 1.2 (Teleport with LanePosition, SpeedAction,
LaneChangeAction, ActivateControllerAction, AssignRouteAction, FollowTrajectoryAction with a
polyline, and SimulationTime / RelativeDistance / TraveledDistance / StoryboardElementState
conditions). Keeping the subset in one module is what lets the in-house engine promise to run
the whole library.
"""

from __future__ import annotations

from collections.abc import Sequence

from scenariogeneration import xosc

SUT_CONTROLLER = "SimtestSUT"
"""Name of the ego's controller; its property `simtest:sut=true` hands the ego to the SUT."""

CAR_LENGTH = 4.5
"""Bounding-box length of every car in the library, in metres."""

CAR_REAR_OVERHANG = 0.9
"""Distance from a car's reference point (rear-axle centre) back to its rear bumper, in metres."""


def car(name: str) -> xosc.Vehicle:
    """A mid-size passenger car whose reference point is the rear-axle centre."""
    bbox = xosc.BoundingBox(1.8, CAR_LENGTH, 1.5, CAR_LENGTH / 2 - CAR_REAR_OVERHANG, 0.0, 0.75)
    front = xosc.Axle(0.5, 0.65, 1.6, 2.8, 0.325)
    rear = xosc.Axle(0.0, 0.65, 1.6, 0.0, 0.325)
    return xosc.Vehicle(name, xosc.VehicleCategory.car, bbox, front, rear, 60.0, 8.0, 10.0, 1500.0)


def pedestrian(name: str) -> xosc.Pedestrian:
    """An adult pedestrian; the reference point is the centre of the footprint."""
    bbox = xosc.BoundingBox(0.6, 0.5, 1.8, 0.0, 0.0, 0.9)
    return xosc.Pedestrian(name, 80.0, xosc.PedestrianCategory.pedestrian, bbox, "adult")


def sut_controller() -> xosc.Controller:
    """The controller that marks the ego as the system under test."""
    props = xosc.Properties()
    props.add_property("simtest:sut", "true")
    return xosc.Controller(SUT_CONTROLLER, props)


def add_ego(entities: xosc.Entities) -> None:
    """Add the entity `Ego`, a car driven by the system under test."""
    entities.add_scenario_object("Ego", car("ego_car"), sut_controller())


def lane_position(road: int, lane: int, s: str | float) -> xosc.LanePosition:
    """A position on a lane centre line; `s` may be a `$Parameter` or `${expression}`."""
    return xosc.LanePosition(s, 0, lane, road)


def ahead_of_ego(gap: str) -> str:
    """Expression for the s of a car whose rear bumper is `gap` (a `$Parameter`) metres in
    front of the ego's front bumper, both in the same direction (reference points are rear
    axles, so the reference points are `gap` + one car length apart)."""
    return f"${{$EgoS + {gap} + {CAR_LENGTH:g}}}"


def teleport(position: xosc.LanePosition | xosc.WorldPosition) -> xosc.TeleportAction:
    """Place an entity."""
    return xosc.TeleportAction(position)


def speed_step(speed: str | float) -> xosc.AbsoluteSpeedAction:
    """Set a speed at once (used at init)."""
    dynamics = xosc.TransitionDynamics(xosc.DynamicsShapes.step, xosc.DynamicsDimension.time, 0)
    return xosc.AbsoluteSpeedAction(speed, dynamics)


def speed_rate(speed: str | float, rate: str | float) -> xosc.AbsoluteSpeedAction:
    """Change speed linearly at `rate` m/s^2 (a deceleration when the target is lower)."""
    dynamics = xosc.TransitionDynamics(
        xosc.DynamicsShapes.linear, xosc.DynamicsDimension.rate, rate
    )
    return xosc.AbsoluteSpeedAction(speed, dynamics)


def lane_change(lane: int, duration: str | float) -> xosc.AbsoluteLaneChangeAction:
    """A sinusoidal lane change to an absolute lane that takes `duration` seconds."""
    dynamics = xosc.TransitionDynamics(
        xosc.DynamicsShapes.sinusoidal, xosc.DynamicsDimension.time, duration
    )
    return xosc.AbsoluteLaneChangeAction(lane, dynamics)


def activate_sut() -> xosc.ActivateControllerAction:
    """Hand both driving domains of the ego to the system under test."""
    return xosc.ActivateControllerAction(lateral=True, longitudinal=True)


def route(name: str, waypoints: Sequence[tuple[int, int, float]]) -> xosc.AssignRouteAction:
    """Assign a route through (road, lane, s) waypoints, shortest path between them."""
    path = xosc.Route(name)
    for road, lane, s in waypoints:
        path.add_waypoint(lane_position(road, lane, s), xosc.RouteStrategy.shortest)
    return xosc.AssignRouteAction(path)


def walk_path(
    name: str, points: Sequence[tuple[float, float, float]]
) -> xosc.FollowTrajectoryAction:
    """Follow a polyline of world (x, y, heading) points at the entity's own speed."""
    positions = [xosc.WorldPosition(x, y, 0.0, h) for x, y, h in points]
    trajectory = xosc.Trajectory(name, False)
    trajectory.add_shape(xosc.Polyline([], positions))
    return xosc.FollowTrajectoryAction(trajectory, xosc.FollowingMode.position)


def init_vehicle(init: xosc.Init, entity: str, road: int, lane: int, s: str, speed: str) -> None:
    """Teleport a vehicle to a lane position and give it its initial speed."""
    init.add_init_action(entity, teleport(lane_position(road, lane, s)))
    init.add_init_action(entity, speed_step(speed))


def init_ego(init: xosc.Init, road: int, lane: int, s: str, speed: str) -> None:
    """Place the ego, set its initial speed and activate the system under test."""
    init_vehicle(init, "Ego", road, lane, s, speed)
    init.add_init_action("Ego", activate_sut())


def at_time(name: str, seconds: float) -> xosc.ValueTrigger:
    """True once simulation time exceeds `seconds`."""
    condition = xosc.SimulationTimeCondition(seconds, xosc.Rule.greaterThan)
    return xosc.ValueTrigger(name, 0, xosc.ConditionEdge.none, condition)


def when_close(
    name: str, trigger_entity: str, other: str, distance: str, rule: xosc.Rule
) -> xosc.EntityTrigger:
    """Compare the longitudinal free space between two entities' bounding boxes (bumper to
    bumper, 0 while they overlap lengthwise) with `distance`."""
    condition = xosc.RelativeDistanceCondition(
        distance,
        rule,
        xosc.RelativeDistanceType.longitudinal,
        other,
        freespace=True,
        coordinate_system=xosc.CoordinateSystem.entity,
    )
    return xosc.EntityTrigger(name, 0, xosc.ConditionEdge.none, condition, trigger_entity)


def after_travel(name: str, entity: str, distance: str) -> xosc.EntityTrigger:
    """True once `entity` has travelled `distance` metres."""
    condition = xosc.TraveledDistanceCondition(distance)
    return xosc.EntityTrigger(name, 0, xosc.ConditionEdge.none, condition, entity)


def after_event(name: str, event: str, delay: float = 0.0) -> xosc.ValueTrigger:
    """True once the event named `event` has completed (plus an optional delay)."""
    condition = xosc.StoryboardElementStateCondition(
        xosc.StoryboardElementType.event, event, xosc.StoryboardElementState.completeState
    )
    return xosc.ValueTrigger(name, delay, xosc.ConditionEdge.none, condition)


def event(name: str, actions: Sequence[xosc.PrivateAction], trigger: object) -> xosc.Event:
    """An event with private actions (started together) and one start trigger."""
    ev = xosc.Event(name, xosc.Priority.override)
    for index, action in enumerate(actions):
        ev.add_action(f"{name}Action{index + 1}" if len(actions) > 1 else f"{name}Action", action)
    ev.add_trigger(trigger)
    return ev


def story(name: str, actor: str, events: Sequence[xosc.Event]) -> xosc.Story:
    """A story with one act and one maneuver for `actor` holding `events` in order."""
    maneuver = xosc.Maneuver(f"{name}Maneuver")
    for ev in events:
        maneuver.add_event(ev)
    group = xosc.ManeuverGroup(f"{name}Group")
    group.add_actor(actor)
    group.add_maneuver(maneuver)
    act = xosc.Act(f"{name}Act", at_time(f"{name}ActStart", 0))
    act.add_maneuver_group(group)
    st = xosc.Story(f"{name}Story", xosc.ParameterDeclarations())
    st.add_act(act)
    return st
