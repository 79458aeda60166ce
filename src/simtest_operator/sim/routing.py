"""Routing: which roads an actor should prefer at forks to reach its route's waypoints.

A breadth-first search over road ends (road, travel direction) through the lane graph finds the
road sequence between consecutive waypoints; the actor then prefers those roads whenever the lane
it follows forks. Lane choice inside a road is not planned: an actor in a lane that does not lead
where the route goes follows its lane (and the route is effectively left).
"""

from __future__ import annotations

import collections

from simtest_operator.opendrive import ContactPoint, RoadNetwork

MAX_ROADS = 10_000
"""Search bound; real maps have a few hundred roads."""


def _exits(roads: RoadNetwork, road_id: str, direction: int) -> set[tuple[str, int]]:
    """(road, direction) pairs reachable by leaving ``road_id`` travelling ``direction``."""
    end = ContactPoint.END if direction > 0 else ContactPoint.START
    s = roads.road_length(road_id) if direction > 0 else 0.0
    found: set[tuple[str, int]] = set()
    for lane_id in roads.lane_ids(road_id, s):
        if lane_id == 0:
            continue
        for entry in roads.next_lanes(road_id, lane_id, end):
            found.add((entry.road_id, 1 if entry.contact_point is ContactPoint.START else -1))
    return found


Node = tuple[str, int]
"""(road id, travel direction +1/-1)."""


def plan(roads: RoadNetwork, start: Node, goal_road: str) -> list[Node] | None:
    """(road, direction) nodes from ``start`` to ``goal_road`` inclusive, or None."""
    if start[0] == goal_road:
        return [start]
    previous: dict[tuple[str, int], tuple[str, int] | None] = {start: None}
    queue = collections.deque([start])
    while queue and len(previous) < MAX_ROADS:
        node = queue.popleft()
        for nxt in sorted(_exits(roads, *node)):
            if nxt in previous:
                continue
            previous[nxt] = node
            if nxt[0] == goal_road:
                path = [nxt]
                back = previous[nxt]
                while back is not None:
                    path.append(back)
                    back = previous[back]
                return path[::-1]
            queue.append(nxt)
    return None


def plan_through(roads: RoadNetwork, start: Node, goals: list[str]) -> list[str]:
    """Roads visiting each goal road in order; a goal that cannot be reached is skipped."""
    route: list[str] = [start[0]]
    here = start
    for goal_road in goals:
        path = plan(roads, here, goal_road)
        if path is None:
            continue
        route.extend(node[0] for node in path[1:])
        here = path[-1]
    return route
