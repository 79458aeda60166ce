"""Status documents of campaigns and batches, computed from scenario states.

Counters count scenarios by where they are; a scenario with a final verdict counts under that
verdict as soon as the verdict is known. The phase of a finished campaign or batch says the worst
thing that happened: ``Cancelled`` (some scenario was skipped by a cancellation) over ``Error``
(some scenario ended Error or Invalid) over ``Failed`` (some Failed or Timeout) over
``Succeeded``.
"""

from __future__ import annotations

import datetime
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from simtest_operator.operator import conditions
from simtest_operator.operator.batches import ScenarioState, State
from simtest_operator.verdicts import Verdict

COUNTER_KEYS = (
    "total",
    "queued",
    "running",
    "passed",
    "failed",
    "errored",
    "timedOut",
    "invalid",
    "skipped",
)
_BY_VERDICT = {
    Verdict.PASSED: "passed",
    Verdict.FAILED: "failed",
    Verdict.ERROR: "errored",
    Verdict.TIMEOUT: "timedOut",
    Verdict.INVALID: "invalid",
    Verdict.SKIPPED: "skipped",
}


def counters(states: Iterable[ScenarioState]) -> dict[str, int]:
    """Counter fields (wire names) of a set of scenarios."""
    out = dict.fromkeys(COUNTER_KEYS, 0)
    for state in states:
        out["total"] += 1
        if state.state.final and state.result is not None:
            out[_BY_VERDICT[state.result.verdict]] += 1
        elif state.state is State.RUNNING:
            out["running"] += 1
        else:
            out["queued"] += 1
    return out


def finished_count(counts: Mapping[str, int]) -> int:
    """Scenarios with a final verdict."""
    return counts["total"] - counts["queued"] - counts["running"]


def progress(counts: Mapping[str, int]) -> str:
    """``finished/total``."""
    return f"{finished_count(counts)}/{counts['total']}"


def final_phase(counts: Mapping[str, int]) -> str:
    """Phase of a set of scenarios that all have final verdicts (``Cancelled`` when some were
    skipped: only a cancellation skips scenarios)."""
    if counts["skipped"]:
        return "Cancelled"
    if counts["errored"] or counts["invalid"]:
        return "Error"
    if counts["failed"] or counts["timedOut"]:
        return "Failed"
    return "Succeeded"


def batch_status(
    *,
    states: Sequence[ScenarioState],
    current: Mapping[str, Any],
    now: datetime.datetime,
) -> dict[str, Any]:
    """The whole status of one ScenarioBatch (results only of recorded, durable verdicts)."""
    counts = counters(states)
    done = finished_count(counts) == counts["total"]
    started = any(s.state is not State.PENDING for s in states)
    phase = final_phase(counts) if done else "Running" if started else "Pending"
    results = [
        s.result.to_wire()
        for s in states
        if s.result is not None
        and (s.state is State.FOLDED or (s.state is State.DONE and s.durable))
    ]
    status: dict[str, Any] = {
        **counts,
        "phase": phase,
        "observedGeneration": 1,
        "progress": progress(counts),
        "results": results,
        "startTime": current.get("startTime") or (conditions.rfc3339(now) if started else None),
        "completionTime": current.get("completionTime")
        or (conditions.rfc3339(now) if done and len(results) == counts["total"] else None),
        "conditions": conditions.merge(
            current.get("conditions"),
            [
                conditions.Desired(
                    type="Complete",
                    status=done and len(results) == counts["total"],
                    reason=phase if done else "InProgress",
                    message=f"{progress(counts)} scenarios finished",
                )
            ],
            now=now,
        ),
    }
    return {k: v for k, v in status.items() if v is not None}


def changed_fields(desired: Mapping[str, Any], current: Mapping[str, Any]) -> dict[str, Any]:
    """The top-level fields of ``desired`` that differ from ``current`` (a merge patch)."""
    return {k: v for k, v in desired.items() if current.get(k) != v}


def only_progress(patch: Mapping[str, Any]) -> bool:
    """A patch that changes counters/progress/throughput only (may be deferred and coalesced)."""
    return set(patch) <= {*COUNTER_KEYS, "progress", "throughput", "batches"}
