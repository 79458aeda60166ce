"""Lateral actions: LaneChangeAction and LaneOffsetAction.

Both move an actor's offset from its lane centre with a dynamics shape. A lane change keeps the
actor's logical lane until it completes and measures the target lane centre afresh every step, so
it follows lanes whose widths change and lanes that continue on the next road; at the end the
actor belongs to the target lane. Durations come from the dynamics (``time``; lateral ``rate``
in m/s) or, for lane offsets, from the maximum lateral acceleration; a lane change shaped over a
``distance`` progresses with the distance driven along the road (as esmini), and no lane change
progresses while its actor stands.
"""

from __future__ import annotations

import math

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim import placements
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import LATERAL, Run, peak_rate_factor, shape_fraction, shape_slope
from simtest_operator.sim.world import World
from simtest_operator.snapshots import JumpCause

DEFAULT_MAX_LATERAL_ACCELERATION = 0.5
"""m/s^2 for LaneOffsetActions without ``maxLateralAcc``."""
SPRING = 0.4
"""Spring stiffness (1/s^2) per m/s^2 of allowed lateral acceleration (lateral distance)."""
LATERAL_TOLERANCE = 0.01
"""Metres from the requested lateral distance at which a non-continuous action is done."""
_STEP_ACCELERATION = 10.0
"""m/s^2 (about 1 g): a lateral speed an action without acceleration limit changes faster than
this within a step has stepped (a declared discontinuity: the heading turns with it)."""


def lanes_between(start: int, target: int) -> int:
    """Signed number of lanes from ``start`` to ``target``, not counting the centre lane."""
    delta = target - start
    if start < 0 < target:
        delta -= 1
    elif target < 0 < start:
        delta += 1
    return delta


def _lane_centre_t(world: World, road_id: str, s: float, lane_id: int) -> float:
    """t of a lane's centre; for a lane beyond the road's outermost one, the road's outer edge
    on that side (see :func:`placements.lane_beyond`)."""
    beyond = placements.lane_beyond(world, road_id, s, lane_id) if world.roads else None
    return world.lane_t(road_id, s, lane_id) if beyond is None else beyond[1]


def _require_lane(actor: Actor, element: str) -> str:
    if actor.mode is not Mode.ROAD or actor.road_id is None:
        raise ScenarioError(f"{element} needs {actor.name!r} on a lane", element=element)
    return actor.road_id


class LaneChangeRun(Run):
    """A running LaneChangeAction."""

    __slots__ = (
        "_by_distance",
        "_delta",
        "_direction",
        "_duration",
        "_elapsed",
        "_offset0",
        "_road_id",
        "_shape",
        "_target_offset",
    )

    def __init__(self, world: World, actor: Actor, action: model.LaneChangeAction) -> None:
        super().__init__(actor, LATERAL)
        road_id = _require_lane(actor, "LaneChangeAction")
        target = action.target
        if isinstance(target, model.AbsoluteTargetLane):
            target_lane = target.lane_id
        else:
            # Positive values count lanes to the reference entity's left: towards +t when it
            # faces along the road, towards -t when it faces against it (as esmini).
            ref = world.actor(target.entity_ref)
            facing = placements.road_coordinates(world, ref)[3]
            target_lane = placements.add_lanes(world.current_lane(ref), target.value * facing)
        self._delta = lanes_between(actor.lane_id, target_lane)
        self._target_offset = action.target_lane_offset or 0.0
        self._offset0 = actor.offset
        self._direction = actor.direction
        """The actor's direction on its road the lane delta and offsets are counted in."""
        self._road_id = road_id
        """The road the change was last aimed on (its target lane's centre is road-specific)."""
        self._shape = action.dynamics.shape
        self._elapsed = 0.0
        """Progress: seconds, or for the distance dimension metres driven along the road."""
        dynamics = action.dynamics
        self._by_distance = dynamics.dimension is model.DynamicsDimension.DISTANCE
        lateral = abs(self._relative_target(world, road_id) - self._offset0)
        if dynamics.shape is model.DynamicsShape.STEP:
            self._duration = 0.0
        elif dynamics.dimension is model.DynamicsDimension.TIME or self._by_distance:
            self._duration = abs(dynamics.value)
        else:
            # the rate is the peak lateral speed (as esmini reads it; the mean for linear)
            rate = abs(dynamics.value)
            self._duration = peak_rate_factor(dynamics.shape) * lateral / rate if rate else 0.0
        if self._duration <= 0.0:
            self._finish(world)
            if lateral > 0.0:
                world.declare(actor, JumpCause.LATERAL_STEP)

    def _target_lane(self) -> int:
        assert self.actor is not None
        return placements.add_lanes(self.actor.lane_id, self._delta)

    def _relative_target(self, world: World, road_id: str) -> float:
        assert self.actor is not None
        s = self.actor.s
        target_t = _lane_centre_t(world, road_id, s, self._target_lane()) + self._target_offset
        return target_t - world.lane_t(road_id, s, self.actor.lane_id)

    def _finish(self, world: World) -> None:
        actor = self.actor
        assert actor is not None
        target = self._target_lane()
        road_id = actor.road_id
        beyond = None
        if road_id is not None and world.roads is not None:
            beyond = placements.lane_beyond(world, road_id, actor.s, target)
        if road_id is None or beyond is None:
            actor.lane_id = target
            actor.offset = self._target_offset
        else:
            # A lane beyond the road: the actor ends on the road's edge (the target's centre as
            # esmini computes it), kept on the outermost lane it has, as esmini re-attaches it.
            outermost, edge = beyond
            actor.lane_id = outermost
            actor.offset = edge - world.lane_t(road_id, actor.s, outermost) + self._target_offset
        self.finished = True

    def step(self, world: World, dt: float) -> None:
        actor = self.actor
        assert actor is not None
        if actor.mode is not Mode.ROAD or actor.road_id is None:
            self.cancel()
            return
        if abs(actor.speed) < 1e-9:
            return  # esmini: no lateral motion while standing, the change waits
        if actor.direction != self._direction:
            # It drove onto a road linked end to end: lane ids and t run the other way, the
            # change goes on to the same side of the vehicle.
            self._direction = actor.direction
            self._delta, self._offset0 = -self._delta, -self._offset0
            self._target_offset = -self._target_offset
        self._hand_over(world)
        target = self._relative_target(world, actor.road_id)
        if actor.road_id != self._road_id:
            self._reaim(target)
        # esmini takes the lateral part of the step's travel at the rate the shape has at the
        # start of the step (so the longitudinal motion is not symmetric about the middle)
        slope = shape_slope(self._shape, self._elapsed / self._duration)
        rate = (target - self._offset0) / self._duration * slope
        if self._by_distance:
            # a distance-shaped change progresses by the distance gained along the road: this
            # step's travel less its lateral part (whatever the speed does meanwhile)
            along = abs(actor.speed) * dt / math.hypot(1.0, rate)
            self._elapsed += along
            actor.steer_rate = rate * along / dt if dt > 0.0 else 0.0
        else:
            self._elapsed += dt
            actor.steer_rate = rate
        if self._elapsed >= self._duration:
            self._finish(world)
            return
        fraction = shape_fraction(self._shape, self._elapsed / self._duration)
        actor.offset = self._offset0 + (target - self._offset0) * fraction
        actor.lane_changing = True

    def _hand_over(self, world: World) -> None:
        """Once the actor is nearer the next lane's centre (towards the target) than its own,
        that lane holds it: where its road ends it follows that lane's successor, the road it
        is on (esmini keeps a changing car on its target lane), not its old lane's connector."""
        actor = self.actor
        assert actor is not None and actor.road_id is not None
        if self._delta == 0 or world.roads is None:
            return
        road_id, s = actor.road_id, actor.s
        step = 1 if self._delta > 0 else -1
        following = placements.add_lanes(actor.lane_id, step)
        if following not in world.roads.lane_ids(road_id, s):
            return
        if world.roads.lane_width(road_id, s, following) <= 0.0:
            return
        here = world.lane_t(road_id, s, actor.lane_id)
        there = world.lane_t(road_id, s, following)
        if abs(here + actor.offset - there) >= abs(actor.offset):
            return
        shift = here - there
        actor.lane_id = following
        actor.offset += shift
        self._offset0 += shift
        self._delta -= step

    def _reaim(self, target: float) -> None:
        """On a new road the target lane's centre can lie elsewhere relative to the actor's lane
        (a one-lane junction connector has no lane to change into: its centre line is the
        target): the change goes on from where the actor is, on the same schedule, instead of
        jumping to where the new target puts the current fraction."""
        actor = self.actor
        assert actor is not None and actor.road_id is not None
        self._road_id = actor.road_id
        done = shape_fraction(self._shape, self._elapsed / self._duration)
        if done < 1.0:
            self._offset0 = (actor.offset - target * done) / (1.0 - done)


class LaneOffsetRun(Run):
    """A running LaneOffsetAction; it ends when its transition is done, ``continuous`` or not
    (esmini 3.6 does, so an endTransition of it can trigger what follows)."""

    __slots__ = ("_action", "_duration", "_elapsed", "_offset0")

    def __init__(self, world: World, actor: Actor, action: model.LaneOffsetAction) -> None:
        super().__init__(actor, LATERAL)
        _require_lane(actor, "LaneOffsetAction")
        self._action = action
        self._offset0 = actor.offset
        self._elapsed = 0.0
        distance = abs(self._target(world) - self._offset0)
        acc = action.max_lateral_acc or DEFAULT_MAX_LATERAL_ACCELERATION
        if action.shape is model.DynamicsShape.STEP or distance < 1e-9:
            self._duration = 0.0
        elif action.shape is model.DynamicsShape.SINUSOIDAL:
            self._duration = math.pi * math.sqrt(distance / (2.0 * acc))
        else:
            # Cubic: the peak acceleration 6d/T^2 at the ends. A linear shape has no finite
            # peak; the reference player sizes it like the cubic one.
            self._duration = math.sqrt(6.0 * distance / acc)
        if self._duration <= 0.0:
            actor.offset = self._target(world)
            self.finished = True
            if distance > 0.0:
                world.declare(actor, JumpCause.LATERAL_STEP)

    def _target(self, world: World) -> float:
        """The offset from the actor's lane centre to aim at. A relative target is ``value``
        to the reference entity's left (in the direction it faces) of where that entity is
        across the road, whichever lane it is in (as esmini)."""
        target = self._action.target
        if isinstance(target, model.AbsoluteTargetLaneOffset):
            return target.value
        actor = self.actor
        assert actor is not None and actor.road_id is not None
        _, _, ref_t, facing = placements.road_coordinates(world, world.actor(target.entity_ref))
        return ref_t + target.value * facing - world.lane_t(actor.road_id, actor.s, actor.lane_id)

    def step(self, world: World, dt: float) -> None:
        # The offset of a step is the transition's value at the step's start (the reference
        # player evaluates before it advances the transition), so it ends one step after
        # its duration.
        actor = self.actor
        assert actor is not None
        elapsed = self._elapsed
        self._elapsed += dt
        target = self._target(world)
        if elapsed >= self._duration - 1e-9:
            actor.offset = target
            self.finished = True
            return
        fraction = shape_fraction(self._action.shape, elapsed / self._duration)
        actor.offset = self._offset0 + (target - self._offset0) * fraction


class LateralDistanceRun(Run):
    """A running LateralDistanceAction: hold a lateral distance to another entity.

    Measured across the road (difference of t, free space subtracting the half widths); the
    requested side is kept (``any``: the side the actor is on now). Without limits the actor
    snaps to the distance (a declared jump when it starts; while it runs, the snaps follow the
    reference's motion). With them it moves like the reference player: a critically damped
    spring (stiffness 0.4 per m/s^2 of allowed acceleration) with the acceleration and the
    lateral speed clamped; a non-continuous action ends within 1 cm of the distance.
    """

    __slots__ = ("_action", "_lateral_speed", "_ref", "_side")

    def __init__(self, world: World, actor: Actor, action: model.LateralDistanceAction) -> None:
        super().__init__(actor, LATERAL)
        _require_lane(actor, "LateralDistanceAction")
        self._action = action
        self._ref = world.actor(action.entity_ref)
        self._lateral_speed = 0.0
        limits = action.constraints
        if limits is not None and limits.max_acceleration is not None:
            # The spring starts from the actor's own motion across the road (as esmini): an
            # entity placed at an angle drives on along its heading, then turns to the
            # distance; from here its heading follows the motion.
            across = actor.direction * actor.speed * math.sin(actor.heading_offset)
            self._lateral_speed = self._clamp(across + actor.lateral_speed, actor.speed)
            actor.heading_offset = 0.0
        if action.displacement is model.LateralDisplacement.LEFT:
            self._side = 1.0
        elif action.displacement is model.LateralDisplacement.RIGHT:
            self._side = -1.0
        else:
            here = self._t(world, actor) - self._t(world, self._ref)
            self._side = 1.0 if here * actor.direction >= 0 else -1.0
        offset = actor.offset
        self.step(world, 0.0)
        if abs(actor.offset - offset) > 1e-9:
            # Without limits the actor snaps to the distance at once (as esmini).
            world.declare(actor, JumpCause.LATERAL_STEP)

    @staticmethod
    def _clamp(speed: float, limit: float) -> float:
        """``speed`` within +-``limit``."""
        return max(-abs(limit), min(abs(limit), speed))

    @staticmethod
    def _t(world: World, actor: Actor) -> float:
        if actor.road_id is None:
            return 0.0
        return world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset

    def step(self, world: World, dt: float) -> None:
        actor, action = self.actor, self._action
        assert actor is not None
        if actor.mode is not Mode.ROAD or actor.road_id is None:
            self.cancel()
            return
        distance = action.distance or 0.0
        if action.freespace:
            distance += (actor.box.width + self._ref.box.width) / 2.0
        target_t = self._t(world, self._ref) + self._side * actor.direction * distance
        target = target_t - world.lane_t(actor.road_id, actor.s, actor.lane_id)
        limits = action.constraints
        rigid = limits is None or (limits.max_acceleration is None and limits.max_speed is None)
        if rigid:
            actor.offset = target
        elif dt > 0.0:
            assert limits is not None
            error = target - actor.offset
            stepped = False
            max_speed = limits.max_speed if limits.max_speed is not None else math.inf
            if limits.max_acceleration is None:
                speed = error / dt  # no acceleration limit: as fast as the speed limit allows
                stepped = True
            else:
                stiffness = SPRING * limits.max_acceleration
                wanted = error * stiffness - self._lateral_speed * 2.0 * math.sqrt(stiffness)
                wanted = max(-limits.max_acceleration, min(limits.max_acceleration, wanted))
                speed = self._lateral_speed + wanted * dt
            speed = self._clamp(speed, min(max_speed, abs(actor.speed)))
            if stepped and abs(speed - self._lateral_speed) > _STEP_ACCELERATION * dt:
                # no acceleration limit: the lateral speed steps and the heading with it (esmini
                # turns 53 degrees in one step), a discontinuity the scenario commands
                world.declare(actor, JumpCause.LATERAL_STEP)
            self._lateral_speed = speed
            actor.offset += speed * dt
            actor.lane_changing = True  # steering sideways takes from the distance driven
        if not action.continuous and abs(actor.offset - target) < LATERAL_TOLERANCE:
            self.finished = True
