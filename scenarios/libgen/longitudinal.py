"""Templates where the danger comes from ahead in the ego's own lane.

following: a lead vehicle slows down by a given amount and speeds up again.
hard-braking: a lead vehicle brakes to a standstill.
cut-out: the lead vehicle leaves the lane late and reveals a stopped or slow vehicle.

Every gap and distance parameter is free space, bumper to bumper (time headways too).
"""

from __future__ import annotations

from scenariogeneration import xosc

from libgen import parts, roads
from libgen.blueprints import Blueprint, check_reach, number, tags_for

EGO_LANE = {"highway_straight": -2, "rural_curved": -1}
"""Lane the ego drives in on each road that hosts these templates."""

EGO_START = 20.0
"""Ego start position s along road 1, in metres."""

SHORT = {"highway_straight": "highway", "rural_curved": "rural"}


def headway_gap(speed: float, thw: float) -> float:
    """Bumper-to-bumper gap that gives a time headway `thw` at `speed`."""
    return round(speed * thw, 1)


def _lead_pair(road: roads.RoadNet) -> tuple[xosc.Entities, xosc.Init]:
    """Ego and a lead `$Gap` ahead in the same lane, both at their initial speeds."""
    lane = EGO_LANE[road.name]
    entities = xosc.Entities()
    parts.add_ego(entities)
    entities.add_scenario_object("Lead", parts.car("lead_car"))
    init = xosc.Init()
    parts.init_ego(init, 1, lane, "$EgoS", "$EgoSpeed")
    parts.init_vehicle(init, "Lead", 1, lane, parts.ahead_of_ego("$Gap"), "$LeadSpeed")
    return entities, init


def following(
    *,
    road: roads.RoadNet,
    speed: float,
    thw: float,
    drop: float,
    decel: float,
    duration: float = 25.0,
    slow_at: float = 4.0,
) -> Blueprint:
    """Lead at the ego's speed `thw` s ahead slows by `drop` m/s at `decel` m/s^2, holds the
    lower speed for 4 s, then returns to the initial speed at 1.5 m/s^2."""
    gap = headway_gap(speed, thw)
    entities, init = _lead_pair(road)
    slow = parts.event(
        "LeadSlowsDown",
        [parts.speed_rate("$LeadLowSpeed", "$LeadDecel")],
        parts.at_time("LeadSlowsDownStart", slow_at),
    )
    resume = parts.event(
        "LeadSpeedsUp",
        [parts.speed_rate("$LeadSpeed", 1.5)],
        parts.after_event("LeadSpeedsUpStart", "LeadSlowsDown", delay=4.0),
    )
    blueprint = Blueprint(
        category="following",
        road=road,
        stem=f"following_{SHORT[road.name]}_v{number(speed)}_thw{number(thw)}"
        f"_drop{number(drop)}_d{number(decel)}",
        description=f"Ego follows a lead at {number(speed)} m/s and {number(thw)} s headway; "
        f"the lead slows by {number(drop)} m/s at {number(decel)} m/s2 and speeds up again",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", EGO_START),
            ("LeadSpeed", speed),
            ("Gap", gap),
            ("LeadLowSpeed", speed - drop),
            ("LeadDecel", decel),
        ),
        duration=duration,
        tags=tags_for("following", road, speed, ["lead-vehicle", "speed-change"]),
        entities=entities,
        init=init,
        stories=(parts.story("Lead", "Lead", [slow, resume]),),
    )
    check_reach(blueprint, "Ego", EGO_START, speed)
    check_reach(blueprint, "Lead", EGO_START + gap + parts.CAR_LENGTH, speed)
    return blueprint


def hard_braking(
    *,
    road: roads.RoadNet,
    speed: float,
    thw: float,
    decel: float,
    duration: float = 20.0,
    brake_at: float = 3.0,
) -> Blueprint:
    """Lead at the ego's speed `thw` s ahead brakes to a standstill at `decel` m/s^2."""
    gap = headway_gap(speed, thw)
    entities, init = _lead_pair(road)
    brake = parts.event(
        "LeadBrakes",
        [parts.speed_rate(0, "$LeadDecel")],
        parts.at_time("LeadBrakesStart", brake_at),
    )
    blueprint = Blueprint(
        category="hard-braking",
        road=road,
        stem=f"hard-braking_{SHORT[road.name]}_v{number(speed)}_thw{number(thw)}_d{number(decel)}",
        description=f"Lead {number(thw)} s ahead of the ego at {number(speed)} m/s brakes "
        f"to a standstill at {number(decel)} m/s2",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", EGO_START),
            ("LeadSpeed", speed),
            ("Gap", gap),
            ("LeadDecel", decel),
        ),
        duration=duration,
        tags=tags_for("hard-braking", road, speed, ["lead-vehicle", "emergency-braking"]),
        entities=entities,
        init=init,
        stories=(parts.story("Lead", "Lead", [brake]),),
    )
    check_reach(blueprint, "Ego", EGO_START, speed)
    return blueprint


def cut_out(
    *,
    speed: float,
    ttc: float,
    obstacle_speed: float,
    duration: float = 25.0,
    obstacle_ahead: float = 300.0,
) -> Blueprint:
    """Ego follows a lead (1.2 s headway) in the middle lane of the highway; when the lead is
    `ttc` seconds from a stopped or slow vehicle ahead it changes to the left lane in 2 s."""
    road = roads.HIGHWAY
    lane = EGO_LANE[road.name]
    gap = headway_gap(speed, 1.2)
    cut_out_distance = round((speed - obstacle_speed) * ttc, 1)
    entities, init = _lead_pair(road)
    entities.add_scenario_object("Obstacle", parts.car("obstacle_car"))
    parts.init_vehicle(init, "Obstacle", 1, lane, "${$EgoS + $ObstacleAhead}", "$ObstacleSpeed")
    leave = parts.event(
        "LeadCutsOut",
        [parts.lane_change(lane + 1, 2.0)],
        parts.when_close(
            "LeadNearObstacle", "Lead", "Obstacle", "$CutOutDistance", xosc.Rule.lessThan
        ),
    )
    obstacle = "stopped" if obstacle_speed == 0 else "slow"
    blueprint = Blueprint(
        category="cut-out",
        road=road,
        stem=f"cut-out_highway_v{number(speed)}_ttc{number(ttc)}_obst{number(obstacle_speed)}",
        description=f"Lead ahead of the ego at {number(speed)} m/s leaves the lane {number(ttc)} s "
        f"before a {obstacle} vehicle ({number(obstacle_speed)} m/s)",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", EGO_START),
            ("LeadSpeed", speed),
            ("Gap", gap),
            ("ObstacleAhead", obstacle_ahead),
            ("ObstacleSpeed", obstacle_speed),
            ("CutOutDistance", cut_out_distance),
        ),
        duration=duration,
        tags=tags_for("cut-out", road, speed, ["lead-vehicle", f"{obstacle}-obstacle"]),
        entities=entities,
        init=init,
        stories=(parts.story("Lead", "Lead", [leave]),),
    )
    check_reach(blueprint, "Lead", EGO_START + gap + parts.CAR_LENGTH, speed)
    return blueprint
