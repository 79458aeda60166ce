"""Base-scenario decomposition: cut a recorded run into interpretable interactions.

Following the scenario.center concept of the seed paper's a-posteriori evaluation, a run is
decomposed into base scenarios -- free driving, following, approaching, cut-in, cut-out, lane
change (of another actor between other lanes), crossing (turning or crossing paths at a junction)
and VRU (a pedestrian or cyclist) -- each with the actor it concerns and a time window, so that
metrics and thresholds can be chosen per situation.

Every other object is located relative to the ego's own driven path (arc length, signed lateral
offset, heading relative to the path): a lead is a same-direction object whose centre lies
within half a lane of that path ahead of the ego. That is omega-prime's curvilinear projection
onto the ego path, without the map: the recordings' maps are lane-level OpenDRIVE, but locating
every sample with ``omega_prime.Locator`` costs seconds per run (docs/evaluation.md), and on the
path the ego drove the ego's lane is the one that matters. The consequence: a lane change of the
ego itself is not detected (its path is the reference).
"""

from __future__ import annotations

import dataclasses
import enum
import math

import numpy as np
import numpy.typing as npt

from simtest_operator.evaluation import geometry2d
from simtest_operator.evaluation.scenes import ActorKind, Array, Scene, Track, median

Mask = npt.NDArray[np.bool_]


class Kind(enum.StrEnum):
    """Base-scenario types."""

    FREE_DRIVING = "free-driving"
    FOLLOWING = "following"
    APPROACHING = "approaching"
    CUT_IN = "cut-in"
    CUT_OUT = "cut-out"
    LANE_CHANGE = "lane-change"
    CROSSING = "crossing"
    VRU = "vru"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Parameters:
    """How relations are read from the geometry."""

    lane_width: float = 3.5
    range: float = 100.0
    """Metres ahead within which an object is a lead."""
    same_direction: float = math.radians(30.0)
    crossing_angle: float = math.radians(20.0)
    """Heading difference at the conflict point from which paths cross rather than merge."""
    approach_speed: float = 1.0
    """Closing speed (m/s) from which following becomes approaching."""
    min_following: float = 2.0
    min_approaching: float = 1.0
    min_free_driving: float = 2.0
    lane_change_lookback: float = 3.0
    """Seconds before a cut-in (after a cut-out) in which the actor must have been alongside."""
    conflict_horizon: float = 10.0
    """Seconds within which two paths' occupation must overlap to count as a conflict."""
    before: float = 2.0
    after: float = 3.0
    exact_distance: float = 30.0
    """Metres (bounding-circle gap) below which box distances are computed exactly."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BaseScenario:
    """One interaction: what, with whom, when (ego frame indices ``first..last`` inclusive)."""

    kind: Kind
    actor: int | None
    start: float
    end: float
    first: int
    last: int
    detail: str = ""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Relation:
    """One object seen from the ego, on the ego's frames (NaN/False where it is absent)."""

    track: Track
    present: Mask
    gap: Array
    """Bumper-to-bumper distance along the ego path (positive ahead)."""
    lateral: Array
    heading: Array
    """Object heading relative to the ego path."""
    closing: Array
    """Ego speed minus the object's speed along the path."""
    in_lane: Mask
    """Same direction, centre within half a lane of the ego path (anywhere along it)."""
    in_lane_ahead: Mask
    in_lane_alongside: Mask
    """In the ego's lane, its front ahead of the ego's rear (a cut-in that ends in a
    collision never gets a positive gap)."""
    adjacent: Mask
    unknown: Mask
    """Present, but beyond where the ego path can be trusted: no relation is read there."""
    distance: Array
    """Box-to-box distance."""
    conflict: Conflict | None
    """(ego frame, object frame) where their paths meet closest in time, if within horizon."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Decomposition:
    """A scene cut into base scenarios, with the relations the metrics are computed from."""

    scene: Scene
    relations: tuple[Relation, ...]
    lead_gap: Array
    """Per ego frame, the gap to the nearest lead (NaN without one)."""
    lead_closing: Array
    lead_actor: npt.NDArray[np.int64]
    """Per ego frame, the nearest lead's object id (-1 without one)."""
    base_scenarios: tuple[BaseScenario, ...]


def _runs(mask: Mask) -> list[tuple[int, int]]:
    """(first, last) index of each run of True."""
    if not len(mask):
        return []
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.diff(padded)
    starts = np.nonzero(edges == 1)[0]
    ends = np.nonzero(edges == -1)[0] - 1
    return list(zip(starts.tolist(), ends.tolist(), strict=True))


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Conflict:
    """Where two boxes occupy the same place closest in time (the PET pair), and whether the
    two cross there at an angle anywhere along the shared place."""

    ego_frame: int
    other_frame: int
    angle: float
    """Largest heading difference (radians, 0..pi/2 folded) over all overlapping pairs."""


def _conflict(ego: Track, other: Track, horizon: float) -> Conflict | None:
    """omega-prime's timegap: the time offset at which the two bounding-box polygons overlap,
    with pairs of instants pre-selected by bounding circles and confirmed by a separating-axis
    test."""
    reach = (math.hypot(ego.length, ego.width) + math.hypot(other.length, other.width)) / 2.0
    dx = ego.x[:, None] - other.x[None, :]
    dy = ego.y[:, None] - other.y[None, :]
    dt = np.abs(ego.t[:, None] - other.t[None, :])
    rows, cols = np.nonzero((dx * dx + dy * dy < reach * reach) & (dt <= horizon))
    if not len(rows):
        return None
    ego_boxes = geometry2d.corners(ego.x[rows], ego.y[rows], ego.yaw[rows], ego.length, ego.width)
    other_boxes = geometry2d.corners(
        other.x[cols], other.y[cols], other.yaw[cols], other.length, other.width
    )
    hit = np.nonzero(geometry2d.overlaps(ego_boxes, other_boxes))[0]
    if not len(hit):
        return None
    best = hit[int(np.argmin(dt[rows[hit], cols[hit]]))]
    angles = np.abs(geometry2d.wrap(other.yaw[cols[hit]] - ego.yaw[rows[hit]]))
    folded = np.minimum(angles, np.pi - angles)
    return Conflict(
        ego_frame=int(rows[best]), other_frame=int(cols[best]), angle=float(folded.max())
    )


def relate(
    scene: Scene, other: Track, path: geometry2d.Path, ego_s: Array, params: Parameters
) -> Relation:
    """Where ``other`` is relative to the ego on each ego frame."""
    ego = scene.ego
    n = len(ego.t)
    index = np.searchsorted(ego.t, other.t)
    index = np.clip(index, 0, max(n - 1, 0))
    matched = np.abs(ego.t[index] - other.t) < 1e-6
    frames, samples = index[matched], np.nonzero(matched)[0]
    present = np.zeros(n, dtype=bool)
    present[frames] = True
    unknown = np.zeros(n, dtype=bool)
    gap = np.full(n, np.nan)
    lateral = np.full(n, np.nan)
    heading = np.full(n, np.nan)
    closing = np.full(n, np.nan)
    distance = np.full(n, np.nan)
    if len(samples):
        s, d, tangent = path.project(other.x[samples], other.y[samples])
        rel = geometry2d.wrap(other.yaw[samples] - tangent)
        trusted = s <= path.trusted_end
        unknown[frames[~trusted]] = True
        known, kept = frames[trusted], trusted
        gap[known] = (s - ego_s[frames] - (ego.length + other.length) / 2.0)[kept]
        lateral[known] = d[kept]
        heading[known] = rel[kept]
        along = other.speed[samples] * np.cos(rel)
        closing[known] = (ego.speed[frames] - along)[kept]
        # Exact box distances where they can matter; far apart, the centre distance minus both
        # half diagonals (a lower bound, at most ~3 m short for cars) is enough.
        reach = (math.hypot(ego.length, ego.width) + math.hypot(other.length, other.width)) / 2
        bound = np.hypot(ego.x[frames] - other.x[samples], ego.y[frames] - other.y[samples])
        bound -= reach
        near = bound < params.exact_distance
        distance[frames] = bound
        fn, sn = frames[near], samples[near]
        ego_box = geometry2d.corners(ego.x[fn], ego.y[fn], ego.yaw[fn], ego.length, ego.width)
        other_box = geometry2d.corners(
            other.x[sn], other.y[sn], other.yaw[sn], other.length, other.width
        )
        distance[fn] = geometry2d.box_distance(ego_box, other_box)
    with np.errstate(invalid="ignore"):
        same_direction = np.abs(heading) < params.same_direction
        half = params.lane_width / 2.0
        road_user = other.kind is not ActorKind.PEDESTRIAN
        in_lane = present & road_user & same_direction & (np.abs(lateral) < half)
        in_lane_ahead = in_lane & (gap > 0.0) & (gap < params.range)
        in_lane_alongside = in_lane & (gap > -(ego.length + other.length)) & (gap < params.range)
        adjacent = (
            present
            & road_user
            & same_direction
            & (np.abs(lateral) >= half)
            & (np.abs(lateral) < 3.0 * half)
            & (gap > -(ego.length + other.length))
            & (gap < params.range)
        )
    return Relation(
        track=other,
        present=present,
        gap=gap,
        lateral=lateral,
        heading=heading,
        closing=closing,
        in_lane=in_lane,
        in_lane_ahead=in_lane_ahead,
        in_lane_alongside=in_lane_alongside,
        adjacent=adjacent,
        unknown=unknown,
        distance=distance,
        conflict=_conflict(ego, other, params.conflict_horizon)
        if _may_cross(other, heading, present, params)
        else None,
    )


def _may_cross(other: Track, heading: Array, present: Mask, params: Parameters) -> bool:
    """Whether a conflict could make a crossing or VRU base scenario: a pedestrian or cyclist,
    or an object that is at some point not heading along the ego path (or off its trusted
    part). Objects that only ever drive along the path (leads, cut-ins) need no search."""
    if other.kind.vulnerable:
        return True
    known = heading[present]
    with np.errstate(invalid="ignore"):
        along = np.abs(known) < params.crossing_angle
    return bool(len(known) == 0 or not np.all(along) or np.isnan(known).any())


def _window(t: Array, centre: float, params: Parameters) -> tuple[int, int]:
    first = int(np.searchsorted(t, centre - params.before, side="left"))
    last = int(np.searchsorted(t, centre + params.after, side="right")) - 1
    return max(first, 0), min(max(last, first), len(t) - 1)


def _lane_events(rel: Relation, t: Array, params: Parameters) -> list[BaseScenario]:
    """Cut-ins, cut-outs and lane changes between other lanes of one object."""
    events: list[BaseScenario] = []
    actor = rel.track.object_id
    inside = rel.in_lane_alongside
    lookback = max(1, round(params.lane_change_lookback / max(median(np.diff(t)), 1e-3)))
    for first, last in _runs(inside):
        if first > 0 and rel.adjacent[max(0, first - lookback) : first].any():
            before = rel.lateral[max(0, first - lookback) : first]
            shift = np.nanmax(np.abs(before)) - abs(rel.lateral[first])
            if shift > 1.0:
                a, b = _window(t, float(t[first]), params)
                side = "left" if np.nanmean(before) > 0 else "right"
                events.append(
                    BaseScenario(
                        kind=Kind.CUT_IN, actor=actor, start=float(t[a]), end=float(t[b]),
                        first=a, last=b, detail=f"from the {side}",
                    )
                )  # fmt: skip
        end = last + 1
        if end < len(t) and rel.adjacent[end : end + lookback].any():
            after = rel.lateral[end : end + lookback]
            shift = np.nanmax(np.abs(after)) - abs(rel.lateral[last])
            if shift > 1.0:
                a, b = _window(t, float(t[end]), params)
                side = "left" if np.nanmean(after) > 0 else "right"
                events.append(
                    BaseScenario(
                        kind=Kind.CUT_OUT, actor=actor, start=float(t[a]), end=float(t[b]),
                        first=a, last=b, detail=f"to the {side}",
                    )
                )  # fmt: skip
    for first, _ in _runs(rel.in_lane & ~rel.in_lane_alongside):
        # Into the ego's lane but behind it (e.g. a merge the ego passed): a lane change.
        if (
            first > 0
            and rel.adjacent[max(0, first - lookback) : first].any()
            and not rel.in_lane_alongside[first - 1]
        ):
            a, b = _window(t, float(t[first]), params)
            events.append(
                    BaseScenario(
                        kind=Kind.LANE_CHANGE, actor=actor, start=float(t[a]), end=float(t[b]),
                        first=a, last=b, detail="into the ego's lane behind the ego",
                    )
                )  # fmt: skip
    # Lane changes between lanes that are not the ego's: the lane index must settle (1 s).
    with np.errstate(invalid="ignore"):
        lane = np.where(rel.adjacent, np.round(rel.lateral / params.lane_width), 0.0)
    settle = lookback // 3 or 1
    previous: float | None = None
    for first, last in _runs(rel.adjacent):
        lanes = lane[first : last + 1]
        for k in range(len(lanes)):
            value = float(lanes[k])
            if previous is not None and value != previous and value != 0.0:
                stable = lanes[k : k + settle]
                if len(stable) == settle and np.all(stable == value):
                    a, b = _window(t, float(t[first + k]), params)
                    events.append(
                        BaseScenario(
                            kind=Kind.LANE_CHANGE, actor=actor, start=float(t[a]),
                            end=float(t[b]), first=a, last=b,
                            detail=f"lane {previous:+.0f} to {value:+.0f}",
                        )
                    )  # fmt: skip
                    previous = value
            elif previous is None:
                previous = value
    return events


def _conflict_event(rel: Relation, scene: Scene, params: Parameters) -> BaseScenario | None:
    """A crossing (vehicles whose boxes share a place at an angle) or a VRU interaction."""
    conflict = rel.conflict
    if conflict is None:
        return None
    i, j = conflict.ego_frame, conflict.other_frame
    ego, other = scene.ego, rel.track
    if other.kind.vulnerable:
        kind = Kind.VRU
    elif conflict.angle > params.crossing_angle:
        kind = Kind.CROSSING
    else:
        return None
    angle = math.degrees(conflict.angle)
    t = ego.t
    start = min(float(ego.t[i]), float(other.t[j])) - 2.0 * params.before
    end = max(float(ego.t[i]), float(other.t[j])) + 1.0
    a = max(int(np.searchsorted(t, start, side="left")), 0)
    b = min(int(np.searchsorted(t, end, side="right")) - 1, len(t) - 1)
    return BaseScenario(
        kind=kind, actor=other.object_id, start=float(t[a]), end=float(t[b]), first=a, last=b,
        detail=f"paths meet at up to {angle:.0f} deg",
    )  # fmt: skip


def _lead_segments(
    t: Array, lead_actor: npt.NDArray[np.int64], closing: Array, params: Parameters
) -> list[BaseScenario]:
    """Following and approaching, per nearest lead; short flickers join their neighbours."""
    events: list[BaseScenario] = []
    period = max(median(np.diff(t)), 1e-3) if len(t) > 1 else 0.1
    for actor in sorted(set(lead_actor.tolist()) - {-1}):
        for first, last in _runs(lead_actor == actor):
            with np.errstate(invalid="ignore"):
                approaching = closing[first : last + 1] > params.approach_speed
            labels = approaching.copy()
            # Join runs shorter than min_approaching into the surrounding label.
            short = max(1, round(params.min_approaching / period))
            for a, b in _runs(labels):
                if b - a + 1 < short:
                    labels[a : b + 1] = False
            for a, b in _runs(~labels):
                if b - a + 1 < short and a > 0 and b < len(labels) - 1:
                    labels[a : b + 1] = True
            for flag, kind, minimum in (
                (True, Kind.APPROACHING, params.min_approaching),
                (False, Kind.FOLLOWING, params.min_following),
            ):
                for a, b in _runs(labels == flag):
                    fa, fb = first + a, first + b
                    if t[fb] - t[fa] + period >= minimum:
                        events.append(
                            BaseScenario(
                                kind=kind, actor=actor, start=float(t[fa]), end=float(t[fb]),
                                first=fa, last=fb,
                            )
                        )  # fmt: skip
    return events


def decompose(scene: Scene, params: Parameters | None = None) -> Decomposition:
    """Every base scenario of ``scene``, in time order."""
    params = params or Parameters()
    ego = scene.ego
    t = ego.t
    n = len(t)
    if n < 2:  # nothing happens in one frame (and the quality check says so)
        empty = np.full(n, np.nan)
        return Decomposition(
            scene=scene, relations=(), lead_gap=empty, lead_closing=empty.copy(),
            lead_actor=np.full(n, -1, dtype=np.int64), base_scenarios=(),
        )  # fmt: skip
    path = geometry2d.Path.of(ego.x, ego.y, ego.yaw)
    ego_s = path.arc_of_vertices(ego.x, ego.y)
    relations = tuple(relate(scene, other, path, ego_s, params) for other in scene.others)
    lead_gap = np.full(n, np.nan)
    lead_closing = np.full(n, np.nan)
    lead_actor = np.full(n, -1, dtype=np.int64)
    for rel in relations:
        better = rel.in_lane_ahead & ~(rel.gap >= lead_gap)
        lead_gap[better] = rel.gap[better]
        lead_closing[better] = rel.closing[better]
        lead_actor[better] = rel.track.object_id
    events: list[BaseScenario] = []
    busy = np.zeros(n, dtype=bool)
    for rel in relations:
        lane_events = _lane_events(rel, t, params)
        events += lane_events
        for event in lane_events:
            busy[event.first : event.last + 1] = True
        busy |= rel.unknown | rel.in_lane_alongside
        conflict = _conflict_event(rel, scene, params)
        if conflict is not None:
            events.append(conflict)
            busy[conflict.first : conflict.last + 1] = True
    events += _lead_segments(t, lead_actor, lead_closing, params)
    period = median(np.diff(t)) if n > 1 else 0.1
    for a, b in _runs((lead_actor == -1) & ~busy):
        if t[b] - t[a] + period >= params.min_free_driving:
            events.append(
                BaseScenario(
                    kind=Kind.FREE_DRIVING, actor=None, start=float(t[a]), end=float(t[b]),
                    first=a, last=b,
                )
            )  # fmt: skip
    events.sort(key=lambda e: (e.start, e.kind.value, -1 if e.actor is None else e.actor))
    return Decomposition(
        scene=scene,
        relations=relations,
        lead_gap=lead_gap,
        lead_closing=lead_closing,
        lead_actor=lead_actor,
        base_scenarios=tuple(events),
    )
