"""Comparing two runs without a database (pure function over outcomes).

Covers: each change class (new, removed, fixed, regressed, still failing, unchanged) including
Timeout/Error/Invalid counting as failing and Skipped as not failing; only the final attempt of a
retried scenario counts; a changed file digest is flagged; counts cover every class.
"""

from __future__ import annotations

from simtest_operator import results
from simtest_operator.results import comparing
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import outcome, scenario


def _stored(
    name: str, verdict: Verdict, *, attempt: int = 1, content: str = ""
) -> results.StoredOutcome:
    return results.StoredOutcome(
        scenario=scenario(name, content=content),
        outcome=outcome(name, verdict, attempts=attempt, reason=f"{verdict.value} reason"),
    )


def test_every_change_class() -> None:
    base = [
        _stored("fixed", Verdict.INVALID),
        _stored("regressed", Verdict.SKIPPED),
        _stored("still", Verdict.ERROR),
        _stored("removed", Verdict.FAILED),
        _stored("same", Verdict.PASSED),
    ]
    other = [
        _stored("fixed", Verdict.PASSED),
        _stored("regressed", Verdict.TIMEOUT),
        _stored("still", Verdict.FAILED, content="edited"),
        _stored("new", Verdict.PASSED),
        _stored("same", Verdict.PASSED),
    ]
    comparison = comparing.compare(base, other, base_label="yesterday", other_label="today")
    by_id = {c.scenario_id: c for c in comparison.changes}
    assert [c.scenario_id for c in comparison.changes] == sorted(by_id)
    assert {k: c.change for k, c in by_id.items()} == {
        "fixed": comparing.Change.FIXED,
        "regressed": comparing.Change.REGRESSED,
        "still": comparing.Change.STILL_FAILING,
        "removed": comparing.Change.REMOVED,
        "new": comparing.Change.NEW,
        "same": comparing.Change.UNCHANGED,
    }
    assert by_id["still"].content_changed
    assert not by_id["same"].content_changed
    assert (by_id["regressed"].before, by_id["regressed"].after) == (
        Verdict.SKIPPED,
        Verdict.TIMEOUT,
    )
    assert by_id["regressed"].reason_after == "Timeout reason"
    assert (by_id["new"].before, by_id["removed"].after) == (None, None)
    assert comparison.counts() == dict.fromkeys(comparing.Change, 1)
    assert comparison.of(comparing.Change.FIXED) == (by_id["fixed"],)


def test_only_the_final_attempt_counts() -> None:
    base = [_stored("a", Verdict.PASSED)]
    other = [_stored("a", Verdict.PASSED, attempt=2), _stored("a", Verdict.ERROR, attempt=1)]
    (change,) = comparing.compare(base, other).changes
    assert change.change is comparing.Change.UNCHANGED
    other = [_stored("a", Verdict.ERROR, attempt=3), _stored("a", Verdict.PASSED, attempt=2)]
    (change,) = comparing.compare(base, other).changes
    assert change.change is comparing.Change.REGRESSED
