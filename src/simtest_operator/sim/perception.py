"""What the system under test perceives: the nearest road user ahead in its path.

On the same road the gap is measured along the road (so curves do not hide the leader) and
"in path" means the lateral footprints overlap; elsewhere the straight corridor ahead of the ego
(shared geometry) decides. Only entities within the sensor range count. Anonymous traffic (driven
by the backend) is perceived like any other road user, through the straight corridor.
"""

from __future__ import annotations

import math

from simtest_operator import geometry
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.sut import Leader
from simtest_operator.sim.world import World


def leader(world: World, ego: Actor, sensor_range: float) -> Leader | None:
    """The nearest entity ahead of ``ego`` in its path, or None."""
    best: Leader | None = None
    ego_state = world.state(ego.name)
    same_road = ego.mode is Mode.ROAD and ego.road_id is not None
    ego_t = 0.0
    if same_road:
        assert ego.road_id is not None
        ego_t = world.lane_t(ego.road_id, ego.s, ego.lane_id) + ego.offset
    for other in world.actors.values():
        if other is ego or not other.placed:
            continue
        if same_road and other.mode is Mode.ROAD and other.road_id == ego.road_id:
            assert ego.road_id is not None
            other_t = world.lane_t(ego.road_id, other.s, other.lane_id) + other.offset
            if abs(other_t - ego_t) >= (ego.box.width + other.box.width) / 2.0:
                continue
            ds = (other.s - ego.s) * ego.direction
            rear = (
                other.box.length - other.front_offset
                if other.direction == ego.direction
                else other.front_offset
            )
            gap = ds - ego.front_offset - rear
            if ds <= 0.0:
                continue
        else:
            other_state = world.state(other.name)
            if not geometry.in_path(ego_state, other_state):
                continue
            if geometry.longitudinal_gap(ego_state, other_state, freespace=False) <= 0.0:
                continue
            gap = geometry.longitudinal_gap(ego_state, other_state, freespace=True)
        if gap > sensor_range or (best is not None and gap >= best.gap):
            continue
        speed = other.speed * math.cos(other.heading - ego.heading)
        best = Leader(gap=max(gap, 0.0), speed=speed)
    for vehicle in world.traffic:
        if not geometry.in_path(ego_state, vehicle):
            continue
        if geometry.longitudinal_gap(ego_state, vehicle, freespace=False) <= 0.0:
            continue
        gap = geometry.longitudinal_gap(ego_state, vehicle, freespace=True)
        if gap > sensor_range or (best is not None and gap >= best.gap):
            continue
        speed = vehicle.speed * math.cos(vehicle.heading - ego.heading)
        best = Leader(gap=max(gap, 0.0), speed=speed)
    return best
