"""Templates where another vehicle moves sideways into the ego's lane.

cut-in: a slower vehicle in the right lane changes into the ego's lane close ahead.
lane-change: a faster vehicle overtakes in the left lane, changes into the ego's lane ahead of
    it and then slows down below the ego's speed.
merge: a vehicle on the on-ramp acceleration lane merges into the ego's lane without yielding.

All three run on right-hand traffic roads where the ego drives in lane -2 along +s. Gaps are
free space, bumper to bumper.
"""

from __future__ import annotations

from scenariogeneration import xosc

from libgen import parts, roads
from libgen.blueprints import Blueprint, check_reach, number, tags_for

EGO_LANE = -2
EGO_START = 20.0


def _ego_and(other: str, other_lane: int, other_s: str) -> tuple[xosc.Entities, xosc.Init]:
    entities = xosc.Entities()
    parts.add_ego(entities)
    entities.add_scenario_object(other, parts.car(f"{other.lower()}_car"))
    init = xosc.Init()
    parts.init_ego(init, 1, EGO_LANE, "$EgoS", "$EgoSpeed")
    parts.init_vehicle(init, other, 1, other_lane, other_s, "$TargetSpeed")
    return entities, init


def cut_in(
    *,
    speed: float,
    gap: float,
    dv: float,
    duration: float = 20.0,
    lead_time: float = 3.0,
    lane_change_time: float = 2.5,
) -> Blueprint:
    """Target `dv` m/s slower in the right lane starts ahead so that the ego closes in for
    `lead_time` seconds; when the gap between them is `gap` m it cuts in."""
    road = roads.HIGHWAY
    start_gap = round(gap + dv * lead_time, 1)
    entities, init = _ego_and("Target", EGO_LANE - 1, parts.ahead_of_ego("$StartGap"))
    cut = parts.event(
        "TargetCutsIn",
        [parts.lane_change(EGO_LANE, "$LaneChangeTime")],
        parts.when_close("TargetClose", "Ego", "Target", "$CutInGap", xosc.Rule.lessThan),
    )
    blueprint = Blueprint(
        category="cut-in",
        road=road,
        stem=f"cut-in_highway_v{number(speed)}_gap{number(gap)}_dv{number(dv)}",
        description=f"A vehicle {number(dv)} m/s slower than the ego ({number(speed)} m/s) cuts "
        f"in from the right {number(gap)} m ahead",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", EGO_START),
            ("TargetSpeed", speed - dv),
            ("StartGap", start_gap),
            ("CutInGap", gap),
            ("LaneChangeTime", lane_change_time),
        ),
        duration=duration,
        tags=tags_for("cut-in", road, speed, ["from-right"]),
        entities=entities,
        init=init,
        stories=(parts.story("Target", "Target", [cut]),),
    )
    check_reach(blueprint, "Ego", EGO_START, speed)
    return blueprint


def lane_change(
    *,
    speed: float,
    dv: float,
    gap: float,
    duration: float = 20.0,
    slow_to: float = 5.0,
    decel: float = 3.0,
) -> Blueprint:
    """Target `dv` m/s faster starts 5 m behind the ego in the left lane; once its rear is
    `gap` m ahead of the ego's front it changes into the ego's lane in 3 s, then slows to
    `speed - slow_to` m/s."""
    road = roads.HIGHWAY
    entities, init = _ego_and("Target", EGO_LANE + 1, "${$EgoS - 5}")
    change = parts.event(
        "TargetChangesLane",
        [parts.lane_change(EGO_LANE, 3.0)],
        parts.when_close("TargetAhead", "Ego", "Target", "$ChangeGap", xosc.Rule.greaterThan),
    )
    slow = parts.event(
        "TargetSlowsDown",
        [parts.speed_rate("$TargetLowSpeed", "$TargetDecel")],
        parts.after_event("TargetSlowsDownStart", "TargetChangesLane"),
    )
    blueprint = Blueprint(
        category="lane-change",
        road=road,
        stem=f"lane-change_highway_v{number(speed)}_dv{number(dv)}_gap{number(gap)}",
        description=f"A vehicle {number(dv)} m/s faster than the ego ({number(speed)} m/s) "
        f"overtakes, changes into its lane {number(gap)} m ahead and slows to "
        f"{number(speed - slow_to)} m/s",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", EGO_START),
            ("TargetSpeed", speed + dv),
            ("ChangeGap", gap),
            ("TargetLowSpeed", speed - slow_to),
            ("TargetDecel", decel),
        ),
        duration=duration,
        tags=tags_for("lane-change", road, speed, ["from-left", "overtaking"]),
        entities=entities,
        init=init,
        stories=(parts.story("Target", "Target", [change, slow]),),
    )
    check_reach(blueprint, "Target", EGO_START, speed + dv)
    return blueprint


MERGE_POINT = 240.0
"""s where the merging vehicle starts its lane change (the ramp lane tapers from 300 m)."""

MERGE_LEAD_TIME = 4.0
"""Seconds every vehicle drives before the merge starts."""


def merge(*, speed: float, merger_speed: float, gap: float, duration: float = 20.0) -> Blueprint:
    """Ego in the right through lane; a vehicle in the acceleration lane at `merger_speed`
    merges in front of it without yielding, `gap` m ahead at the moment it starts its 3 s lane
    change, then accelerates by 5 m/s at 1 m/s^2."""
    road = roads.MERGE
    merger_start = round(MERGE_POINT - merger_speed * MERGE_LEAD_TIME, 1)
    ego_start = round(MERGE_POINT - gap - parts.CAR_LENGTH - speed * MERGE_LEAD_TIME, 1)
    if ego_start < 5.0:
        raise ValueError(f"merge v{speed} gap{gap}: the ego would start before the road")
    entities, init = _ego_and("Merger", EGO_LANE - 1, "$MergerS")
    change = parts.event(
        "MergerMerges",
        [parts.lane_change(EGO_LANE, 3.0)],
        parts.after_travel("MergerAtMergePoint", "Merger", "$MergeTravel"),
    )
    speed_up = parts.event(
        "MergerSpeedsUp",
        [parts.speed_rate("$MergerEndSpeed", 1.0)],
        parts.after_event("MergerSpeedsUpStart", "MergerMerges"),
    )
    blueprint = Blueprint(
        category="merge",
        road=road,
        stem=f"merge_onramp_v{number(speed)}_vm{number(merger_speed)}_gap{number(gap)}",
        description=f"A vehicle at {number(merger_speed)} m/s merges from the on-ramp "
        f"{number(gap)} m ahead of the ego ({number(speed)} m/s)",
        parameters=(
            ("EgoSpeed", speed),
            ("EgoS", ego_start),
            ("TargetSpeed", merger_speed),
            ("MergerS", merger_start),
            ("MergeTravel", round(MERGE_POINT - merger_start, 1)),
            ("MergerEndSpeed", merger_speed + 5.0),
        ),
        duration=duration,
        tags=tags_for("merge", road, speed, ["from-right", "forced-merge"]),
        entities=entities,
        init=init,
        stories=(parts.story("Merger", "Merger", [change, speed_up]),),
    )
    check_reach(blueprint, "Ego", ego_start, speed)
    check_reach(blueprint, "Merger", merger_start, merger_speed + 5.0)
    return blueprint
