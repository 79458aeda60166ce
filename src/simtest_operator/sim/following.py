"""LongitudinalDistanceAction: keep a distance or time gap to another entity.

Distance keeping without acceleration limits is rigid, as in the reference player: the actor is
put at the requested gap along its lane and takes the reference's speed. With limits it follows
the reference player's critically damped spring towards the gap, its acceleration clamped to the
limits and changed no faster than the allowed rates (jerk).
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim import measures
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import LONGITUDINAL, Run
from simtest_operator.sim.world import World

SPRING = 0.4
"""Spring constant per m/s^2 of allowed acceleration (1/s^2 per m/s^2) of the gap model."""
GAP_TOLERANCE = 0.1
"""Gap error (m) below which a non-continuous distance action is done."""


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
