"""Longitudinal actions that depend on another entity: LongitudinalDistanceAction and
SynchronizeAction.

Distance keeping without acceleration limits is rigid, as in the reference player: the actor is
put at the requested gap along its lane and takes the reference's speed. With limits it follows
the reference player's critically damped spring towards the gap, its acceleration clamped to the
limits and changed no faster than the allowed rates (jerk).

Synchronize re-plans every step: given the time the master needs to reach its target at its
current speed (from where it was at the start of the step, also when it moved first), the actor
picks the acceleration of a cubic position profile that arrives at its own target at that time
with the requested final speed (or, without one, the constant acceleration that arrives on
time). A steady-state part shortens the planned distance and time.
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim import measures, positions
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import LONGITUDINAL, Run
from simtest_operator.sim.world import World

SPRING = 0.4
"""Spring constant per m/s^2 of allowed acceleration (1/s^2 per m/s^2) of the gap model."""
GAP_TOLERANCE = 0.1
"""Gap error (m) below which a non-continuous distance action is done."""
MASTER_TOLERANCE = 1.0
"""Default distance (m) at which the synchronize master counts as arrived."""


class DistanceRun(Run):
    """A running LongitudinalDistanceAction."""

    __slots__ = ("_acceleration", "_action", "_ahead", "_ref")

    def __init__(
        self, world: World, actor: Actor, action: model.LongitudinalDistanceAction
    ) -> None:
        super().__init__(actor, LONGITUDINAL)
        self._action = action
        self._ref = world.actor(action.entity_ref)
        self._acceleration = 0.0
        displacement = action.displacement
        if displacement is model.LongitudinalDisplacement.ANY:
            # keep the side the actor is on now (esmini)
            self._ahead = self._gap(world) >= 0.0
        else:
            self._ahead = displacement is model.LongitudinalDisplacement.TRAILING
        self._apply(world, 0.0)

    def _gap(self, world: World) -> float:
        """Longitudinal distance to the reference, positive when it is ahead."""
        assert self.actor is not None
        action = self._action
        return measures.longitudinal(
            world,
            self.actor,
            self._ref,
            freespace=action.freespace,
            system=action.coordinate_system,
        )

    def _desired(self) -> float:
        action = self._action
        if action.distance is not None:
            return action.distance
        return (action.time_gap or 0.0) * max(self._ref.speed, 0.0)

    def _apply(self, world: World, dt: float) -> None:
        actor, action = self.actor, self._action
        assert actor is not None
        ahead = self._ahead
        gap = self._gap(world)
        if not ahead:
            gap = -gap
        error = gap - self._desired()
        limits = action.constraints
        if limits is None or (limits.max_acceleration is None and limits.max_deceleration is None):
            if actor.mode is Mode.ROAD and world.roads is not None and actor.road_id is not None:
                location = world.roads.advance(
                    actor.road_id,
                    actor.s,
                    actor.lane_id,
                    error * actor.direction * (1 if ahead else -1),
                )
                actor.road_id, actor.s, actor.lane_id = (
                    location.road_id,
                    location.s,
                    location.lane_id,
                )
                world.pose_on_road(actor)
            actor.speed = self._ref.speed
            self.finished = not action.continuous
            return
        # Critically damped spring towards the gap (esmini's model): stiffer when the actor
        # may brake harder, acceleration and jerk limited.
        max_acc = _limit(limits.max_acceleration)
        max_dec = _limit(limits.max_deceleration)
        excess = error if ahead else -error  # > 0: the reference is further ahead than wanted
        stiffness = (max_acc if excess < 0.0 else max_dec) * SPRING
        closing = actor.speed - self._ref.speed
        wanted = excess * stiffness - closing * 2.0 * math.sqrt(stiffness)
        wanted = min(max(wanted, -max_dec), max_acc)
        # The rates limit building up braking or acceleration, not releasing it (as esmini).
        if wanted < min(self._acceleration, 0.0):
            wanted = max(wanted, self._acceleration - _limit(limits.max_deceleration_rate) * dt)
        elif wanted > max(self._acceleration, 0.0):
            wanted = min(wanted, self._acceleration + _limit(limits.max_acceleration_rate) * dt)
        self._acceleration = wanted
        speed = actor.speed + wanted * dt
        if limits.max_speed is not None:
            speed = min(max(speed, -limits.max_speed), limits.max_speed)
        actor.speed = speed
        if not action.continuous and abs(error) < GAP_TOLERANCE:
            self.finished = True

    @property
    def _rigid(self) -> bool:
        limits = self._action.constraints
        return limits is None or (
            limits.max_acceleration is None and limits.max_deceleration is None
        )

    def step(self, world: World, dt: float) -> None:
        if self._rigid:
            assert self.actor is not None
            self.actor.speed = self._ref.speed  # placed exactly after everyone moved
            return
        self._apply(world, dt)

    def after_motion(self, world: World) -> None:
        if self._rigid and not self.finished:
            self._apply(world, 0.0)


def _limit(value: float | None) -> float:
    return value if value is not None and value > 0 else math.inf


class SynchronizeRun(Run):
    """A running SynchronizeAction."""

    __slots__ = ("_action", "_last_master", "_master", "_master_target", "_target")

    def __init__(self, world: World, actor: Actor, action: model.SynchronizeAction) -> None:
        super().__init__(actor, LONGITUDINAL)
        self._action = action
        self._master = world.actor(action.master_entity_ref)
        master_target = positions.resolve(world, action.target_position_master)
        target = positions.resolve(world, action.target_position)
        self._master_target = (master_target.x, master_target.y)
        self._target = (target.x, target.y)
        self._last_master = math.inf

    def _final_speed(self) -> float | None:
        final = self._action.final_speed
        if final is None:
            return None
        if isinstance(final, model.AbsoluteFinalSpeed):
            return final.value
        if final.value_type is model.SpeedTargetValueType.FACTOR:
            return self._master.speed * final.value
        return self._master.speed + final.value

    def _steady(self, final: float | None) -> tuple[float, float]:
        """(distance, time) reserved for the steady-state part at the final speed."""
        action_final = self._action.final_speed
        steady = action_final.steady_state if action_final is not None else None
        if steady is None or final is None:
            return 0.0, 0.0
        if steady.distance is not None:
            return steady.distance, steady.distance / final if final > 0 else 0.0
        time = steady.time or 0.0
        return final * time, time

    def step(self, world: World, dt: float) -> None:
        actor = self.actor
        assert actor is not None
        master = self._master
        seen = world.state(master.name)  # as it was at time t, also when it moved first
        dm = math.hypot(self._master_target[0] - seen.x, self._master_target[1] - seen.y)
        tolerance = self._action.target_tolerance_master or MASTER_TOLERANCE
        final = self._final_speed()
        if dm <= tolerance or (dm > self._last_master + 1e-6 and dm < 5.0 * tolerance):
            if final is not None:
                actor.speed = final
            self.finished = True
            return
        self._last_master = dm
        if master.speed <= 0.01:
            return
        remaining_time = dm / master.speed
        distance = math.hypot(self._target[0] - actor.x, self._target[1] - actor.y)
        steady_distance, steady_time = self._steady(final)
        distance -= steady_distance
        remaining_time -= steady_time
        if distance <= 0.0 or remaining_time <= dt:
            if final is not None:
                actor.speed = final
            return
        v = actor.speed
        if final is None:
            acceleration = 2.0 * (distance - v * remaining_time) / remaining_time**2
        else:
            acceleration = (
                6.0 * distance - 4.0 * v * remaining_time - 2.0 * final * remaining_time
            ) / (remaining_time**2)
        actor.speed = max(v + acceleration * dt, 0.0)
