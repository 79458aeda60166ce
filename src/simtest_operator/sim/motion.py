"""Motion: advance one actor's pose by one step from its speed and lane offset.

ROAD actors move ``speed * dt`` along their lane through the lane graph (preferring their route's
roads at forks); a change of the lateral position this step tilts the heading by the angle of the
resulting velocity, as a real lane change does. FREE actors move straight along their heading.
PATH actors were placed by their trajectory run already. Odometer and the timers that
StandStill/OffRoad/EndOfRoad conditions read are updated here too.
"""

from __future__ import annotations

import math

from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World
from simtest_operator.snapshots import JumpCause

_LOOKAHEAD = 4
"""Route roads considered ahead of the current one (a junction is road, connector, road)."""
_VANISHED = 0.01
"""Metres of lane width below which a narrowing lane has ended (a merge lane)."""
STANDSTILL_SPEED = 1e-3
"""Speed (m/s) below which an actor counts as standing still."""


def lateral_position(world: World, actor: Actor) -> float:
    """Absolute t of a ROAD actor (for the heading tilt of lateral motion)."""
    if actor.mode is not Mode.ROAD or actor.road_id is None:
        return 0.0
    return world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset


def relative_heading(actor: Actor, speed: float) -> float:
    """A ROAD actor's heading relative to its lane (towards +t) as its last step moved it at
    ``speed``: the lateral motion of that step over the distance."""
    if speed <= 0.0:
        return 0.0
    return math.asin(max(-1.0, min(1.0, actor.lateral_speed / speed)))


def move(
    world: World,
    actor: Actor,
    dt: float,
    *,
    before: tuple[str | None, int, float],
    start: tuple[float, float],
    placed: bool = False,
) -> None:
    """Advance ``actor`` by ``dt`` (speed and offset already updated for this step);
    ``before`` is its (road, lane, offset) and ``start`` its (x, y) at the start of the step;
    ``placed`` says a trajectory already put it where it is at the end of the step."""
    x0, y0 = start
    road_before, lane_before, offset_before = before
    was_stuck = actor.stuck
    if placed:
        actor.lateral_speed = 0.0
        if actor.mode is not Mode.PATH:  # a trajectory gave its own velocity
            actor.set_travel(None)
    elif actor.mode is Mode.ROAD and actor.road_id is not None and world.roads is not None:
        lateral_rate = 0.0
        if road_before == actor.road_id and dt > 0:
            if lane_before == actor.lane_id:
                lateral_rate = (actor.offset - offset_before) / dt
            else:
                t_before = world.lane_t(actor.road_id, actor.s, lane_before) + offset_before
                lateral_rate = (lateral_position(world, actor) - t_before) / dt
        speed = actor.speed
        distance = speed * dt
        changing_lanes = actor.steer_rate is not None  # a lane change counts lanes from here
        steered = actor.lane_changing and lateral_rate != 0.0
        if steered:
            # A lane change steers: the speed is along the path, so the lateral part of this
            # step's travel is taken from the longitudinal one (esmini's lane change).
            steer = actor.steer_rate if actor.steer_rate is not None else lateral_rate
            lateral = min(abs(steer) * dt, abs(distance))
            distance = math.copysign(math.sqrt(distance * distance - lateral * lateral), distance)
        actor.lane_changing = False
        actor.steer_rate = None
        # s per metre driven at the lateral position the last pose found (one step old: the
        # lateral motion within a step changes it by far less than a per mille)
        stretch = actor.stretch
        stretched = distance * stretch
        s_before = actor.s
        location = world.roads.advance(
            actor.road_id,
            actor.s,
            actor.lane_id,
            stretched * actor.direction,
            prefer_roads=actor.route[actor.route_index + 1 : actor.route_index + _LOOKAHEAD],
            straightest=not actor.route,
        )
        walked = 1 if distance >= 0 else -1
        actor.stuck = location.remaining > 1e-9 or (was_stuck and distance == 0.0)
        if actor.stuck and not was_stuck:
            # It stops short of its step with its speed kept for one more step: a stop the
            # recorded velocity does not explain.
            world.declare(actor, JumpCause.ROAD_END)
        if actor.stuck and was_stuck:
            # The lane ended: the entity stands there, as in esmini, which drops the speed one
            # step after the end was reached (a teleport right at the end keeps the speed).
            actor.speed = 0.0
        actor.road_id, actor.s, actor.lane_id = location.road_id, location.s, location.lane_id
        if stretched != 0.0:  # a zero walk reports direction +1 whatever the travel direction
            direction = location.direction * walked
            if direction != actor.direction:
                # t flips relative to travel (a road linked end to end): keep the offset and the
                # lateral motion on the same side of the vehicle
                actor.offset = -actor.offset
                lateral_rate = -lateral_rate
            actor.direction = direction
        same_lane = location.road_id == road_before and location.lane_id == lane_before
        if same_lane and not changing_lanes:
            _leave_vanished_lane(world, actor, s_before)
        along = abs(distance) / dt if dt > 0 else abs(actor.speed)
        tilt = math.atan2(actor.direction * lateral_rate, along) if actor.speed else 0.0
        road_kept = location.road_id == road_before
        if not road_kept and actor.route:
            ahead = actor.route[actor.route_index : actor.route_index + _LOOKAHEAD]
            if location.road_id in ahead:
                actor.route_index += ahead.index(location.road_id)
                _pick_route_lane(world, actor)
        world.pose_on_road(actor, tilt)
        actor.lateral_speed = lateral_rate
        if dt > 0:
            # Along the lane by the distance it got, across it at the lateral rate (the heading
            # may point elsewhere: an entity placed at an angle). The distance is the walk in s
            # over the stretch along it: where the curvature changes (into a bend, onto the next
            # road) the one-step-old stretch made it more or less than the speed says.
            along = speed  # (not |distance| / dt: that differs from it in the last bits)
            if location.remaining > 0.0 or actor.stretch != stretch:
                mean = (stretch + actor.stretch) / 2.0
                driven = max(abs(stretched) - location.remaining, 0.0) / mean
                along = math.copysign(driven, distance) / dt
            elif steered:
                along = distance / dt
            _travel_on_lane(actor, along, lateral_rate, tilt)
        else:
            actor.set_travel(None)
    elif actor.mode is Mode.FREE:
        actor.x += actor.speed * math.cos(actor.heading) * dt
        actor.y += actor.speed * math.sin(actor.heading) * dt
        actor.lateral_speed = 0.0
        actor.set_travel(None)
    actor.odometer += math.hypot(actor.x - x0, actor.y - y0)
    update_timers(world, actor, dt, was_stuck=was_stuck)


def _leave_vanished_lane(world: World, actor: Actor, s_before: float) -> None:
    """A lane that narrowed to nothing under the actor (a merge lane's end) no longer holds it:
    it belongs to the lane next to it, nearer the centre, where it is (its offset takes the
    difference), instead of riding a lane of no width to a link that snaps it across."""
    roads = world.roads
    assert roads is not None and actor.road_id is not None
    road_id, lane_id = actor.road_id, actor.lane_id
    width = roads.lane_width(road_id, actor.s, lane_id)
    if width >= _VANISHED or width >= roads.lane_width(road_id, s_before, lane_id):
        return
    inner = lane_id - (1 if lane_id > 0 else -1)
    if inner == 0 or roads.lane_width(road_id, actor.s, inner) < _VANISHED:
        return
    t = world.lane_t(road_id, actor.s, lane_id) + actor.offset
    actor.lane_id = inner
    actor.offset = t - world.lane_t(road_id, actor.s, inner)


def _travel_on_lane(actor: Actor, along: float, lateral_rate: float, tilt: float) -> None:
    """The world velocity of a lane-following actor: ``along`` its lane in its direction of
    travel, ``lateral_rate`` towards +t (its heading is the lane's turned by its heading
    offset and ``tilt``)."""
    base = actor.heading - actor.heading_offset - tilt
    cos_b, sin_b = math.cos(base), math.sin(base)
    across = actor.direction * lateral_rate
    if across == 0.0 and actor.heading_offset == 0.0 and tilt == 0.0:
        actor.set_travel(None if along == actor.speed else (along * cos_b, along * sin_b))
        return
    actor.set_travel((along * cos_b - across * sin_b, along * sin_b + across * cos_b))


def update_timers(world: World, actor: Actor, dt: float, *, was_stuck: bool) -> None:
    actor.standstill_time = (
        actor.standstill_time + dt if abs(actor.speed) < STANDSTILL_SPEED else 0.0
    )
    # Time at the end of the road counts from the moment it was reached (end of this step).
    actor.end_of_road_time = actor.end_of_road_time + dt if actor.stuck and was_stuck else 0.0
    if world.roads is None:
        return
    # Lane-following actors are on the road unless an offset pushes them past its edge (also
    # when stuck at a road's end); only free and path-following actors, and a lane-bound one
    # beside its own road, need the (costlier) projection: a point beside one road can lie on
    # another (a junction's connectors overlap), and that is road surface all the same.
    if actor.mode is Mode.ROAD and (actor.offset == 0.0 or _within_road_edges(world, actor)):
        on_road = True
    else:
        on_road = world.roads.is_on_road(actor.x, actor.y)
    actor.offroad_time = 0.0 if on_road else actor.offroad_time + dt


def _within_road_edges(world: World, actor: Actor) -> bool:
    """Whether a lane-bound actor's reference point lies on a lane of any type but ``none``
    (esmini's off-road rule: beyond the road's outer lanes, not counting ``none`` lanes)."""
    roads = world.roads
    assert roads is not None and actor.road_id is not None
    t = world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset
    return any(
        bounds.t_min - 1e-9 <= t <= bounds.t_max + 1e-9
        for bounds in roads.lanes_at(actor.road_id, actor.s)
        if bounds.lane_id != 0 and bounds.type != "none"
    )


def _pick_route_lane(world: World, actor: Actor) -> None:
    """Entering a road where the lane graph splits (one lane feeding two), take the lane whose
    successors continue the route, as the reference player does."""
    roads = world.roads
    if roads is None or actor.road_id is None:
        return
    following = actor.route[actor.route_index + 1 : actor.route_index + _LOOKAHEAD]
    if not following:
        return

    road_id = actor.road_id
    exit_s = (
        roads.road_length(road_id) if roads.driving_direction(road_id, actor.lane_id) > 0 else 0.0
    )

    def continues(lane_id: int) -> bool:
        if any(entry.road_id in following for entry in roads.successors(road_id, lane_id)):
            return True
        # a lane that narrows to nothing before the road's exit (a merge lane) goes on
        # through the lane next to it, nearer the centre (_leave_vanished_lane moves it there)
        inner = lane_id - (1 if lane_id > 0 else -1)
        return (
            inner != 0
            and roads.lane_width(road_id, exit_s, lane_id) < _VANISHED
            and any(entry.road_id in following for entry in roads.successors(road_id, inner))
        )

    if continues(actor.lane_id):
        return
    candidates = [
        lane_id
        for lane_id in roads.lane_ids(actor.road_id, actor.s)
        if lane_id * actor.lane_id > 0
        and continues(lane_id)
        # a lane still 0 m wide here (opening further on) does not hold the actor yet: its
        # centre lies on the border, a jump away (the mirror of _leave_vanished_lane)
        and roads.lane_width(actor.road_id, actor.s, lane_id) >= _VANISHED
    ]
    if candidates:
        actor.lane_id = min(candidates, key=lambda lane_id: abs(lane_id - actor.lane_id))
