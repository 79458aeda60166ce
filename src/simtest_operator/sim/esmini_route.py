"""esmini's FollowRouteController: change lanes in time to drive the lanes an assigned route needs.

The engine's routing (:mod:`~simtest_operator.sim.route_planning`) only prefers the route's roads
at forks; an actor in a lane that does not lead on leaves the route. esmini's FollowRoute
controller plans over lanes instead and, while it is active (lateral domain), starts its own
lane changes (sinusoidal, ``laneChangeTime`` seconds) towards the lane each road of the route
must be left in, and towards the target waypoint's lane on the last road. The scenario's own
actions keep running (esmini's additive mode), except that the controller's lane change takes
the lateral domain while it runs.

Semantics imitated from esmini (ControllerFollowRoute, LaneIndependentRouter):

- one leg at a time: from where the actor is to the next scenario waypoint on another road (a
  waypoint on the actor's current road is skipped; none left: the controller deactivates);
- on each road before the last, the waypoint is the middle of the stretch at the road's exit
  where a lane leading onto the next road exists; on the last road, the scenario waypoint;
- a lane change starts once the actor is within ``max(laneChangeTime * speed, 25 m)`` of the
  waypoint along the road, in another lane, and no other entity on the same road and side, in
  another lane, is closer than ``minDistForCollision`` (0 or less: no check);
- passing a waypoint in its lane moves on to the next one; passing it in another lane re-plans
  the leg from where the actor is; no path: the controller deactivates;
- ``testMode`` stops the actor (speed 0) when the controller deactivates.
"""

from __future__ import annotations

import dataclasses
import math

from simtest_operator.opendrive import DRIVABLE_LANE_TYPES, ContactPoint, RoadNetwork
from simtest_operator.openscenario import model
from simtest_operator.sim import route_planning
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World

TYPE_NAME = "FollowRouteController"
"""The ``esminiController`` property value that selects this controller."""

MIN_LANE_WIDTH = 0.5
"""Narrower target lanes (m) are not changed into (esmini's minLaneWidth)."""

MIN_TRIGGER_DISTANCE = 25.0
"""Lane changes start at least this far (m) before their waypoint."""


@dataclasses.dataclass(frozen=True, slots=True)
class Waypoint:
    """A lane at a distance along a road: where the actor must be when it passes ``s``."""

    road_id: str
    lane_id: int
    s: float


def is_follow_route(controller: model.Controller) -> bool:
    return controller.property("esminiController") == TYPE_NAME


class FollowRoute:
    """One actor's FollowRoute controller; :meth:`step` once per step while it drives."""

    __slots__ = (
        "_current",
        "_fresh",
        "_last_lane",
        "_leg_target",
        "_planned",
        "_targets",
        "_waypoints",
        "active",
        "change",
        "lane_change_time",
        "min_dist",
        "name",
        "test_mode",
    )

    def __init__(self, controller: model.Controller) -> None:
        self.name = controller.name
        self.min_dist = controller.number("minDistForCollision", 10.0)
        self.lane_change_time = controller.number("laneChangeTime", 5.0)
        self.test_mode = (controller.property("testMode") or "").strip().lower() == "true"
        self.active = False
        self.change: object | None = None
        """The lane change this controller started last (the dispatcher's run)."""
        self._targets: list[Waypoint] = []
        """The assigned route's waypoints (the scenario's)."""
        self._leg_target = 0
        self._waypoints: list[Waypoint] = []
        """The current leg's waypoints: one per road, the last is the scenario waypoint."""
        self._current = 0
        self._planned = False
        self._fresh = False
        """A route came this step: esmini's controller sees it after this step's motion."""
        self._last_lane: tuple[str, int] | None = None
        """(road, lane) the actor was in at the previous step (to judge a passed waypoint)."""

    def activate(self) -> None:
        """(Re)start from the first scenario waypoint, as esmini's Activate does."""
        self.active = True
        self._leg_target = 0
        self._current = 0
        self._planned = False
        self._waypoints = []

    def assign(self, targets: list[Waypoint]) -> None:
        self._fresh = True
        self._targets = targets
        self._leg_target = 0
        self._current = 0
        self._planned = False
        self._waypoints = []

    def step(self, world: World, actor: Actor, *, changing: bool) -> int | None:
        """Advance the controller; returns a lane to change to now, if one is due."""
        roads = world.roads
        if not self.active or not self._targets or roads is None:
            return None
        if self._fresh:
            self._fresh = False
            return None
        if actor.mode is not Mode.ROAD or actor.road_id is None:
            return None
        if not self._planned and not self._plan(world, actor):
            return None
        if self._current >= len(self._waypoints):
            self._deactivate(actor)
            return None
        waypoint = self._waypoints[self._current]
        lane = world.current_lane(actor)
        change: int | None = None
        if waypoint.road_id == actor.road_id and lane != waypoint.lane_id:
            reach = max(self.lane_change_time * actor.speed, MIN_TRIGGER_DISTANCE)
            near = abs(actor.s - waypoint.s) < reach
            if near and not changing and self._can_change(world, actor, lane, waypoint):
                change = waypoint.lane_id
        self._update(world, actor, lane, waypoint)
        self._last_lane = (actor.road_id, lane)
        return change

    # --- internals ----------------------------------------------------------------------------

    def _deactivate(self, actor: Actor) -> None:
        self.active = False
        if self.test_mode:
            actor.speed = 0.0

    def _plan(self, world: World, actor: Actor) -> bool:
        """Plan the next leg; False when there is none (the controller deactivated)."""
        roads = world.roads
        assert roads is not None and actor.road_id is not None
        target = self._targets[self._leg_target]
        if target.road_id == actor.road_id:
            self._leg_target += 1
            if self._leg_target >= len(self._targets):
                self._deactivate(actor)
                return False
            target = self._targets[self._leg_target]
        here = Waypoint(actor.road_id, world.current_lane(actor), actor.s)
        waypoints = plan_leg(roads, here, actor.direction, target)
        if waypoints is None:
            self._deactivate(actor)
            return False
        self._waypoints = waypoints
        self._current = 0
        self._planned = True
        # The actor takes the planned roads at forks (esmini resets the entity's route too).
        actor.route = tuple(w.road_id for w in waypoints)
        actor.route_index = 0
        return True

    def _update(self, world: World, actor: Actor, lane: int, waypoint: Waypoint) -> None:
        status = self._status(actor, lane, waypoint)
        if status is None:
            return
        if status:
            self._current += 1
            last_road = waypoint.road_id == self._waypoints[-1].road_id
            if last_road and self._leg_target < len(self._targets) - 1:
                self._leg_target += 1
                self._planned = False
                self._plan(world, actor)
            return
        self._planned = False
        self._plan(world, actor)

    def _status(self, actor: Actor, lane: int, waypoint: Waypoint) -> bool | None:
        """True: passed in its lane; False: passed in another lane; None: not reached."""
        if waypoint.road_id == actor.road_id:
            beyond = (actor.s - waypoint.s) * actor.direction > 0.0
            return (lane == waypoint.lane_id) if beyond else None
        previous = self._last_lane
        if previous is None or previous[0] != waypoint.road_id:
            return None
        return previous[1] == waypoint.lane_id

    def _can_change(self, world: World, actor: Actor, lane: int, waypoint: Waypoint) -> bool:
        roads = world.roads
        assert roads is not None and actor.road_id is not None
        if waypoint.lane_id not in roads.lane_ids(actor.road_id, actor.s):
            return False
        if self.min_dist <= 0.0:
            return True
        if roads.lane_width(actor.road_id, actor.s, waypoint.lane_id) < MIN_LANE_WIDTH:
            return False
        for other in world.actors.values():
            if other is actor or not other.placed or other.road_id != actor.road_id:
                continue
            other_lane = world.current_lane(other)
            if other_lane == lane or other_lane * lane <= 0:
                continue
            if math.hypot(other.x - actor.x, other.y - actor.y) < self.min_dist:
                return False
        return True


def plan_leg(
    roads: RoadNetwork, start: Waypoint, direction: int, target: Waypoint
) -> list[Waypoint] | None:
    """The waypoints from ``start`` (travelling ``direction``) to ``target``: per road before
    the target's, the lane to leave it in and where; then ``target``. None when no road path
    leads there."""
    lane = start.lane_id
    if start.road_id == target.road_id and lane == target.lane_id:
        return None
    # The target lane must be reached driving its way (a lane of the other carriageway is not).
    arrive = roads.driving_direction(target.road_id, target.lane_id)
    path = route_planning.plan(roads, (start.road_id, direction), target.road_id, arrive)
    if path is None or len(path) < 2:
        return None
    # Backwards from the target lane: on each road, a lane that enters the next road in the lane
    # wanted there if one does (esmini's lane-level search reaches the target road in the target
    # lane), else any lane leading onto the next road; the nearest one to the lane wanted next.
    wanted = target.lane_id
    lanes: list[int] = []
    for index in range(len(path) - 2, -1, -1):
        road_id, direction = path[index]
        next_road = path[index + 1][0]
        entries = _entries(roads, road_id, direction, next_road)
        if not entries:
            return None
        direct = [lane_id for lane_id, entered in entries.items() if wanted in entered]
        if direct:
            near = lane if index == 0 else wanted
            best = min(direct, key=lambda c: (abs(c - near), abs(c)))
        else:
            best = min(entries, key=lambda c: (min(abs(e - wanted) for e in entries[c]), abs(c)))
        lanes.append(best)
        wanted = best
    lanes.reverse()
    result: list[Waypoint] = []
    for index, (road_id, direction) in enumerate(path[:-1]):
        best = lanes[index]
        stretch = _exit_stretch(roads, road_id, direction, best)
        length = roads.road_length(road_id)
        s = length - stretch / 2.0 if direction > 0 else stretch / 2.0
        if index == 0 and (start.s > length - stretch if direction > 0 else start.s < stretch):
            s = start.s  # already in the stretch: the waypoint is where the actor is
        result.append(Waypoint(road_id, best, s))
    result.append(target)
    return result


def _entries(
    roads: RoadNetwork, road_id: str, direction: int, next_road: str
) -> dict[int, set[int]]:
    """The lanes of a road travelled in ``direction`` that lead onto ``next_road``, each with
    the lanes of ``next_road`` it enters."""
    end = ContactPoint.END if direction > 0 else ContactPoint.START
    exit_s = roads.road_length(road_id) if direction > 0 else 0.0
    found: dict[int, set[int]] = {}
    for lane_id in roads.lane_ids(road_id, exit_s):
        if lane_id == 0 or roads.driving_direction(road_id, lane_id) != direction:
            continue
        entered = {
            e.lane_id for e in roads.next_lanes(road_id, lane_id, end) if e.road_id == next_road
        }
        if entered:
            found[lane_id] = entered
    return found


def _exit_stretch(roads: RoadNetwork, road_id: str, direction: int, lane_id: int) -> float:
    """Length of the lane sections at the road's exit where ``lane_id`` exists as a drivable
    lane (esmini's LaneIndependentRouter puts the waypoint in its middle)."""
    road = roads.road(road_id)
    sections = list(road.lane_sections)
    ends = [s.s for s in sections[1:]] + [road.length]
    order = range(len(sections) - 1, -1, -1) if direction > 0 else range(len(sections))
    stretch = 0.0
    for i in order:
        lane = sections[i].lane(lane_id)
        if lane is None or lane.type not in DRIVABLE_LANE_TYPES:
            break
        stretch += ends[i] - sections[i].s
    return stretch
