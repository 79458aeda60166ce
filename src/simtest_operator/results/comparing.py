"""Comparing two campaign runs scenario by scenario: what is new, fixed, regressed, still failing.

A pure function over two lists of final outcomes, so it works on runs in one store, in two stores
(two output folders) or on hand-made values in a test. Scenarios are matched by id; a changed
file digest is reported alongside the change class, since a "regression" on an edited scenario
may be the edit's doing.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Iterable, Mapping

from simtest_operator.results import records
from simtest_operator.verdicts import Verdict


class Change(enum.StrEnum):
    """How one scenario's final verdict moved from the base run to the other run."""

    NEW = "new"
    """Only in the other run (a scenario added since the base run)."""
    REMOVED = "removed"
    """Only in the base run."""
    FIXED = "fixed"
    """Failing in the base run, passing now."""
    REGRESSED = "regressed"
    """Passing (or skipped) in the base run, failing now."""
    STILL_FAILING = "still failing"
    """Failing in both runs (the verdict or reason may have changed)."""
    UNCHANGED = "unchanged"
    """Not failing in either run."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioChange:
    """One scenario in a comparison."""

    scenario_id: str
    change: Change
    before: Verdict | None
    after: Verdict | None
    reason_before: str = ""
    reason_after: str = ""
    content_changed: bool = False
    """The scenario file's digest differs between the two runs."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Comparison:
    """All scenarios of both runs, sorted by id, with their change class."""

    base: str
    """Label of the base run (run key or output folder)."""
    other: str
    changes: tuple[ScenarioChange, ...]

    def of(self, change: Change) -> tuple[ScenarioChange, ...]:
        """The scenarios with one change class."""
        return tuple(c for c in self.changes if c.change is change)

    def counts(self) -> Mapping[Change, int]:
        """How many scenarios fall into each change class (every class present)."""
        return {change: len(self.of(change)) for change in Change}


def final_outcomes(
    outcomes: Iterable[records.StoredOutcome],
) -> dict[str, records.StoredOutcome]:
    """The last attempt of each scenario, keyed by scenario id."""
    final: dict[str, records.StoredOutcome] = {}
    for stored in outcomes:
        current = final.get(stored.scenario.scenario_id)
        if current is None or stored.outcome.attempts >= current.outcome.attempts:
            final[stored.scenario.scenario_id] = stored
    return final


def compare(
    base: Iterable[records.StoredOutcome],
    other: Iterable[records.StoredOutcome],
    *,
    base_label: str = "base",
    other_label: str = "other",
) -> Comparison:
    """Classify every scenario of either run; only the final attempt of each counts."""
    before = final_outcomes(base)
    after = final_outcomes(other)
    changes = []
    for scenario_id in sorted(before.keys() | after.keys()):
        a = before.get(scenario_id)
        b = after.get(scenario_id)
        changes.append(
            ScenarioChange(
                scenario_id=scenario_id,
                change=classify(a.verdict if a else None, b.verdict if b else None),
                before=a.verdict if a else None,
                after=b.verdict if b else None,
                reason_before=a.outcome.reason if a else "",
                reason_after=b.outcome.reason if b else "",
                content_changed=bool(a and b and a.scenario.sha256 != b.scenario.sha256),
            )
        )
    return Comparison(base=base_label, other=other_label, changes=tuple(changes))


def classify(before: Verdict | None, after: Verdict | None) -> Change:
    """How one scenario's verdict moved (None: the scenario is not on that side)."""
    if before is None:
        return Change.NEW
    if after is None:
        return Change.REMOVED
    failed_before = records.is_failing(before)
    failed_after = records.is_failing(after)
    if failed_before and failed_after:
        return Change.STILL_FAILING
    if failed_before:
        return Change.FIXED
    if failed_after:
        return Change.REGRESSED
    return Change.UNCHANGED
