"""Condition evaluation: the raw truth of every supported OpenSCENARIO condition.

Entity conditions are evaluated per triggering entity and combined with the ``any``/``all`` rule;
the satisfied entities are returned too (``selectTriggeringEntities``). Edges and delays are the
trigger layer's business (:mod:`~simtest_operator.sim.triggers`). An unsupported condition raises
the error that turns the run ``Invalid`` when it is first evaluated, i.e. when execution reaches it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from simtest_operator import geometry
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim import (
    angles,
    clearance,
    measures,
    placements,
    positions,
    time_of_day,
)
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.triggers import Truth
from simtest_operator.sim.world import World
from simtest_operator.snapshots import EntityKind

StateQuery = Callable[[model.StoryboardElementType, str, model.StoryboardElementState], bool]

_EPSILON = 1e-9
SCENARIO_RUNNER_STILL = 0.1
"""m/s up to which an entity stands still under ScenarioRunner's rules. ScenarioRunner's
StandStill restarts its clock above 0.001 m/s, but CARLA's physics brings a braking vehicle to
rest while the stand-in's car-following model only approaches zero; 0.1 m/s is ScenarioRunner's
own standstill in its RunningStopTest."""
REACH_HEADING_TOLERANCE = 0.05
"""Radians within which an entity must face a ReachPositionCondition's position that is written
with an ``Orientation`` (esmini's ``TrigByReachPosition`` angular tolerance)."""
_OBJECT_TYPES = {
    "vehicle": EntityKind.VEHICLE,
    "pedestrian": EntityKind.PEDESTRIAN,
    "miscellaneous": EntityKind.MISC_OBJECT,
}


def compare(value: float, rule: model.Rule, reference: float) -> bool:
    """``value <rule> reference`` with a tiny tolerance for the equality rules."""
    if rule is model.Rule.GREATER_THAN:
        return value > reference
    if rule is model.Rule.LESS_THAN:
        return value < reference
    if rule is model.Rule.GREATER_OR_EQUAL:
        return value >= reference - _EPSILON
    if rule is model.Rule.LESS_OR_EQUAL:
        return value <= reference + _EPSILON
    equal = abs(value - reference) <= _EPSILON * max(1.0, abs(reference))
    return equal if rule is model.Rule.EQUAL_TO else not equal


def _compare_typed(current: model.ParameterValue, rule: model.Rule, text: str) -> bool:
    if isinstance(current, bool):
        wanted = text.strip().lower() in ("true", "1")
        return compare(float(current), rule, float(wanted))
    if isinstance(current, int | float):
        try:
            return compare(float(current), rule, float(text))
        except ValueError:
            raise ScenarioError(f"cannot compare number {current} with {text!r}") from None
    order = {
        model.Rule.EQUAL_TO: current == text,
        model.Rule.NOT_EQUAL_TO: current != text,
        model.Rule.GREATER_THAN: current > text,
        model.Rule.LESS_THAN: current < text,
        model.Rule.GREATER_OR_EQUAL: current >= text,
        model.Rule.LESS_OR_EQUAL: current <= text,
    }
    return order[rule]


class Conditions:
    """Evaluates condition bodies against the world and the storyboard state."""

    __slots__ = (
        "_driven_since",
        "_scenario_runner",
        "_signed_longitudinal",
        "_state_query",
        "_still_since",
        "_world",
    )

    def __init__(
        self,
        world: World,
        state_query: StateQuery,
        *,
        signed_longitudinal: bool = False,
        scenario_runner: bool = False,
    ) -> None:
        self._world = world
        self._state_query = state_query
        self._signed_longitudinal = signed_longitudinal
        self._scenario_runner = scenario_runner
        self._still_since: dict[tuple[int, str], tuple[float, float]] = {}
        """ScenarioRunner's StandStill clocks: (condition, entity) -> (slow since, last seen)."""
        self._driven_since: dict[tuple[int, str], tuple[float, float]] = {}
        """ScenarioRunner's DriveDistance: (condition, entity) -> (odometer at start, last seen)."""

    def __call__(self, body: model.ByEntity | model.ByValue) -> Truth:
        if isinstance(body, model.ByValue):
            return self._by_value(body.condition), frozenset()
        satisfied = frozenset(
            name for name in body.triggering_entities if self._entity(name, body.condition)
        )
        if body.rule is model.TriggeringEntitiesRule.ALL:
            return len(satisfied) == len(set(body.triggering_entities)), satisfied
        return bool(satisfied), satisfied

    # --- value conditions ---------------------------------------------------------------------

    def _by_value(self, condition: model.ValueCondition) -> bool:
        world = self._world
        if isinstance(condition, model.SimulationTimeCondition):
            return compare(world.time, condition.rule, condition.value)
        if isinstance(condition, model.StoryboardElementStateCondition):
            return self._state_query(condition.element_type, condition.element_ref, condition.state)
        if isinstance(condition, model.ParameterCondition):
            if condition.parameter_ref not in world.parameters:
                raise ScenarioError(
                    f"parameter {condition.parameter_ref!r} is not declared",
                    element="ParameterCondition",
                    line=condition.line,
                )
            current = world.parameters[condition.parameter_ref]
            return _compare_typed(current, condition.rule, condition.value)
        if isinstance(condition, model.VariableCondition):
            if condition.variable_ref not in world.variables:
                raise ScenarioError(
                    f"variable {condition.variable_ref!r} is not declared",
                    element="VariableCondition",
                    line=condition.line,
                )
            current = world.variables[condition.variable_ref]
            return _compare_typed(current, condition.rule, condition.value)
        if isinstance(condition, model.TrafficSignalCondition):
            return world.signals.get(condition.name) == condition.state
        if isinstance(condition, model.TrafficSignalControllerCondition):
            return world.signal_controllers.phase(condition.controller_ref) == condition.phase
        if isinstance(condition, model.TimeOfDayCondition):
            past = time_of_day.seconds_past(condition.date_time, world)
            return past is not None and compare(past, condition.rule, 0.0)
        if isinstance(condition, model.UserDefinedValueCondition):
            return False  # no source of user values in the stand-in; listed as ignored
        raise placements.unsupported(condition)

    # --- entity conditions --------------------------------------------------------------------

    def _entity(self, name: str, condition: model.EntityCondition) -> bool:
        world = self._world
        actor = world.actor(name)
        if isinstance(condition, model.Unsupported):
            raise placements.unsupported(condition)
        if not actor.placed:
            return False
        if isinstance(condition, model.SpeedCondition):
            value = actor.lateral_speed if _lateral(condition.direction) else actor.speed
            return compare(value, condition.rule, condition.value)
        if isinstance(condition, model.AccelerationCondition):
            return compare(
                _acceleration(actor, condition.direction), condition.rule, condition.value
            )
        if isinstance(condition, model.StandStillCondition):
            if self._scenario_runner:
                return self._slow_for(condition, actor) >= condition.duration - _EPSILON
            return actor.standstill_time >= condition.duration - _EPSILON and actor.speed == 0.0
        if isinstance(condition, model.TraveledDistanceCondition):
            if self._scenario_runner:
                return self._driven_for(condition, actor) > condition.value
            return actor.odometer >= condition.value
        if isinstance(condition, model.EndOfRoadCondition):
            return actor.stuck and actor.end_of_road_time >= condition.duration - _EPSILON
        if isinstance(condition, model.OffRoadCondition):
            return actor.offroad_time > 0.0 and actor.offroad_time >= condition.duration - _EPSILON
        if isinstance(condition, model.RelativeSpeedCondition):
            other = world.actor(condition.entity_ref)
            relative = _relative_speed(actor, other, condition.direction)
            return compare(relative, condition.rule, condition.value)
        if isinstance(condition, model.CollisionCondition):
            return self._collision(actor, condition)
        if isinstance(condition, model.ReachPositionCondition):
            target = positions.resolve(world, condition.position)
            if not math.hypot(target.x - actor.x, target.y - actor.y) <= condition.tolerance:
                return False
            # a position written with an Orientation is reached only facing that way (esmini)
            oriented = getattr(condition.position, "orientation", None) is not None
            return not oriented or angles.within(
                actor.heading, target.heading, REACH_HEADING_TOLERANCE
            )
        if isinstance(condition, model.DistanceCondition):
            target = positions.resolve(world, condition.position)
            if self._scenario_runner and condition.along_route and world.roads is not None:
                # InTriggerDistanceToOSCPosition with alongRoute: its route planner's way from
                # the actor's lane waypoint to the position's (straight where none leads there)
                start = world.roads.to_road(actor.x, actor.y, actor.road_id)
                goal = world.roads.to_road(target.x, target.y)
                way = None
                if start is not None and goal is not None:
                    way = measures.along_lanes(world.roads, start, goal)
                if way is not None:
                    return compare(way, condition.rule, condition.value)
            across = _across_road(world, actor, target, condition)
            if across is not None:
                return compare(across, condition.rule, condition.value)
            point = measures.point_state(target.x, target.y, target.heading)
            value = measures.to_point(
                world.state(name),
                point,
                kind=condition.relative_distance_type,
                freespace=condition.freespace,
            )
            return compare(value, condition.rule, condition.value)
        if isinstance(condition, model.RelativeDistanceCondition):
            other = world.actor(condition.entity_ref)
            value = measures.between(
                world,
                actor,
                other,
                kind=condition.relative_distance_type,
                freespace=condition.freespace,
                system=condition.coordinate_system,
            )
            longitudinal = (
                condition.relative_distance_type is model.RelativeDistanceType.LONGITUDINAL
            )
            if longitudinal and self._signed_longitudinal:
                # OpenSCENARIO 1.0 files, as esmini reads them: a reference behind is at a negative
                # distance, so "greater than 10 m" waits until it is 10 m ahead (1.1+: absolute).
                return compare(value, condition.rule, condition.value)
            return compare(abs(value), condition.rule, condition.value)
        if isinstance(condition, model.TimeHeadwayCondition):
            if self._scenario_runner:
                arrival = self._arrival(actor, condition.entity_ref, condition)
                return compare(arrival, condition.rule, condition.value)
            return compare(self._headway(actor, condition), condition.rule, condition.value)
        if isinstance(condition, model.RelativeClearanceCondition):
            return clearance.is_clear(self._world, actor, condition)
        if isinstance(condition, model.TimeToCollisionCondition):
            if self._scenario_runner and condition.entity_ref is not None:
                arrival = self._arrival(actor, condition.entity_ref, condition)
                return compare(arrival, condition.rule, condition.value)
            return compare(self._ttc(actor, condition), condition.rule, condition.value)
        if isinstance(condition, model.AngleCondition | model.RelativeAngleCondition):
            return self._angle(actor, condition)
        raise ScenarioError(f"condition {type(condition).__name__} is not supported")

    def _driven_for(self, condition: model.TraveledDistanceCondition, actor: Actor) -> float:
        """Metres ``actor`` drove since the condition started watching (ScenarioRunner's
        DriveDistance counts from its first check, or again after a pause)."""
        now = self._world.time
        key = (id(condition), actor.name)
        start, seen = self._driven_since.get(key, (actor.odometer, now))
        if now - seen > 1.5 * self._world.dt:
            start = actor.odometer
        self._driven_since[key] = (start, now)
        return actor.odometer - start

    def _slow_for(self, condition: model.StandStillCondition, actor: Actor) -> float:
        """Seconds ``actor`` has been at most :data:`SCENARIO_RUNNER_STILL` fast, counted from
        when the condition started watching (ScenarioRunner's StandStill starts its clock when
        the condition is first checked, or again after a pause, and restarts it on motion)."""
        now = self._world.time
        key = (id(condition), actor.name)
        since, seen = self._still_since.get(key, (now, now))
        if now - seen > 1.5 * self._world.dt or actor.speed > SCENARIO_RUNNER_STILL:
            since = now
        self._still_since[key] = (since, now)
        return now - since

    def _angle(
        self, actor: Actor, condition: model.AngleCondition | model.RelativeAngleCondition
    ) -> bool:
        world = self._world
        kind, system = condition.angle_type, condition.coordinate_system
        value = angles.angle(world, actor, kind, system)
        if isinstance(condition, model.RelativeAngleCondition):
            other = world.actor(condition.entity_ref)
            reference = angles.angle(world, other, kind, system) if other.placed else None
            value = None if value is None or reference is None else value - reference
        return value is not None and angles.within(value, condition.angle, condition.tolerance)

    def _collision(self, actor: Actor, condition: model.CollisionCondition) -> bool:
        world = self._world
        me = world.state(actor.name)
        if condition.entity_ref is not None:
            other = world.actor(condition.entity_ref)
            return other.placed and geometry.boxes_overlap(me, world.state(other.name))
        kind = _OBJECT_TYPES.get(condition.by_type or "")
        for other in world.actors.values():
            if other is actor or not other.placed or (kind is not None and other.kind is not kind):
                continue
            if geometry.boxes_overlap(me, world.state(other.name)):
                return True
        return False

    def _arrival(
        self,
        actor: Actor,
        entity_ref: str,
        condition: model.TimeHeadwayCondition | model.TimeToCollisionCondition,
    ) -> float:
        """ScenarioRunner's time to arrival at another entity, which it reads for both
        TimeHeadway and TimeToCollision to an entity (``InTimeToArrivalToVehicle``): the distance
        between the two actors' locations (box centres in CARLA; minus both half lengths with
        ``freespace``) over the difference of their speeds, infinite unless the entity is the
        faster -- whoever is ahead, whatever the directions. The distance is straight, or with
        ``alongRoute="true"`` the way along the lanes (:func:`measures.along_lanes`; straight
        when no lane leads there)."""
        world = self._world
        other = world.actor(entity_ref)
        me, them = world.state(actor.name), world.state(other.name)
        (ax, ay, _), (bx, by, _) = me.box_center(), them.box_center()
        distance = math.hypot(bx - ax, by - ay)
        roads = world.roads
        if condition.along_route and roads is not None:
            start = roads.to_road(ax, ay, actor.road_id, heading=me.heading)
            goal = roads.to_road(bx, by, other.road_id, heading=them.heading)
            if start is not None and goal is not None:
                way = measures.along_lanes(roads, start, goal)
                distance = distance if way is None else way
        if condition.freespace:
            distance -= (me.box.length + them.box.length) / 2.0
        closing = actor.speed - other.speed
        return distance / closing if closing > 0.0 else math.inf

    def _headway(self, actor: Actor, condition: model.TimeHeadwayCondition) -> float:
        other = self._world.actor(condition.entity_ref)
        kind, system = _distance_kind(condition)
        distance = measures.between(
            self._world,
            actor,
            other,
            kind=kind,
            freespace=condition.freespace,
            system=system,
        )
        if kind is model.RelativeDistanceType.EUCLIDEAN:
            ahead = measures.longitudinal(
                self._world, actor, other, freespace=False, system=model.CoordinateSystem.ENTITY
            )
            distance = distance if ahead > 0.0 else -1.0  # alongside or behind: no headway
        if distance < 0.0 or actor.speed <= 0.0:
            # No headway when the reference is behind or the entity stands: then the condition
            # holds for no rule (esmini on light_state and velodrome behaves so).
            return math.nan
        return distance / actor.speed

    def _ttc(self, actor: Actor, condition: model.TimeToCollisionCondition) -> float:
        world = self._world
        kind, system = _distance_kind(condition)
        me = world.state(actor.name)
        if condition.entity_ref is not None:
            other_actor = world.actor(condition.entity_ref)
            distance = measures.between(
                world,
                actor,
                other_actor,
                kind=kind,
                freespace=condition.freespace,
                system=system,
            )
            other = world.state(other_actor.name)
        elif condition.position is not None:
            target = positions.resolve(world, condition.position)
            other = measures.point_state(target.x, target.y, target.heading)
            distance = measures.to_point(me, other, kind=kind, freespace=condition.freespace)
        else:
            raise ScenarioError(
                "TimeToCollisionCondition needs an entity or a position",
                element="TimeToCollisionCondition",
                line=condition.line,
            )
        if kind is not model.RelativeDistanceType.EUCLIDEAN and distance < 0:
            return math.inf
        closing = measures.closing_speed(me, other, kind)
        if closing <= 0.0:
            return math.inf
        return abs(distance) / closing


def _acceleration(actor: Actor, direction: model.DirectionalDimension | None) -> float:
    """The acceleration an AccelerationCondition reads, as esmini measures it: without a
    direction the magnitude of the world-frame acceleration (so braking at 5 m/s^2 reads 5, and
    a curve at constant speed its centripetal part), else its component along (longitudinal)
    or to the left of (lateral) the heading; the vertical one is 0 (flat motion)."""
    ax, ay = actor.acceleration_xy
    if direction is None:
        return math.hypot(ax, ay)
    cos_h, sin_h = math.cos(actor.heading), math.sin(actor.heading)
    if direction is model.DirectionalDimension.LONGITUDINAL:
        return ax * cos_h + ay * sin_h
    if direction is model.DirectionalDimension.LATERAL:
        return -ax * sin_h + ay * cos_h
    return 0.0


def _relative_speed(
    actor: Actor, reference: Actor, direction: model.DirectionalDimension | None
) -> float:
    """A RelativeSpeedCondition's value, as esmini measures it: without a direction the
    difference of the speeds; with ``longitudinal``/``lateral`` the difference of the two
    world-frame velocities along/left of the *reference* entity's heading (a car crossing at
    right angles has no longitudinal speed relative to it); vertical 0 (flat motion)."""
    if direction is None:
        return actor.speed - reference.speed
    cos_h, sin_h = math.cos(reference.heading), math.sin(reference.heading)
    dvx = actor.velocity_xy[0] - reference.velocity_xy[0]
    dvy = actor.velocity_xy[1] - reference.velocity_xy[1]
    if direction is model.DirectionalDimension.LONGITUDINAL:
        return dvx * cos_h + dvy * sin_h
    if direction is model.DirectionalDimension.LATERAL:
        return -dvx * sin_h + dvy * cos_h
    return 0.0


def _across_road(
    world: World, actor: Actor, target: placements.Placement, condition: model.DistanceCondition
) -> float | None:
    """A lateral distance in road or lane coordinates to a position on the actor's road: the
    difference of their t (esmini), wherever along the road the position is; None otherwise."""
    lane = target.lane
    if (
        condition.relative_distance_type is not model.RelativeDistanceType.LATERAL
        or condition.coordinate_system
        not in (model.CoordinateSystem.ROAD, model.CoordinateSystem.LANE)
        or condition.freespace
        or lane is None
        or actor.mode is not Mode.ROAD
        or actor.road_id != lane.road_id
    ):
        return None
    there = world.lane_t(lane.road_id, lane.s, lane.lane_id) + lane.offset
    here = world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset
    return abs(there - here)


def _lateral(direction: model.DirectionalDimension | None) -> bool:
    return direction is model.DirectionalDimension.LATERAL


def _distance_kind(
    condition: model.TimeHeadwayCondition | model.TimeToCollisionCondition,
) -> tuple[model.RelativeDistanceType, model.CoordinateSystem]:
    """What distance a headway/TTC condition means: its relative distance type in its coordinate
    system (default: longitudinal in the entity frame). The deprecated ``alongRoute="false"``
    means the straight (Euclidean) distance, a headway existing only while the reference is
    ahead: against esmini that reproduces both vehicles side by side on an oval (velodrome: no
    headway) and the chord across a circle (light_state: the lane change starts when the
    straight distance, not the distance along the road, drops under the threshold)."""
    if condition.along_route is False:
        return model.RelativeDistanceType.EUCLIDEAN, model.CoordinateSystem.ENTITY
    return condition.relative_distance_type, condition.coordinate_system
