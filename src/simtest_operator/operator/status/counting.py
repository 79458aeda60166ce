"""Counters of campaigns and batches, and the phase they imply.

Counters count scenarios by where they are; a scenario with a final verdict counts under that
verdict as soon as the verdict is known. The phase of a finished campaign or batch says the worst
thing that happened: ``Cancelled`` (some scenario was skipped by a cancellation) over ``Error``
(some scenario ended Error or Invalid) over ``Failed`` (some Failed or Timeout) over
``Succeeded``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from simtest_operator.api.v1alpha1 import Counters
from simtest_operator.operator.batches import ScenarioState, State
from simtest_operator.verdicts import Verdict

COUNTER_KEYS = tuple(str(field.alias) for field in Counters.model_fields.values())
"""The counter fields' wire names, in the schema's order (``total`` ... ``skipped``)."""
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
