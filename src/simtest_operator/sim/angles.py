"""Angles of an entity in the coordinate systems OpenSCENARIO's angle conditions name (1.3).

``entity``/``world``: the entity's own heading, pitch or roll in the world. ``road``/``lane``:
the heading measured from the direction of increasing s of the road's reference line, or of the
lane centre line, at the entity's position (a car driving its lane along s is at 0, one driving
a lane against s at pi). The readers refuse what cannot be measured here (trajectory frames, road
pitch and roll), so every condition that reaches this module has an answer.
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor
from simtest_operator.sim.world import World

_TURN = 2.0 * math.pi


def angle(
    world: World, actor: Actor, kind: model.AngleType, system: model.CoordinateSystem
) -> float | None:
    """The angle in radians, wrapped to [-pi, pi]; None off the roads in a road frame."""
    if kind is model.AngleType.PITCH:
        return math.remainder(actor.pitch, _TURN)
    if kind is model.AngleType.ROLL:
        return math.remainder(actor.roll, _TURN)
    if system not in (model.CoordinateSystem.ROAD, model.CoordinateSystem.LANE):
        return math.remainder(actor.heading, _TURN)
    coord = world.road_coord(actor.x, actor.y, actor.heading)
    if coord is None or not coord.on_road:
        return None
    reference = coord.heading_of_road
    if system is model.CoordinateSystem.LANE and coord.lane_id != 0 and world.roads is not None:
        reference = world.roads.lane_pose(coord.road_id, coord.s, coord.lane_id).heading
    return math.remainder(actor.heading - reference, _TURN)


def within(value: float, wanted: float, tolerance: float) -> bool:
    """``value`` equals ``wanted`` within ``tolerance``, going round the circle either way."""
    return abs(math.remainder(value - wanted, _TURN)) <= tolerance + 1e-9
