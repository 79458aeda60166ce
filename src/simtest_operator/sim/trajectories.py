"""FollowTrajectoryAction: move an actor along a sampled path.

With a Timing (and vertex times) the path prescribes position over time, so the action owns both
control domains and derives the speed; without one the actor keeps the speed its longitudinal
actions give it and the path only steers (lateral domain). When the path ends the actor rejoins
the lane under it (or continues straight in open space).

As in the reference player (esmini): the trajectory clock runs ``scale`` times as fast as the
simulation and the position is read at clock + ``offset``; a relative clock starts at the path
time of the ``initialDistanceOffset`` point, and the action ends when the clock (without the
offset) reaches the last vertex time. An entity faces against the path when the first vertex
gives a heading against it, or (untimed, no heading given) when it starts while reversing; it
then moves along the path by minus its speed, so a negative speed backs it towards the start
when it faces along the path.
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim import placements, positions, shapes
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.runs import BOTH, LATERAL, Run
from simtest_operator.sim.world import World
from simtest_operator.snapshots import JumpCause

_ON_PATH = 1e-3
"""Metres an entity may be off its trajectory's start and still be on it (no jump to declare);
radians its heading may differ from the start's."""


class PathRun(Run):
    """A running FollowTrajectoryAction."""

    __slots__ = ("_against", "_clock0", "_distance", "_path", "_t0", "_timing")

    def __init__(self, world: World, actor: Actor, action: model.FollowTrajectoryAction) -> None:
        trajectory = action.trajectory
        if isinstance(trajectory, model.Unsupported):
            raise placements.unsupported(trajectory)
        start = placements.Placement(x=actor.x, y=actor.y, z=actor.z, heading=actor.heading)
        self._path = shapes.sample(trajectory.shape, lambda p: positions.resolve(world, p), start)
        self._timing = action.timing if self._path.times is not None else None
        if self._timing is not None and action.following_mode is model.FollowingMode.FOLLOW:
            self._path = self._path.following(actor.speed)
        super().__init__(actor, BOTH if self._timing is not None else LATERAL)
        self._t0 = world.time
        self._distance = min(max(action.initial_distance_offset or 0.0, 0.0), self._path.length)
        self._clock0 = self._path.time_at_distance(self._distance)
        along = self._path.at_distance(self._distance)[2]
        given = _given_heading(world, trajectory.shape, self._distance)
        if given is not None and not _ignores_heading(actor):
            self._against = math.cos(given - along) < 0.0
        else:
            # Untimed and started while reversing: the entity backs along the path, facing
            # against it (a parking car backs out along a trajectory drawn the way it moves).
            self._against = self._timing is None and actor.speed < 0.0
        self._place(actor, self._distance)
        turned = abs(math.remainder(actor.heading - start.heading, 2.0 * math.pi))
        if math.hypot(actor.x - start.x, actor.y - start.y) > _ON_PATH or turned > _ON_PATH:
            # put elsewhere, or turned at once to the start's heading (its box swings round)
            world.declare(actor, JumpCause.TRAJECTORY_START)
        if self._timing is not None and self._against:
            actor.speed = -abs(actor.speed)

    def _place(self, actor: Actor, distance: float) -> None:
        actor.x, actor.y, actor.heading = self._path.at_distance(distance)
        if self._against:
            actor.heading = math.remainder(actor.heading + math.pi, 2.0 * math.pi)
        actor.mode = Mode.PATH
        actor.placed = True

    def step(self, world: World, dt: float) -> None:
        actor = self.actor
        assert actor is not None
        timing = self._timing
        path = self._path
        rest = 0.0
        if timing is not None:
            assert path.times is not None
            now = world.time + dt
            if timing.domain is model.ReferenceContext.RELATIVE:
                clock = self._clock0 + (now - self._t0) * timing.scale
            else:
                clock = now * timing.scale
            at = clock + timing.offset
            target = path.distance_at_time(at)
            done = clock >= path.times[-1] - 1e-9
            sign = -1.0 if self._against else 1.0
            if done:
                # Leave the path at the speed of its last piece, carrying on the time left over.
                speed = path.speed_at_time(min(at, path.times[-1])) * timing.scale
                actor.speed = sign * speed
                scale = timing.scale if timing.scale > 0 else 1.0
                rest = (clock - path.times[-1]) / scale * speed
            else:
                actor.speed = sign * (target - self._distance) / dt if dt > 0 else 0.0
        else:
            delta = (-actor.speed if self._against else actor.speed) * dt
            target = self._distance + delta
            if delta > 0.0 and target >= path.length:
                done, rest = True, target - path.length
            elif delta < 0.0 and target <= 0.0:
                done, rest = True, -target
            else:
                done = False
        before, self._distance = self._distance, min(max(target, 0.0), path.length)
        self._place(actor, self._distance)
        if dt > 0:
            # along the path (the piece this step drove), whatever heading it gives the entity
            rate = (self._distance - before) / dt
            direction = path.direction_at((self._distance + before) / 2.0)
            actor.set_travel((rate * math.cos(direction), rate * math.sin(direction)))
        if done:
            self.finished = True
            world.attach(actor)
            # On along its heading, forwards or backwards as its speed says.
            _carry_on(world, actor, math.copysign(rest, actor.speed) if actor.speed else 0.0)

    def cancel(self) -> None:
        was_running = not self.finished
        super().cancel()
        if was_running and self.actor is not None and self.actor.mode is Mode.PATH:
            self.actor.mode = Mode.FREE


def _ignores_heading(actor: Actor) -> bool:
    """esmini's entity property ``ignoreHeadingForTrajMotion``: the direction of motion along
    a path follows the speed alone, whatever heading the path gives."""
    return any(
        p.name == "ignoreHeadingForTrajMotion" and p.value.strip().lower() in ("true", "1")
        for p in actor.obj.properties
    )


def _given_heading(world: World, shape: model.Shape, distance: float) -> float | None:
    """The heading a polyline whose first vertex gives one explicitly (a world position's
    ``h``, an absolute orientation) prescribes at ``distance``: that of the vertex starting the
    segment there, or the segment's direction where the vertex gives none. None when the first
    vertex gives no heading: the entity then faces along the path."""
    if not isinstance(shape, model.Polyline) or not _explicit(shape.vertices[0].position):
        return None
    placed = [positions.resolve(world, v.position) for v in shape.vertices]
    total, index = 0.0, 0
    for k in range(1, len(placed)):
        step = math.hypot(placed[k].x - placed[k - 1].x, placed[k].y - placed[k - 1].y)
        total += step
        if step > 1e-6 and total <= distance + 1e-9:
            index = k  # the last vertex at or before the distance
    if _explicit(shape.vertices[index].position):
        return placed[index].heading
    return None


def _explicit(position: model.Position) -> bool:
    if isinstance(position, model.WorldPosition):
        return position.h is not None
    orientation = getattr(position, "orientation", None)
    return isinstance(orientation, model.Orientation) and orientation.type in (
        None,
        model.ReferenceContext.ABSOLUTE,
    )


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
