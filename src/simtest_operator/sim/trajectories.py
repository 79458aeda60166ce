"""FollowTrajectoryAction: move an actor along a sampled path.

With a Timing (and vertex times) the path prescribes position over time, so the action owns both
control domains and derives the speed; without one the actor keeps the speed its longitudinal
actions give it and the path only steers (lateral domain). When the path ends the actor rejoins
the lane under it (or continues straight in open space).
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim import placements, positions, shapes
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import BOTH, LATERAL, Run
from simtest_operator.sim.world import World


class PathRun(Run):
    """A running FollowTrajectoryAction."""

    __slots__ = ("_distance", "_path", "_reverse", "_t0", "_timing")

    def __init__(self, world: World, actor: Actor, action: model.FollowTrajectoryAction) -> None:
        trajectory = action.trajectory
        if isinstance(trajectory, model.Unsupported):
            raise placements.unsupported(trajectory)
        start = placements.Placement(x=actor.x, y=actor.y, z=actor.z, heading=actor.heading)
        self._path = shapes.sample(trajectory.shape, lambda p: positions.resolve(world, p), start)
        self._timing = action.timing if self._path.times is not None else None
        if self._timing is not None and action.following_mode is model.FollowingMode.FOLLOW:
            self._path = self._path.following()
        super().__init__(actor, BOTH if self._timing is not None else LATERAL)
        self._t0 = world.time
        # Untimed and started while reversing: the entity backs along the path, facing against
        # it (esmini's rule; a parking car backs out along a trajectory drawn the way it moves).
        self._reverse = self._timing is None and actor.speed < 0.0
        self._distance = min(max(action.initial_distance_offset or 0.0, 0.0), self._path.length)
        self._place(actor, self._distance)

    def _place(self, actor: Actor, distance: float) -> None:
        actor.x, actor.y, actor.heading = self._path.at_distance(distance)
        if self._reverse:
            actor.heading = math.remainder(actor.heading + math.pi, 2.0 * math.pi)
        actor.mode = Mode.PATH
        actor.placed = True

    def step(self, world: World, dt: float) -> None:
        actor = self.actor
        assert actor is not None
        timing = self._timing
        path = self._path
        if timing is not None:
            now = world.time + dt
            base = self._t0 if timing.domain is model.ReferenceContext.RELATIVE else 0.0
            scale = timing.scale if timing.scale > 0 else 1.0
            path_time = (now - base - timing.offset) / scale
            assert path.times is not None
            done = path_time >= path.times[-1]
            if done:
                # Leave the path at the speed of its last piece, carrying the time left over.
                actor.speed = path.speed_at_time(path.times[-1]) / scale
                overshoot = (path_time - path.times[-1]) * scale * actor.speed
                target = path.length + overshoot
            else:
                target = path.distance_at_time(path_time)
                actor.speed = (target - self._distance) / dt if dt > 0 else 0.0
        else:
            target = self._distance + (-actor.speed if self._reverse else actor.speed) * dt
            done = target >= path.length
        self._distance = min(max(target, 0.0), path.length)
        self._place(actor, self._distance)
        if done:
            self.finished = True
            world.attach(actor)
            rest = target - path.length
            _carry_on(world, actor, -rest if self._reverse else rest)

    def cancel(self) -> None:
        was_running = not self.finished
        super().cancel()
        if was_running and self.actor is not None and self.actor.mode is Mode.PATH:
            self.actor.mode = Mode.FREE


def _carry_on(world: World, actor: Actor, distance: float) -> None:
    """Move an actor that just left its path by the rest of this step's ``distance`` (along
    its heading; negative: backwards)."""
    if abs(distance) <= 1e-9:
        return
    roads = world.roads
    if actor.mode is Mode.ROAD and roads is not None and actor.road_id is not None:
        location = roads.advance(actor.road_id, actor.s, actor.lane_id, distance * actor.direction)
        actor.road_id, actor.s, actor.lane_id = location.road_id, location.s, location.lane_id
        world.pose_on_road(actor)
    elif actor.mode is Mode.FREE:
        actor.x += distance * math.cos(actor.heading)
        actor.y += distance * math.sin(actor.heading)
