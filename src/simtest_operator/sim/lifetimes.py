"""How long actions last under ScenarioRunner's rules (its atomics' ``update``, not the standard).

ScenarioRunner turns an action into an atomic behaviour that hands a target to the actor's
controller and then only watches for its own end:

- a SpeedAction (``ChangeActorTargetSpeed``) ends once more than its dynamics ``value`` seconds
  have passed, or, with ``dynamicsDimension="distance"``, once the actor is more than ``value``
  metres (straight line) from where it started -- whatever the shape: a ``step`` to a new speed
  keeps its event running for that time or distance, and a ``rate`` is read as seconds. The
  controller keeps the target after the action ended, so the speed change itself
  (:class:`SpeedHold` ``inner``) goes on to its end;
- AcquirePositionAction and AssignRouteAction (``ChangeActorWaypoints``) end when the controller
  reached the last waypoint (:class:`RouteHold`) -- never for an ``external_control`` actor,
  whose controller reports no goal (the route still guides the SUT at junctions);
- a lateral action aimed at an ``external_control`` actor reaches that controller, which runs
  nothing: it moves no one and ends only when the actor happens to meet its goal
  (:class:`IgnoredLateral`).

A newer action of the same kind on the same actor ends the older one (its goal was replaced).
The runs here that steer nothing claim no control domain; the dispatcher watches them.
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim import placements
from simtest_operator.sim.actors import Actor
from simtest_operator.sim.runs import NO_DOMAINS, Run
from simtest_operator.sim.world import World

REACH = 4.0
"""m: a waypoint is reached within this distance (ScenarioRunner's simple vehicle control)."""
PASS_ASIDE = 8.0
"""m: a waypoint passed at most this far to the side counts as reached (the stand-in keeps its
lane where ScenarioRunner's controller steers to the point)."""
OFFSET_REACHED = 0.1
"""m: ScenarioRunner's ``ChangeActorLaneOffset`` threshold for a reached offset."""
_EPSILON = 1e-9


class SpeedHold(Run):
    """A SpeedAction as ScenarioRunner's ``ChangeActorTargetSpeed`` lets it last."""

    __slots__ = ("_continuous", "_inner", "_limit", "_metres", "_start", "_start_time")

    def __init__(
        self, world: World, actor: Actor, action: model.SpeedAction, inner: Run | None
    ) -> None:
        super().__init__(actor, inner.domains if inner is not None else NO_DOMAINS)
        self._inner = inner
        dynamics = action.dynamics
        self._metres = dynamics.dimension is model.DynamicsDimension.DISTANCE
        self._limit = abs(dynamics.value)
        self._start = (actor.x, actor.y)
        self._start_time = world.time
        target = action.target
        self._continuous = isinstance(target, model.RelativeTargetSpeed) and target.continuous

    @property
    def successor(self) -> Run | None:
        """The speed change still under way after the action ended (None when it is done)."""
        inner = self._inner
        return inner if inner is not None and not inner.finished else None

    def cancel(self) -> None:
        super().cancel()
        if self._inner is not None:
            self._inner.cancel()

    def step(self, world: World, dt: float) -> None:
        if self._inner is not None and not self._inner.finished:
            self._inner.step(world, dt)

    def after_motion(self, world: World) -> None:
        if self.finished or self._continuous:
            return
        assert self.actor is not None
        if self._metres:
            done = math.dist((self.actor.x, self.actor.y), self._start) > self._limit
        else:
            done = world.time + world.dt - self._start_time > self._limit + _EPSILON
        self.finished = done


class RouteHold(Run):
    """A routing action as ScenarioRunner's ``ChangeActorWaypoints`` lets it last: until the
    actor reached the last waypoint (within :data:`REACH`, or passed it within
    :data:`PASS_ASIDE` to the side). ``goal`` None: never (an ``external_control`` actor's
    controller never reports a reached goal), unless replaced or stopped."""

    __slots__ = ("_goal",)

    def __init__(self, actor: Actor, goal: placements.Placement | None) -> None:
        super().__init__(actor)
        self._goal = goal

    def step(self, world: World, dt: float) -> None:
        """Nothing to steer: the route is the actor's; see :meth:`after_motion`."""

    def after_motion(self, world: World) -> None:
        actor = self.actor
        assert actor is not None
        if self._goal is None:
            return
        dx, dy = self._goal.x - actor.x, self._goal.y - actor.y
        ahead = dx * math.cos(actor.heading) + dy * math.sin(actor.heading)
        aside = -dx * math.sin(actor.heading) + dy * math.cos(actor.heading)
        self.finished = math.hypot(dx, dy) <= REACH or (ahead < 0.0 and abs(aside) <= PASS_ASIDE)


class IgnoredLateral(Run):
    """A lateral action on an externally controlled actor: it moves no one; a non-continuous
    absolute LaneOffsetAction ends when the actor is within :data:`OFFSET_REACHED` of the
    offset, every other one when it is stopped or replaced."""

    __slots__ = ("_offset",)

    def __init__(self, actor: Actor, action: model.LaneOffsetAction | model.LaneChangeAction):
        super().__init__(actor)
        target = action.target if isinstance(action, model.LaneOffsetAction) else None
        self._offset = (
            target.value
            if isinstance(target, model.AbsoluteTargetLaneOffset)
            and isinstance(action, model.LaneOffsetAction)
            and not action.continuous
            else None
        )

    def step(self, world: World, dt: float) -> None:
        """Nothing to steer."""

    def after_motion(self, world: World) -> None:
        assert self.actor is not None
        if self._offset is not None:
            self.finished = abs(self.actor.offset - self._offset) < OFFSET_REACHED
