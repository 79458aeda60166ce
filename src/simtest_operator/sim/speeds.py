"""Longitudinal speed actions: SpeedAction (all shapes and dimensions, absolute and relative,
continuous) and SpeedProfileAction.

A transition runs from the speed at the action start to the target with the dynamics shape over a
duration derived from the dimension: ``time`` is the duration, ``distance`` the distance covered
(duration = distance / mean speed), ``rate`` the peak acceleration (linear: duration =
|dv| / rate). A relative target is re-read each step, continuous or not (esmini's
LongSpeedAction::Step), so the transition bends towards a moving target (over a ``rate`` its
duration is re-derived from it: the speed ramps at the rate until it meets the target). A
``continuous`` one keeps tracking it after the transition and never ends by itself, never
changing speed faster than the vehicle's performance; one that is not continuous ends where
its transition meets the target.
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim import profiles
from simtest_operator.sim.actors import Actor
from simtest_operator.sim.runs import LONGITUDINAL, Run, peak_rate_factor, shape_fraction
from simtest_operator.sim.world import World

DEFAULT_ACCELERATION = 5.0
"""Acceleration (m/s^2) for speed-profile entries that give no time, without constraints or
vehicle performance."""

END_EPSILON = 1e-9
"""Seconds by which a transition's elapsed time may fall short of its duration and still end:
the sum of steps is a float (30 x 0.05 s < 1.5 s), and the reference player ends the action in
the step that reaches the duration (within its SMALL_NUMBER), not one step later."""


def target_speed(
    world: World, target: model.AbsoluteTargetSpeed | model.RelativeTargetSpeed
) -> float:
    if isinstance(target, model.AbsoluteTargetSpeed):
        return target.value
    ref = world.actor(target.entity_ref).speed
    if target.value_type is model.SpeedTargetValueType.FACTOR:
        return ref * target.value
    return ref + target.value


def transition_duration(
    dynamics: model.TransitionDynamics,
    v0: float,
    v1: float,
    performance: model.Performance | None = None,
) -> float:
    """Seconds a speed transition from v0 to v1 takes under ``dynamics``.

    Like the reference player, a transition never asks more than the vehicle's performance
    allows: its peak acceleration (deceleration) is capped at ``maxAcceleration``
    (``maxDeceleration``), which stretches the duration when needed. A time or distance of
    zero is a step whatever the shape, and a step ignores the performance (as there).
    """
    value = abs(dynamics.value)
    if dynamics.shape is model.DynamicsShape.STEP or (
        dynamics.dimension is not model.DynamicsDimension.RATE and value < 1e-9
    ):
        return 0.0
    if dynamics.dimension is model.DynamicsDimension.TIME:
        duration = value
    elif dynamics.dimension is model.DynamicsDimension.DISTANCE:
        mean = abs(v0 + v1) / 2.0
        duration = value / mean if mean > 1e-6 else 0.0
    else:  # the rate is the peak acceleration (the mean for linear), as esmini reads it
        duration = peak_rate_factor(dynamics.shape) * abs(v1 - v0) / value if value > 1e-9 else 0.0
    if performance is not None:
        limit = performance.max_acceleration if v1 > v0 else performance.max_deceleration
        if limit > 0:
            duration = max(duration, peak_rate_factor(dynamics.shape) * abs(v1 - v0) / limit)
    return duration


class SpeedRun(Run):
    """A running SpeedAction on one actor."""

    __slots__ = ("_action", "_duration", "_elapsed", "_progress", "_v0")

    def __init__(self, world: World, actor: Actor, action: model.SpeedAction) -> None:
        super().__init__(actor, LONGITUDINAL)
        self._action = action
        self._v0 = actor.speed
        self._elapsed = 0.0
        self._progress = 0.0
        """Fraction of a continuous transition done (its pace follows the moving target)."""
        target = target_speed(world, action.target)
        self._duration = transition_duration(
            action.dynamics, self._v0, target, actor.obj.performance
        )
        if self._duration <= 0.0:
            actor.speed = target
            self.finished = not self._continuous

    @property
    def _continuous(self) -> bool:
        target = self._action.target
        return isinstance(target, model.RelativeTargetSpeed) and target.continuous

    def step(self, world: World, dt: float) -> None:
        assert self.actor is not None
        target = target_speed(world, self._action.target)
        if self._continuous:
            self._track(target, dt)
            return
        if self._action.dynamics.dimension is model.DynamicsDimension.RATE:
            # a moving target moves the end of a ramp at the given rate
            self._duration = transition_duration(
                self._action.dynamics, self._v0, target, self.actor.obj.performance
            )
        self._elapsed += dt
        if self._duration <= 0.0 or self._elapsed >= self._duration - END_EPSILON:
            self.actor.speed = target
            self.finished = not self._continuous
            return
        fraction = shape_fraction(self._action.dynamics.shape, self._elapsed / self._duration)
        self.actor.speed = self._v0 + (target - self._v0) * fraction

    def _track(self, target: float, dt: float) -> None:
        """One step towards a continuous (moving) target, as the reference player does: the
        transition's pace is re-derived from the current target each step (a target that ran
        away stretches it to the vehicle's performance), and no step changes the speed by more
        than the performance allows, during the transition or while tracking after it (a
        follower cannot copy a harder braking than its own maxDeceleration), whatever the shape:
        a ``step`` jumps to the target only when the action starts (esmini's Start), then
        tracks within the performance like any other (its Step)."""
        actor = self.actor
        assert actor is not None
        dynamics = self._action.dynamics
        performance = actor.obj.performance
        if self._progress < 1.0:
            duration = transition_duration(dynamics, self._v0, target, performance)
            self._progress = min(self._progress + dt / duration, 1.0) if duration > 0 else 1.0
        wanted = self._v0 + (target - self._v0) * shape_fraction(dynamics.shape, self._progress)
        if self._progress >= 1.0:
            wanted = target
        if performance is not None:
            if performance.max_deceleration > 0:
                wanted = max(wanted, actor.speed - performance.max_deceleration * dt)
            if performance.max_acceleration > 0:
                wanted = min(wanted, actor.speed + performance.max_acceleration * dt)
        actor.speed = wanted


class SpeedProfileRun(Run):
    """A running SpeedProfileAction: the entries planned into speed segments at the start
    (:mod:`~simtest_operator.sim.profiles`), then the speed read off them each step."""

    __slots__ = ("_segments",)

    def __init__(self, world: World, actor: Actor, action: model.SpeedProfileAction) -> None:
        super().__init__(actor, LONGITUDINAL)
        offset = world.actor(action.entity_ref).speed if action.entity_ref is not None else 0.0
        self._segments = profiles.plan(
            [(entry.time, entry.speed + offset) for entry in action.entries],
            start=world.time,
            speed=actor.speed,
            acceleration=actor.acceleration,
            follow=action.following_mode is model.FollowingMode.FOLLOW,
            limits=_limits(action.constraints, actor.obj.performance),
        )

    def step(self, world: World, dt: float) -> None:
        assert self.actor is not None
        time = world.time + dt
        last = self._segments[-1]
        if time >= last.t - profiles.EPSILON:
            self.actor.speed = last.v
            self.finished = True
            return
        self.actor.speed = profiles.speed_at(self._segments, time)


def _limits(
    constraints: model.DynamicConstraints | None, performance: model.Performance | None
) -> profiles.Limits:
    """Speed-profile limits: the action's constraints, else the vehicle's performance."""

    def pick(mine: float | None, theirs: float | None, default: float) -> float:
        value = mine if mine is not None else theirs
        return value if value is not None and value > 0 else default

    given = constraints or model.DynamicConstraints()
    return profiles.Limits(
        acceleration=pick(
            given.max_acceleration,
            performance.max_acceleration if performance else None,
            DEFAULT_ACCELERATION,
        ),
        deceleration=pick(
            given.max_deceleration,
            performance.max_deceleration if performance else None,
            DEFAULT_ACCELERATION,
        ),
        acceleration_rate=pick(
            given.max_acceleration_rate,
            performance.max_acceleration_rate if performance else None,
            math.inf,
        ),
        deceleration_rate=pick(
            given.max_deceleration_rate,
            performance.max_deceleration_rate if performance else None,
            math.inf,
        ),
    )
