"""SynchronizeAction as the reference player (esmini) runs it: the actor reaches its target when
the master reaches the master's target.

Every step both distances are measured (the master as it was at the start of the step, also
when it moved first): along the road (difference of s) when the entity drives a road and its
target lies on that road, else in a straight line (always for an entity following a
trajectory). The action is done when the actor is within ``targetTolerance`` of its target, the
master within ``targetToleranceMaster`` of its own (1 m each by default), either distance grows
(the target was passed) or the master arrives within this step; the actor then takes the final
speed, if one is given, and keeps it (along the trajectory it follows, if any).

Otherwise both distances are shortened by their tolerance (the plan reaches the edge of the
tolerance circle) and the master's time left is its distance over its speed along the road's
reference line (its velocity projected on the road's s-axis, forwards or reversing). Without a
final speed the actor accelerates constantly to arrive on time. With one it follows esmini's speed
profile of constant accelerations: straight to the final speed when that arrives on time (linear),
else first towards an apex speed and then straight down (convex) or up (concave) to the final
speed, or, when even the apex would be negative, braking to a stop, waiting and starting again. A
steady state (``TargetDistanceSteadyState``/``TargetTimeSteadyState``, a time taken as distance at
the final speed at the start) reserves the last stretch to be covered at the final speed: the plan
aims at its start, and once there (or once time runs short) the actor keeps the final speed. As in
esmini, the actor's own speed in the apex calculation is its velocity along its road's s-axis (near
zero for a pedestrian crossing the road), its speed as given elsewhere.
"""

from __future__ import annotations

import enum
import math

from simtest_operator.openscenario import model
from simtest_operator.sim import positions
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import LONGITUDINAL, Run
from simtest_operator.sim.world import World

DEFAULT_TOLERANCE = 0.0
"""Tolerance (m) of ``targetTolerance`` and ``targetToleranceMaster`` when not given."""
SMALL = 1e-10
LARGE = 1e10
"""esmini's stand-ins for zero and infinity (a master standing still has LARGE time left)."""
MAX_DECELERATION = 8.0
"""Braking (m/s^2) when a stop is needed and there is no room to brake gently (esmini)."""
ON_LINE = 0.1
"""Speed difference (m/s) under which the actor counts as on the straight profile line."""


class _Phase(enum.Enum):
    NONE = "none"
    APEX = "apex"  # first part of a two-part profile, towards the apex speed
    LINEAR = "linear"  # straight to the final speed
    STOPPING = "stopping"  # braking to a stop at the latest
    STOPPED = "stopped"  # standing, waiting for the time to start again
    WAITING = "waiting"  # stopped at once, waiting for the master to move
    STEADY = "steady"  # at the final speed for the steady-state stretch


class SynchronizeRun(Run):
    """A running SynchronizeAction."""

    __slots__ = (
        "_action",
        "_convex",
        "_last",
        "_last_master",
        "_master",
        "_master_target",
        "_phase",
        "_steady",
        "_target",
        "_tolerance",
        "_tolerance_master",
    )

    def __init__(self, world: World, actor: Actor, action: model.SynchronizeAction) -> None:
        super().__init__(actor, LONGITUDINAL)
        self._action = action
        self._master = world.actor(action.master_entity_ref)
        master_target = positions.resolve(world, action.target_position_master)
        target = positions.resolve(world, action.target_position)
        self._master_target = _Target(world, master_target.x, master_target.y)
        self._target = _Target(world, target.x, target.y)
        self._tolerance = _tolerance(action.target_tolerance)
        self._tolerance_master = _tolerance(action.target_tolerance_master)
        self._last = math.inf
        self._last_master = math.inf
        self._phase = _Phase.NONE
        self._convex = False
        self._steady = self._steady_distance()

    def _final_speed(self) -> float | None:
        final = self._action.final_speed
        if final is None:
            return None
        if isinstance(final, model.AbsoluteFinalSpeed):
            return final.value
        if final.value_type is model.SpeedTargetValueType.FACTOR:
            return self._master.speed * final.value
        return self._master.speed + final.value

    def _steady_distance(self) -> float | None:
        """Length of the steady-state stretch (a time is taken at the final speed now)."""
        final_speed = self._action.final_speed
        steady = final_speed.steady_state if final_speed is not None else None
        if steady is None:
            return None
        if steady.distance is not None:
            return steady.distance
        return (steady.time or 0.0) * (self._final_speed() or 0.0)

    def step(self, world: World, dt: float) -> None:
        actor = self.actor
        assert actor is not None
        seen = world.state(self._master.name)  # as it was at time t, also when it moved first
        master_dist = self._master_target.distance(world, self._master, seen.x, seen.y)
        dist = self._target.distance(world, actor, actor.x, actor.y)
        done = (
            dist < self._tolerance + SMALL
            or master_dist < self._tolerance_master + SMALL
            or dist > self._last
            or master_dist > self._last_master
        )
        self._last, self._last_master = dist, master_dist
        # plan to reach the edge of the tolerance circles
        dist = max(dist - self._tolerance, SMALL)
        master_dist = max(master_dist - self._tolerance_master, SMALL)
        time_left = LARGE
        # how fast the master gets along the road, whichever way it faces: a master reversing
        # towards its target (Euro NCAP CPRA_Cm) arrives as surely as one driving there (esmini
        # starts the pedestrian for it); one moving away ends the action on the growing distance
        master_speed = abs(_speed_along_road(world, seen.x, seen.y, seen.heading, seen.speed))
        if master_speed > SMALL:
            time_left = master_dist / master_speed
            done = done or time_left < dt
        final = self._final_speed()
        if done:
            if final is not None:
                actor.speed = final
            self.finished = True
            return
        if final is None:
            # constant acceleration arriving on time, whatever the speed there
            actor.speed += 2.0 * (dist / time_left - actor.speed) / time_left * dt
            return
        if self._steady is not None and self._phase is not _Phase.STEADY:
            steady_time = self._steady / final if final != 0.0 else LARGE
            if dist - self._steady < SMALL or time_left - steady_time < SMALL:
                self._phase = _Phase.STEADY
            else:
                dist -= self._steady
                time_left -= steady_time
        acceleration = self._profile(world, actor, dist, time_left, final, dt)
        if acceleration is not None:
            actor.speed += acceleration * dt

    def _profile(
        self, world: World, actor: Actor, dist: float, time_left: float, final: float, dt: float
    ) -> float | None:
        """Acceleration of the speed profile this step; None when the speed was set directly."""
        phase = self._phase
        if phase is _Phase.STEADY:
            actor.speed = final
            return None
        if phase is _Phase.WAITING:
            if time_left >= LARGE:
                return None
            phase = self._phase = _Phase.NONE
        if phase is _Phase.STOPPING:
            actor.speed -= MAX_DECELERATION * dt
            if actor.speed < 0.0:
                actor.speed = 0.0
                self._phase = _Phase.WAITING
            return None
        if phase is _Phase.STOPPED:
            if final > 0.0 and time_left < 2.0 * dist / final:
                phase = self._phase = _Phase.LINEAR
            else:
                actor.speed = 0.0
                return None
        if phase is _Phase.LINEAR:
            if time_left > LARGE - 1.0:
                actor.speed = 0.0  # the master stands still
            else:
                actor.speed = max(0.0, _linear_start_speed(max(0.0, final), time_left, dist))
            return None
        on_line = time_left < LARGE and (
            abs(actor.speed - (2.0 * dist / time_left - final)) < ON_LINE
        )
        if phase is _Phase.APEX and on_line:
            self._phase = _Phase.LINEAR  # on the straight line to the final speed
            return None
        if phase is _Phase.NONE:
            self._phase = _Phase.APEX
            self._convex = (final + actor.speed) / 2.0 < dist / time_left
        v0 = math.copysign(
            abs(_speed_along_road(world, actor.x, actor.y, actor.heading, actor.speed)),
            actor.speed if actor.speed != 0.0 else 1.0,
        )
        apex, acceleration = _apex(dist, time_left, v0, final)
        if (acceleration < 0.0) if self._convex else (acceleration > 0.0):
            self._phase = _Phase.LINEAR  # past the apex
            return 0.0
        if apex < 0.0:
            # even the apex would be negative: brake to a stop, wait, start again
            stop_time = 2.0 * v0 * dist / (v0 * v0 + final * final)
            acceleration = -v0 / stop_time if abs(stop_time) > SMALL else 0.0
            if stop_time * v0 / 2.0 > dist / 2.0:
                acceleration = -MAX_DECELERATION
                self._phase = _Phase.STOPPING
            if v0 + acceleration * dt < 0.0:
                actor.speed = 0.0
                self._phase = _Phase.STOPPED
                return None
        return acceleration


def _tolerance(value: float | None) -> float:
    return DEFAULT_TOLERANCE if value is None else value


def _linear_start_speed(final: float, time: float, dist: float) -> float:
    """Speed from which constant acceleration covers ``dist`` in ``time`` ending at ``final``."""
    if time < 0.001 or dist < 0.001:
        return 0.0
    return 2.0 * dist / time - final


def _apex(dist: float, time: float, v0: float, v1: float) -> tuple[float, float]:
    """Apex speed and first acceleration of the two-part profile from ``v0`` to ``v1`` that
    covers ``dist`` in ``time`` (two constant accelerations of equal size, opposite sign)."""
    if abs(v1 - v0) < SMALL:
        apex = (dist - time / 2.0 * v0) / (time / 2.0)
        return apex, (apex - v0) / (time / 2.0)
    root = math.sqrt(2.0) * math.sqrt(
        max(0.0, 2.0 * dist * dist - 2.0 * (v1 + v0) * time * dist + (v1 * v1 + v0 * v0) * time**2)
    )
    for sign in (1.0, -1.0):
        at = -(sign * root + 2.0 * dist - 2.0 * v1 * time) / (2.0 * (v1 - v0))
        if 0.0 < at < time:
            apex = (2.0 * dist - sign * root) / (2.0 * time)
            return apex, (apex - v0) / at
    return 0.0, 0.0


class _Target:
    """A target point and where it lies on the road network (fixed when the action starts)."""

    __slots__ = ("_road", "x", "y")

    def __init__(self, world: World, x: float, y: float) -> None:
        self.x, self.y = x, y
        self._road = world.road_coord(x, y)

    def distance(self, world: World, entity: Actor, x: float, y: float) -> float:
        """From an entity at (x, y): along the road when it drives one this target lies on,
        else in a straight line (esmini's road-path distance and its world-distance fallback;
        an entity following a trajectory measures in a straight line)."""
        there = self._road
        if entity.mode is Mode.ROAD and there is not None:
            here = world.road_coord(x, y)
            if here is not None and here.road_id == there.road_id:
                return abs(there.s - here.s)
        return math.hypot(self.x - x, self.y - y)


def _speed_along_road(world: World, x: float, y: float, heading: float, speed: float) -> float:
    """``speed`` projected on the reference line of the road under (x, y), sign kept (esmini
    measures how fast an entity progresses along the road)."""
    coord = world.road_coord(x, y)
    if coord is None:
        return speed
    along = abs(speed * math.cos(heading - coord.heading_of_road))
    return math.copysign(along, speed) if speed != 0.0 else 0.0
