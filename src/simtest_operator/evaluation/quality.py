"""Evidence quality: is a recording complete and consistent enough to back a verdict?

A run may only be ``Passed`` on evidence that covers it. Three of omega-prime's qualification
metrics are computed here with its definitions (``temporal_completeness``,
``duplicate_record_rate``, ``data_format_consistency``; tests/evaluation/test_reeval_quality.py
checks the numbers against omega-prime's own functions), on numpy instead of polars: importing
omega-prime costs 4-14 s per process, more than re-simulating the run. omega-prime's
``record_completeness`` and ``attribute_completeness`` are 100 % by construction for a decoded
recording (the reader fills every column), so they are not repeated. The rest are the checks
omega-prime's format needs but does not make (see docs/evaluation.md): frame rate >= 10 Hz, no
frame gaps, a host vehicle in every frame, a map whose reference matches, constant box size and
class per object, positions that agree with the recorded velocities, and a recording that
covers the run's simulated time.

A jump the scenario commands (a teleport, a trajectory's start, a lane change of step shape, a
stop at a road's end, an entity deleted and added) is declared by the simulation and recorded
with the evidence (``simtest.discontinuity`` records); only the frame interval that ends at a
declared jump is excused, and only for its entity, so the same jump undeclared is still caught.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from simtest_operator.evaluation.scenes import ObjectColumns, RecordedColumns, host_id, median
from simtest_operator.geometry import unexplained_displacement
from simtest_operator.snapshots import Discontinuity, JumpCause

_RANGES = {
    "length": (0.0, math.inf, False),
    "width": (0.0, math.inf, False),
    "height": (0.0, math.inf, True),
    "roll": (-math.pi, math.pi, True),
    "pitch": (-math.pi, math.pi, True),
    "yaw": (-math.pi, math.pi, True),
}
"""omega-prime's value checks (column -> low, high, low inclusive); high always inclusive."""
_CHECKED_COLUMNS = 20
"""Columns of omega-prime's ``polars_schema`` that ``data_format_consistency`` counts."""
_SAME_TIME = 1e-6
"""Seconds within which a declared jump's time is a frame's time."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class QualityRules:
    """Thresholds; the defaults are omega-prime's PASS limits and its format's rules."""

    min_rate_hz: float = 10.0
    timing_tolerance: float = 0.05
    """omega-prime ``temporal_completeness``: max RMS of relative frame-period deviation."""
    min_temporal_completeness: float = 100.0
    coverage_tolerance: float = 0.25
    """Seconds the recording may end before the run's simulated time (last partial period)."""
    max_position_error: float = 0.5
    """Metres a position may differ from the previous one moved by a mean of the two frames'
    recorded velocities."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Quality:
    """The metrics and, when the evidence is not sound, why."""

    metrics: Mapping[str, float]
    issues: tuple[str, ...]

    @property
    def complete(self) -> bool:
        return not self.issues

    def incomplete_reason(self) -> str:
        """Why this evidence cannot back a ``Passed`` verdict (the reason of such a run, in
        ``simtest run`` and in ``simtest evaluate`` alike)."""
        return f"evidence incomplete: {'; '.join(self.issues)}"


def _temporal_completeness(objects: Mapping[int, ObjectColumns], period: float) -> list[float]:
    """Per track, the RMS of its frame periods' relative deviation from ``period``
    (omega-prime counts the share of tracks at or under the tolerance)."""
    tracks = [np.diff(np.sort(np.asarray(o.t))) for o in objects.values() if len(o.t) > 1]
    if not tracks or period <= 0.0:
        return []
    return [float(np.sqrt(np.mean(((d - period) / period) ** 2))) for d in tracks]


def _format_consistency(objects: Mapping[int, ObjectColumns]) -> tuple[float, int]:
    """omega-prime's ``data_format_consistency`` (percent valid values) and the invalid count."""
    total = invalid = 0
    for o in objects.values():
        n = len(o.t)
        total += n * _CHECKED_COLUMNS
        for name, (low, high, inclusive) in _RANGES.items():
            values = np.asarray(getattr(o, name), dtype=np.float64)
            above = values >= low if inclusive else values > low
            invalid += int(np.count_nonzero(~(above & (values <= high))))
        types = np.asarray(o.object_type)
        invalid += int(np.count_nonzero((types < 0) | (types > 4)))
        invalid += int(np.count_nonzero(np.asarray(o.t) < 0))
    return (100.0 if total == 0 else 100.0 * (total - invalid) / total), invalid


def _declared_intervals(
    t: npt.NDArray[np.float64], times: Sequence[float]
) -> npt.NDArray[np.bool_]:
    """Per frame interval of a track, whether a declared jump falls in it: after its first
    frame, at or before its second (the frame that first shows the new state)."""
    excused = np.zeros(max(len(t) - 1, 0), dtype=np.bool_)
    for at in times:
        excused |= (t[:-1] + _SAME_TIME < at) & (at <= t[1:] + _SAME_TIME)
    return excused


def _consistency_issues(
    objects: Mapping[int, ObjectColumns], max_error: float, jumps: Sequence[Discontinuity]
) -> list[str]:
    declared: dict[int, list[float]] = {}
    for jump in jumps:
        object_id = jump.entity if jump.object_id is None else jump.object_id
        declared.setdefault(object_id, []).append(jump.time)
    issues = []
    for object_id, o in sorted(objects.items()):
        if len(o.t) < 2:
            continue
        if np.ptp(np.asarray(o.length)) > 1e-6 or np.ptp(np.asarray(o.width)) > 1e-6:
            issues.append(f"object {object_id} changes its box size")
        if len(set(o.object_type)) > 1 or len(set(o.vehicle_type)) > 1:
            issues.append(f"object {object_id} changes its class")
        t = np.asarray(o.t)
        x, y = np.asarray(o.x), np.asarray(o.y)
        vx, vy = np.asarray(o.vx), np.asarray(o.vy)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            issues.append(f"object {object_id} has non-finite positions")
            continue
        error = unexplained_displacement(np.diff(t), np.diff(x), np.diff(y), vx, vy)
        excused = _declared_intervals(t, declared.get(object_id, ()))
        wrong = np.nonzero((error > max_error) & ~excused)[0]
        if len(wrong):
            first = int(wrong[0])
            issues.append(
                f"object {object_id} jumps {error[first]:.2f} m against its velocity "
                f"at t={t[first + 1]:.2f} s"
            )
    return issues


def _host_frames(recorded: RecordedColumns) -> tuple[int, int]:
    """(frames that show the host vehicle, frames due to show it): an ego the scenario deleted
    is not due until it is added again, when it comes back under a fresh OSI id."""
    times = np.asarray(recorded.frame_times, dtype=np.float64)
    hosts = {h for h in recorded.host_ids if h is not None}
    shown = np.zeros(len(times), dtype=np.bool_)
    for h in hosts & recorded.objects.keys():
        shown |= np.isin(times, np.asarray(recorded.objects[h].t, dtype=np.float64))
    entities = {
        j.entity for j in recorded.discontinuities if j.object_id in hosts or j.entity in hosts
    }
    gone = np.zeros(len(times), dtype=np.bool_)
    for entity in entities:
        since: float | None = None
        for jump in sorted(recorded.discontinuities, key=lambda j: j.time):
            if jump.entity != entity:
                continue
            if jump.cause is JumpCause.DELETED and since is None:
                since = jump.time
            elif jump.cause is JumpCause.ADDED and since is not None:
                gone |= (times >= since - _SAME_TIME) & (times < jump.time - _SAME_TIME)
                since = None
        if since is not None:
            gone |= times >= since - _SAME_TIME
    return int(np.count_nonzero(shown & ~gone)), int(np.count_nonzero(~gone))


def _content_issues(
    recorded: RecordedColumns, frames: int, *, map_expected: bool, host_expected: bool
) -> list[str]:
    """A host vehicle in every frame (when the scenario has one: a file of signals only has
    none) and a map whose reference matches (when it has a road network: one without records
    none)."""
    issues = []
    host = host_id(recorded)
    missing_host = sum(1 for h in recorded.host_ids if h is None)
    if not host_expected and host is None:
        pass
    elif host is None or host not in recorded.objects:
        issues.append("no host vehicle (ego) in the recording")
    elif missing_host or len(recorded.objects[host].t) != frames:
        shown, due = _host_frames(recorded)
        if missing_host or shown != due:
            issues.append(f"host vehicle {host} is in {shown} of {due} frames")
    if recorded.map_xml is None:
        if map_expected:
            issues.append("no map (ground_truth_map channel) in the recording")
    elif recorded.map_references and recorded.map_references != {recorded.map_channel_reference}:
        issues.append(
            f"map_reference {sorted(recorded.map_references)} does not match the map channel's "
            f"{recorded.map_channel_reference!r}"
        )
    return issues


def assess(
    recorded: RecordedColumns,
    *,
    simulated_seconds: float,
    rules: QualityRules | None = None,
    map_expected: bool = True,
    host_expected: bool = True,
) -> Quality:
    """Quality metrics of one decoded recording and the issues that make it incomplete;
    ``map_expected`` False: the run had no road network, so no map channel is due;
    ``host_expected`` False: it had no ego, so no host vehicle is."""
    rules = rules or QualityRules()
    issues: list[str] = []
    times = np.asarray(recorded.frame_times, dtype=np.float64)
    metrics: dict[str, float] = {"frames": float(len(times))}
    if len(times) < 2:
        if len(times) == 1 and simulated_seconds <= rules.coverage_tolerance:
            # The run ended before its second frame was due (an empty storyboard): the first
            # frame covers it, as the coverage rule allows.
            single = _content_issues(
                recorded, 1, map_expected=map_expected, host_expected=host_expected
            )
            return Quality(metrics=metrics, issues=tuple(single))
        return Quality(metrics=metrics, issues=("recording has fewer than two frames",))
    periods = np.diff(times)
    period = median(periods)
    metrics["rateHz"] = round(1.0 / period, 3) if period > 0 else 0.0
    if np.any(periods <= 0):
        issues.append("frame timestamps do not increase")
    elif metrics["rateHz"] < rules.min_rate_hz - 1e-9:
        issues.append(f"frame rate {metrics['rateHz']:g} Hz < {rules.min_rate_hz:g} Hz")
    gaps = np.nonzero(periods > 1.5 * period)[0]
    metrics["frameGaps"] = float(len(gaps))
    if len(gaps):
        issues.append(
            f"{len(gaps)} frame gap(s), first after t={times[gaps[0]]:.2f} s "
            f"({periods[gaps[0]]:.2f} s long)"
        )
    metrics["recordedSeconds"] = round(float(times[-1] - times[0]), 4)
    if times[-1] < simulated_seconds - rules.coverage_tolerance:
        issues.append(
            f"recording ends at t={times[-1]:.2f} s, the run simulated {simulated_seconds:.2f} s"
        )
    issues += _content_issues(
        recorded, len(times), map_expected=map_expected, host_expected=host_expected
    )
    rms = _temporal_completeness(recorded.objects, period)
    good = sum(1 for value in rms if value <= rules.timing_tolerance) if rms else 0
    # Without any object (a scenario of signals only) no track can be incomplete.
    metrics["temporalCompleteness"] = (
        100.0 * good / len(rms) if rms else (0.0 if recorded.objects else 100.0)
    )
    if metrics["temporalCompleteness"] < rules.min_temporal_completeness:
        issues.append(
            f"temporal completeness {metrics['temporalCompleteness']:.1f} % "
            f"< {rules.min_temporal_completeness:g} %"
        )
    samples = sum(len(o.t) for o in recorded.objects.values())
    distinct = sum(len(set(o.t)) for o in recorded.objects.values())
    metrics["duplicateRecordRate"] = 100.0 * (samples - distinct) / samples if samples else 0.0
    # omega-prime's validation (stricter than its qualification thresholds) rejects any
    # duplicate (object, time) and any value out of range, so a single one is an issue.
    if samples != distinct:
        issues.append(
            f"{samples - distinct} duplicate (object, time) record(s), duplicate record rate "
            f"{metrics['duplicateRecordRate']:.2f} %"
        )
    metrics["dataFormatConsistency"], invalid = _format_consistency(recorded.objects)
    if invalid:
        issues.append(
            f"{invalid} value(s) out of omega-prime's ranges, data format consistency "
            f"{metrics['dataFormatConsistency']:.2f} %"
        )
    issues += _consistency_issues(
        recorded.objects, rules.max_position_error, recorded.discontinuities
    )
    return Quality(metrics={k: round(v, 4) for k, v in metrics.items()}, issues=tuple(issues))
