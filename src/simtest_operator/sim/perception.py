"""What the system under test perceives: the nearest road user ahead in its path, and the stop
lines of traffic lights and stop signs ahead on its route.

On the same road the gap is measured along the road (so curves do not hide the leader) and
"in path" means the lateral footprints overlap; elsewhere the straight corridor ahead of the ego
(shared geometry) decides. Only entities within the sensor range count. Anonymous traffic (driven
by the backend) is perceived like any other road user, through the straight corridor.

Stop lines are found by walking the lanes ahead (:meth:`RoadNetwork.walk`) the way motion will
take them (the route's next roads preferred at forks) and looking each lane up in the world's
:attr:`~simtest_operator.sim.world.World.signal_index`; a light's aspect is the state the
scenario set (TrafficSignalStateAction, a controller's phase), unknown when never set.
"""

from __future__ import annotations

import math

from simtest_operator import geometry
from simtest_operator.drivermodel import Aspect, Leader, SignalAhead
from simtest_operator.opendrive import Control
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World
from simtest_operator.snapshots import EntityState


def leader(world: World, ego: Actor, sensor_range: float) -> Leader | None:
    """The nearest entity ahead of ``ego`` in its path, or None."""
    ego_state = world.state(ego.name)
    same_road = ego.mode is Mode.ROAD and ego.road_id is not None
    ego_t = 0.0
    if same_road:
        assert ego.road_id is not None
        ego_t = world.lane_t(ego.road_id, ego.s, ego.lane_id) + ego.offset
    # (gap, or None when not ahead in the path; speed; heading) of every other road user
    candidates: list[tuple[float | None, float, float]] = []
    for other in world.actors.values():
        if other is ego or not other.placed or other.name in world.ghosts:
            continue
        if same_road and other.mode is Mode.ROAD and other.road_id == ego.road_id:
            assert ego.road_id is not None
            gap = _gap_along_road(world, ego, other, ego_t)
        else:
            gap = _gap_in_corridor(ego_state, world.state(other.name))
        candidates.append((gap, other.speed, other.heading))
    for vehicle in world.traffic:
        candidates.append((_gap_in_corridor(ego_state, vehicle), vehicle.speed, vehicle.heading))
    best: Leader | None = None
    for gap, speed, heading in candidates:
        if gap is None or gap > sensor_range or (best is not None and gap >= best.gap):
            continue
        best = Leader(gap=max(gap, 0.0), speed=speed * math.cos(heading - ego.heading))
    return best


def _gap_along_road(world: World, ego: Actor, other: Actor, ego_t: float) -> float | None:
    """Bumper gap along the shared road when the lateral footprints overlap and ``other`` is
    ahead; None otherwise."""
    assert ego.road_id is not None
    other_t = world.lane_t(ego.road_id, other.s, other.lane_id) + other.offset
    if abs(other_t - ego_t) >= (ego.box.width + other.box.width) / 2.0:
        return None
    ds = (other.s - ego.s) * ego.direction
    if ds <= 0.0:
        return None
    rear = (
        other.box.length - other.front_offset
        if other.direction == ego.direction
        else other.front_offset
    )
    return ds - ego.front_offset - rear


def _gap_in_corridor(ego: EntityState, other: EntityState) -> float | None:
    """Free-space gap to ``other`` in the straight corridor ahead of the ego; None when it is
    not in that corridor or not ahead."""
    if not geometry.in_path(ego, other):
        return None
    if geometry.longitudinal_gap(ego, other, freespace=False) <= 0.0:
        return None
    return geometry.longitudinal_gap(ego, other, freespace=True)


_ROUTE_LOOKAHEAD = 4
"""Route roads preferred at forks, counting the current one (as motion takes them)."""


def signals_ahead(world: World, actor: Actor, horizon: float) -> tuple[SignalAhead, ...]:
    """The stop lines within ``horizon`` metres ahead of ``actor``'s front bumper on the lanes it
    will drive, nearest line per signal, with the lights' aspects (empty off the lanes, or on a
    map without traffic lights and stop signs)."""
    roads = world.roads
    if roads is None or actor.mode is not Mode.ROAD or actor.road_id is None:
        return ()
    index = world.signal_index
    if not index:
        return ()
    front = actor.front_offset
    found: dict[str, tuple[float, Control]] = {}
    for stretch in roads.walk(
        actor.road_id,
        actor.s,
        actor.lane_id,
        horizon + max(front, 0.0),
        direction=actor.direction,
        prefer_roads=actor.route[actor.route_index + 1 : actor.route_index + _ROUTE_LOOKAHEAD],
    ):
        lines = index.lines(stretch.road_id, stretch.lane_id)
        if not lines or roads.driving_direction(stretch.road_id, stretch.lane_id) != (
            stretch.direction
        ):
            continue
        low, high = sorted((stretch.s_from, stretch.s_to))
        for line, control in lines:
            if not low <= line.s <= high:
                continue
            distance = stretch.start + (line.s - stretch.s_from) * stretch.direction - front
            if distance <= 0.0 or distance > horizon:
                continue
            known = found.get(control.signal_id)
            if known is None or distance < known[0]:
                found[control.signal_id] = (distance, control.control)
    if not found:
        return ()
    aspects = index.aspects(world.signals)
    return tuple(
        SignalAhead(
            key=key,
            distance=distance,
            stop_sign=control is Control.STOP_SIGN,
            aspect=aspects.get(key, Aspect.UNKNOWN),
        )
        for key, (distance, control) in found.items()
    )
