"""FollowTrajectoryAction: move an actor along a sampled path.

With a Timing (and vertex times) the path prescribes position over time, so the action owns both
control domains and derives the speed; without one the actor keeps the speed its longitudinal
actions give it and the path only steers (lateral domain). When the path ends the actor rejoins
the lane under it (or continues straight in open space).
"""

from __future__ import annotations

from simtest_operator.openscenario import model
from simtest_operator.sim import paths, positions
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import BOTH, LATERAL, Run
from simtest_operator.sim.world import World


class PathRun(Run):
    """A running FollowTrajectoryAction."""

    __slots__ = ("_distance", "_path", "_t0", "_timing")

    def __init__(self, world: World, actor: Actor, action: model.FollowTrajectoryAction) -> None:
        trajectory = action.trajectory
        if isinstance(trajectory, model.Unsupported):
            raise positions.unsupported(trajectory)
        start = positions.Placement(x=actor.x, y=actor.y, z=actor.z, heading=actor.heading)
        self._path = paths.sample(trajectory.shape, lambda p: positions.resolve(world, p), start)
        self._timing = action.timing if self._path.times is not None else None
        super().__init__(actor, BOTH if self._timing is not None else LATERAL)
        self._t0 = world.time
        self._distance = min(max(action.initial_distance_offset or 0.0, 0.0), self._path.length)
        self._place(actor, self._distance)

    def _place(self, actor: Actor, distance: float) -> None:
        actor.x, actor.y, actor.heading = self._path.at_distance(distance)
        actor.mode = Mode.PATH
        actor.placed = True

    def step(self, world: World, dt: float) -> None:
        actor = self.actor
        assert actor is not None
        timing = self._timing
        if timing is not None:
            now = world.time + dt
            base = self._t0 if timing.domain is model.ReferenceContext.RELATIVE else 0.0
            scale = timing.scale if timing.scale > 0 else 1.0
            path_time = (now - base - timing.offset) / scale
            target = self._path.distance_at_time(path_time)
            actor.speed = (target - self._distance) / dt if dt > 0 else 0.0
            assert self._path.times is not None
            done = path_time >= self._path.times[-1]
        else:
            target = self._distance + actor.speed * dt
            done = target >= self._path.length
        self._distance = min(max(target, 0.0), self._path.length)
        self._place(actor, self._distance)
        if done:
            self.finished = True
            world.attach(actor)

    def cancel(self) -> None:
        was_running = not self.finished
        super().cancel()
        if was_running and self.actor is not None and self.actor.mode is Mode.PATH:
            self.actor.mode = Mode.FREE
