"""The ScenarioBatch's status: counters, phase and the durable results of its slice."""

from __future__ import annotations

import datetime
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.operator.batches import ScenarioState, State
from simtest_operator.operator.status import conditions, counting


def batch_status(
    *,
    states: Sequence[ScenarioState],
    current: Mapping[str, Any],
    now: datetime.datetime,
) -> dict[str, Any]:
    """The whole status of one ScenarioBatch (results only of recorded, durable verdicts);
    ``current`` is the observed wire status, whose times and conditions carry over."""
    counts = counting.counters(states)
    done = counting.finished_count(counts) == counts["total"]
    started = any(s.state is not State.PENDING for s in states)
    phase = counting.final_phase(counts) if done else "Running" if started else "Pending"
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
        "progress": counting.progress(counts),
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
                    message=f"{counting.progress(counts)} scenarios finished",
                )
            ],
            now=now,
        ),
    }
    return {k: v for k, v in status.items() if v is not None}
