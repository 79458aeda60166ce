"""Templates where the critical actor crosses the ego's path.

ltap: left turn across path, opposite direction (LTAP/OD). The ego goes straight through the
    four-way junction northbound; an oncoming car turns left (east) across its path. Start
    positions are chosen so that the target reaches the conflict point `offset` seconds after
    the ego would at constant speeds (negative: the target is there first).
pedestrian-crossing: a pedestrian waiting at the kerb starts to walk across the road when the
    ego's front is `tta` seconds away from the crossing line (time to arrival at constant speed).
pedestrian-turn-back: the same start, but at the far kerb the pedestrian turns round and walks
    back across, so a logical scenario over the same parameters has two separate failure
    regions (the ego meets the pedestrian stepping out, or coming back); a search benchmark case.

Geometry (see roads.py): the junction centre is the origin, road 1 runs north along x=0 from
y=-215 to y=-15, lane -1 of road 1 is centred on x=+1.75. The rural road starts at the origin
heading east; its first 150 m are straight, lane -1 is centred on y=-1.75.
"""

from __future__ import annotations

import math

from scenariogeneration import xosc

from libgen import parts, roads
from libgen.blueprints import Blueprint, number, tags_for

ARRIVAL_TIME = 6.0
"""Seconds the ego needs from its start to the LTAP conflict point at constant speed."""

EGO_TO_CONFLICT = 17.7
"""Path length from the end of road 1 to the LTAP conflict point along the ego's lane (m)."""

TARGET_TO_CONFLICT = 13.2
"""Path length from the start of road 3 to the conflict point along the left turn (m)."""

EGO_FRONT = parts.CAR_LENGTH - parts.CAR_REAR_OVERHANG
"""Distance from the ego's reference point to its front bumper (m)."""

KERB = 5.5
"""Lateral distance of the waiting pedestrian from the road's centre line (m)."""


def ltap(*, speed: float, target_speed: float, offset: float, duration: float = 15.0) -> Blueprint:
    """Ego northbound straight on; target southbound turns left across its path."""
    road = roads.JUNCTION
    ego_start = round(roads.ARM_LENGTH - (speed * ARRIVAL_TIME - EGO_TO_CONFLICT), 1)
    target_start = round(target_speed * (ARRIVAL_TIME + offset) - TARGET_TO_CONFLICT, 1)
    if not (ego_start >= 5.0 and 5.0 <= target_start <= roads.ARM_LENGTH - 5.0):
        raise ValueError(f"ltap v{speed} vt{target_speed} offset{offset}: starts off the arms")
    entities = xosc.Entities()
    parts.add_ego(entities)
    entities.add_scenario_object("Target", parts.car("target_car"))
    init = xosc.Init()
    parts.init_ego(init, 1, -1, "$EgoS", "$EgoSpeed")
    init.add_init_action("Ego", parts.route("EgoStraight", [(1, -1, ego_start), (3, -1, 60.0)]))
    parts.init_vehicle(init, "Target", 3, 1, "$TargetS", "$TargetSpeed")
    init.add_init_action(
        "Target", parts.route("TargetLeftTurn", [(3, 1, target_start), (2, -1, 60.0)])
    )
    when = "before" if offset < 0 else "after"
    return Blueprint(
        category="ltap",
        road=road,
        stem=f"ltap_junction_v{number(speed)}_vt{number(target_speed)}_dt{number(offset)}",
        description=f"Oncoming car at {number(target_speed)} m/s turns left across the path of "
        f"the ego ({number(speed)} m/s), reaching the conflict point {number(abs(offset))} s "
        f"{when} it",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", ego_start),
            ("TargetSpeed", target_speed),
            ("TargetS", target_start),
            ("ArrivalOffset", offset),
        ),
        duration=duration,
        tags=tags_for("ltap", road, speed, ["oncoming", "left-turn", f"target-{when}"]),
        entities=entities,
        init=init,
        stories=(),
    )


def _pedestrian_scenario(
    *,
    road: roads.RoadNet,
    stem: str,
    description: str,
    speed: float,
    walk_speed: float,
    tta: float,
    ego_start: tuple[int, int, float],
    walk: list[tuple[float, float, float]],
    extra_init: list[xosc.AssignRouteAction],
    extra_tags: list[str],
    duration: float,
    category: str = "pedestrian-crossing",
) -> Blueprint:
    entities = xosc.Entities()
    parts.add_ego(entities)
    entities.add_scenario_object("Pedestrian", parts.pedestrian("adult"))
    init = xosc.Init()
    road_id, lane, s = ego_start
    parts.init_ego(init, road_id, lane, "$EgoS", "$EgoSpeed")
    for action in extra_init:
        init.add_init_action("Ego", action)
    x, y, h = walk[0]
    init.add_init_action("Pedestrian", parts.teleport(xosc.WorldPosition(x, y, 0.0, h)))
    init.add_init_action("Pedestrian", parts.speed_step(0))
    trigger_distance = round(speed * tta, 1)
    start = parts.event(
        "PedestrianWalks",
        [parts.walk_path("CrossingPath", walk), parts.speed_step("$WalkSpeed")],
        parts.when_close(
            "EgoApproaches", "Ego", "Pedestrian", "$TriggerDistance", xosc.Rule.lessThan
        ),
    )
    return Blueprint(
        category=category,
        road=road,
        stem=stem,
        description=description,
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", s),
            ("WalkSpeed", walk_speed),
            ("TriggerDistance", trigger_distance),
        ),
        duration=duration,
        tags=tags_for(category, road, speed, extra_tags),
        entities=entities,
        init=init,
        stories=(parts.story("Pedestrian", "Pedestrian", [start]),),
    )


def pedestrian_junction(
    *, speed: float, tta: float, walk_speed: float, duration: float = 15.0
) -> Blueprint:
    """Pedestrian crosses road 1 from the right, 8 m before the junction."""
    crossing_y = -(roads.JUNCTION_RADIUS + 8.0)
    ego_s = round(roads.ARM_LENGTH - 8.0 - speed * (tta + 4.0) - EGO_FRONT, 1)
    west, south = math.pi, -math.pi / 2
    walk = [(KERB, crossing_y, west), (-KERB, crossing_y, west), (-KERB, crossing_y - 10.0, south)]
    return _pedestrian_scenario(
        road=roads.JUNCTION,
        stem=f"pedestrian-crossing_junction_v{number(speed)}_tta{number(tta)}"
        f"_walk{number(walk_speed)}",
        description=f"A pedestrian at {number(walk_speed)} m/s crosses from the right in front "
        f"of the junction when the ego ({number(speed)} m/s) is {number(tta)} s away",
        speed=speed,
        walk_speed=walk_speed,
        tta=tta,
        ego_start=(1, -1, ego_s),
        walk=walk,
        extra_init=[parts.route("EgoStraight", [(1, -1, ego_s), (3, -1, 60.0)])],
        extra_tags=["from-right", "crosswalk"],
        duration=duration,
    )


def pedestrian_turn_back(
    *, speed: float, tta: float, walk_speed: float, duration: float = 20.0
) -> Blueprint:
    """Pedestrian crosses road 1 from the right like :func:`pedestrian_junction`, turns back at
    the far kerb and walks back across (then away along the near side)."""
    crossing_y = -(roads.JUNCTION_RADIUS + 8.0)
    ego_s = round(roads.ARM_LENGTH - 8.0 - speed * (tta + 4.0) - EGO_FRONT, 1)
    west, east, south = math.pi, 0.0, -math.pi / 2
    walk = [
        (KERB, crossing_y, west),
        (-KERB, crossing_y, west),
        (KERB, crossing_y, east),
        (KERB, crossing_y - 10.0, south),
    ]
    return _pedestrian_scenario(
        road=roads.JUNCTION,
        stem=f"pedestrian-turn-back_junction_v{number(speed)}_tta{number(tta)}"
        f"_walk{number(walk_speed)}",
        description=f"A pedestrian at {number(walk_speed)} m/s crosses from the right in front "
        f"of the junction when the ego ({number(speed)} m/s) is {number(tta)} s away, turns "
        "back at the far kerb and crosses again",
        speed=speed,
        walk_speed=walk_speed,
        tta=tta,
        ego_start=(1, -1, ego_s),
        walk=walk,
        extra_init=[parts.route("EgoStraight", [(1, -1, ego_s), (3, -1, 60.0)])],
        extra_tags=["from-right", "crosswalk", "turn-back"],
        duration=duration,
        category="pedestrian-turn-back",
    )


RURAL_CROSSING_X = 140.0
"""Where pedestrians cross the rural road (on its first straight)."""


def pedestrian_rural(
    *, speed: float, tta: float, side: str, duration: float = 15.0, walk_speed: float = 1.4
) -> Blueprint:
    """Pedestrian crosses the rural road mid-block from the near (right) or far (left) side."""
    north, south = math.pi / 2, -math.pi / 2
    if side == "near":
        walk = [
            (RURAL_CROSSING_X, -KERB, north),
            (RURAL_CROSSING_X, KERB, north),
            (RURAL_CROSSING_X + 10.0, KERB, 0.0),
        ]
    else:
        walk = [
            (RURAL_CROSSING_X, KERB, south),
            (RURAL_CROSSING_X, -KERB, south),
            (RURAL_CROSSING_X + 10.0, -KERB, 0.0),
        ]
    ego_s = 10.0
    if RURAL_CROSSING_X - ego_s - EGO_FRONT < speed * (tta + 1.0):
        raise ValueError(f"rural crossing v{speed} tta{tta}: the trigger would fire at once")
    side_tag = "from-right" if side == "near" else "from-left"
    return _pedestrian_scenario(
        road=roads.RURAL,
        stem=f"pedestrian-crossing_rural_v{number(speed)}_tta{number(tta)}_{side}",
        description=f"A pedestrian crosses the rural road from the {side} side when the ego "
        f"({number(speed)} m/s) is {number(tta)} s away",
        speed=speed,
        walk_speed=walk_speed,
        tta=tta,
        ego_start=(1, -1, ego_s),
        walk=walk,
        extra_init=[],
        extra_tags=[side_tag, "mid-block"],
        duration=duration,
    )
