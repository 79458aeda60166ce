"""Routing: which roads an actor should prefer at forks to reach its route's waypoints.

A shortest-path search (Dijkstra, by road length) over road ends (road, travel direction)
through the lane graph finds the road sequence between consecutive waypoints; the actor then
prefers those roads whenever the lane it follows forks. Lane choice inside a road is not
planned: an actor in a lane that does not lead where the route goes follows its lane (and the
route is effectively left).
"""

from __future__ import annotations

import heapq
import math

from simtest_operator.opendrive import ContactPoint, RoadNetwork

MAX_ROADS = 10_000
"""Search bound; real maps have a few hundred roads."""


def exits(roads: RoadNetwork, road_id: str, direction: int) -> set[tuple[str, int]]:
    """(road, direction) pairs reachable by leaving ``road_id`` travelling ``direction``."""
    end = ContactPoint.END if direction > 0 else ContactPoint.START
    s = roads.road_length(road_id) if direction > 0 else 0.0
    found: set[tuple[str, int]] = set()
    for lane_id in roads.lane_ids(road_id, s):
        # Only lanes driven in the travel direction lead on (the lane graph is symmetric).
        if lane_id == 0 or roads.driving_direction(road_id, lane_id) != direction:
            continue
        for entry in roads.next_lanes(road_id, lane_id, end):
            found.add((entry.road_id, 1 if entry.contact_point is ContactPoint.START else -1))
    return found


Node = tuple[str, int]
"""(road id, travel direction +1/-1)."""


def plan(
    roads: RoadNetwork, start: Node, goal_road: str, goal_direction: int | None = None
) -> list[Node] | None:
    """Shortest (by road length) chain of (road, direction) nodes from ``start`` to
    ``goal_road`` (travelled in ``goal_direction`` when given) inclusive, or None."""

    def reached(node: Node) -> bool:
        return node[0] == goal_road and goal_direction in (None, node[1])

    if reached(start):
        return [start]
    best: dict[Node, float] = {start: 0.0}
    previous: dict[Node, Node | None] = {start: None}
    queue: list[tuple[float, Node]] = [(0.0, start)]
    while queue and len(previous) < MAX_ROADS:
        cost, node = heapq.heappop(queue)
        if cost > best.get(node, math.inf):
            continue
        if reached(node):
            path = [node]
            back = previous[node]
            while back is not None:
                path.append(back)
                back = previous[back]
            return path[::-1]
        for nxt in sorted(exits(roads, *node)):
            total = cost + roads.road_length(nxt[0])
            if total < best.get(nxt, math.inf):
                best[nxt] = total
                previous[nxt] = node
                heapq.heappush(queue, (total, nxt))
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
