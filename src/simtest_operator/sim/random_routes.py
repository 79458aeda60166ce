"""RandomRouteAction: a route drawn at random through the road network ahead of the entity.

The route is a chain of roads: from the road the entity is on, in its travel direction, each next
road is drawn uniformly from the roads its driven lanes lead onto (at a junction: one connector
per way through), until the route is :data:`MAX_LENGTH` long or reaches a dead end. It is then
assigned as an AssignRouteAction's route is (the entity prefers its roads at forks). The draw
uses the world's seeded generator, so a run repeats exactly with the same seed, and different
seeds take different ways.
"""

from __future__ import annotations

import random

from simtest_operator.opendrive import RoadNetwork
from simtest_operator.sim import route_planning

MAX_LENGTH = 5_000.0
"""Metres of road a random route covers: more than any scenario drives before it ends."""
MAX_ROADS = 500
"""Roads in a random route at most (a map of short roads reaches this first)."""


def draw(roads: RoadNetwork, start: route_planning.Node, rng: random.Random) -> tuple[str, ...]:
    """The roads of a random route from ``start`` (road, travel direction), ``start``'s first."""
    route = [start[0]]
    node = start
    length = 0.0
    while len(route) < MAX_ROADS and length < MAX_LENGTH:
        options = sorted(route_planning.exits(roads, *node))
        if not options:
            break
        node = rng.choice(options)
        route.append(node[0])
        length += roads.road_length(node[0])
    return tuple(route)
