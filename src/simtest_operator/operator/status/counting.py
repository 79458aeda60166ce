"""Counters of campaigns and batches, and the phase they imply.

Counters count scenarios by where they are; a scenario with a final verdict counts under that
verdict as soon as the verdict is known. The phase of a finished campaign or batch says the worst
thing that happened: ``Cancelled`` (some scenario was skipped by a cancellation) over ``Error``
(some scenario ended Error or Invalid) over ``Failed`` (some Failed or Timeout) over
``Succeeded``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from collections.abc import Set as AbstractSet

from simtest_operator.api.v1alpha1 import Counters
from simtest_operator.operator.batches import Layout, Progress, ScenarioState, State
from simtest_operator.operator.observed import BatchView
from simtest_operator.operator.status.records import ResultRecord
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


def progress_counters(known: Progress) -> dict[str, int]:
    """Counter fields of a whole campaign: the open batches' states counted one by one, the
    closed batches' counters summed, the absent batches' scenarios queued (or skipped)."""
    out = counters(known.explicit.values())
    for key, value in known.closed.items():
        out[key] += value
    absent = known.absent_scenarios
    out["total"] += absent
    out["skipped" if known.skipped_absent else "queued"] += absent
    return out


class Tally:
    """The counters of the closed batches (every result in the status), kept across steps.

    A batch's results are read again only when its resourceVersion changes, and the sum moves
    by the difference, so a step costs one comparison per batch instead of a pass over every
    result of the campaign. One per campaign loop; a fresh one gives the same answers (it only
    has more to read).
    """

    def __init__(self) -> None:
        self._seen: dict[int, tuple[BatchView, dict[str, int] | None]] = {}
        self._open: set[int] = set()
        self._total = dict.fromkeys(COUNTER_KEYS, 0)
        self._shared: dict[tuple[int, ...], dict[str, int]] = {}
        """One counters object per distinct value: most closed batches count alike ("10
        passed"), and a campaign keeps one entry per batch for its whole run."""

    @property
    def open(self) -> AbstractSet[int]:
        """Indices of the batches that are not closed."""
        return self._open

    @property
    def total(self) -> Mapping[str, int]:
        """Counters of every closed batch's scenarios."""
        return self._total

    def counts(self, index: int) -> Mapping[str, int] | None:
        """Counters of one closed batch (None: not closed, or not seen)."""
        seen = self._seen.get(index)
        return seen[1] if seen is not None else None

    def sync(self, batches: Mapping[int, BatchView], layout: Layout) -> Tally:
        """Take in the batches as they are now (returns itself)."""
        for index, batch in batches.items():
            seen = self._seen.get(index)
            if seen is not None and (seen[0] is batch or _same(seen[0], batch)):
                continue  # the cache hands the same view until the object changes
            self._forget(index)
            counts = _closed_counts(batch, layout.positions(index), layout)
            if counts is not None:
                counts = self._shared.setdefault(tuple(counts.values()), counts)
            self._seen[index] = (batch, counts)
            if counts is None:
                self._open.add(index)
            else:
                self._add(counts, 1)
        if len(self._seen) > len(batches):  # some were deleted
            for index in [i for i in self._seen if i not in batches]:
                self._forget(index)
                del self._seen[index]
        return self

    def _forget(self, index: int) -> None:
        seen = self._seen.get(index)
        if seen is None:
            return
        if seen[1] is None:
            self._open.discard(index)
        else:
            self._add(seen[1], -1)

    def _add(self, counts: Mapping[str, int], sign: int) -> None:
        for key, value in counts.items():
            self._total[key] += sign * value


def _same(old: BatchView, new: BatchView) -> bool:
    return old.uid == new.uid and old.resource_version == new.resource_version


def _closed_counts(batch: BatchView, positions: range, layout: Layout) -> dict[str, int] | None:
    """Counters of a batch whose status holds a result for each of its scenarios, else None."""
    if len(batch.results) != len(positions):  # as folding's test for a final status
        return None
    records: dict[str, ResultRecord] = {}
    for record in batch.results:
        records.setdefault(record.id, record)
    out = dict.fromkeys(COUNTER_KEYS, 0)
    for position in positions:
        kept = records.get(layout.ids[position])
        if kept is None:
            return None
        out["total"] += 1
        out[_BY_VERDICT[kept.verdict]] += 1
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
