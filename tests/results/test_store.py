"""The results store against SQLite and a real PostgreSQL (same tests, both backends).

Covers: a campaign's round trip (campaign, frozen list, outcomes with metrics, artifacts, versions,
hashes, finish); idempotent ``add_outcome`` per scenario+attempt (re-recording replaces, never
duplicates); retries keep every attempt but report the last; resuming with the same run key or the
same campaign info; non-finite metrics; outcomes for scenarios outside the frozen list; newest-first
campaign listing; comparison of two runs inside one store; and the errors for unknown runs, naive
timestamps, a run key of another campaign and a mismatched outcome.
"""

from __future__ import annotations

import datetime
import math

import pytest

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, campaign, outcome, scenario


def test_round_trip_of_a_finished_campaign(store: results.Store) -> None:
    listed = [scenario("cut-in/a.xosc", tags=("highway", "night"), road="A9.xodr"),
              scenario("ped/b.xosc", category="pedestrian")]  # fmt: skip
    key = store.begin_campaign(campaign(), scenarios=listed)
    failing = outcome(
        "cut-in/a.xosc",
        Verdict.FAILED,
        reason="minTTC 0.8 s < 1.5 s at t=12.3 s",
        metrics={"minTTC": 0.8, "maxDecel": 6.5},
        simulated_seconds=20.0,
        wall_seconds=0.4,
        artifacts={"recording": "cut-in/a/recording.mcap", "log": "cut-in/a/log.txt"},
        ignored_elements=("EnvironmentAction",),
        versions={"simulator": "sumo-1.20", "sut": "1.4.0"},
    )
    store.add_outcome(key, listed[0], failing, content_hashes={"scenario": listed[0].sha256,
                                                               "recording": "cd" * 32})  # fmt: skip
    store.add_outcome(key, listed[1], outcome("ped/b.xosc"))
    store.finish_campaign(key, finished_at=T0 + datetime.timedelta(minutes=3), phase="Failed")

    record = store.campaign(key)
    assert record is not None
    assert record.info == campaign()
    assert record.finished_at == T0 + datetime.timedelta(minutes=3)
    assert record.phase == "Failed"
    assert store.scenarios(key) == tuple(listed)
    stored = {s.scenario.scenario_id: s for s in store.outcomes(key)}
    assert stored["cut-in/a.xosc"].outcome == failing
    assert stored["cut-in/a.xosc"].scenario == listed[0]
    assert stored["cut-in/a.xosc"].content_hashes == {"scenario": listed[0].sha256,
                                                      "recording": "cd" * 32}  # fmt: skip
    assert stored["ped/b.xosc"].content_hashes == {"scenario": listed[1].sha256}
    assert stored["ped/b.xosc"].recorded_at == T0


def test_recording_an_attempt_twice_replaces_it(store: results.Store) -> None:
    s = scenario("a.xosc")
    key = store.begin_campaign(campaign(), scenarios=[s])
    store.add_outcome(key, s, outcome("a.xosc", Verdict.FAILED, metrics={"minTTC": 0.5, "x": 1}))
    store.add_outcome(key, s, outcome("a.xosc", Verdict.PASSED, metrics={"minTTC": 2.0}))
    every = store.outcomes(key, final_only=False)
    assert len(every) == 1
    assert every[0].verdict is Verdict.PASSED
    assert every[0].outcome.metrics == {"minTTC": 2.0}


def test_retries_keep_every_attempt_and_report_the_last(store: results.Store) -> None:
    s = scenario("a.xosc")
    key = store.begin_campaign(campaign(), scenarios=[s])
    store.add_outcome(key, s, outcome("a.xosc", Verdict.ERROR, reason="pod lost", attempts=1))
    store.add_outcome(key, s, outcome("a.xosc", Verdict.PASSED, attempts=2))
    attempts = store.outcomes(key, final_only=False)
    assert [o.verdict for o in attempts] == [Verdict.ERROR, Verdict.PASSED]
    (final,) = store.outcomes(key)
    assert (final.verdict, final.outcome.attempts) == (Verdict.PASSED, 2)


def test_beginning_again_resumes_the_run(store: results.Store) -> None:
    first, second = scenario("a.xosc"), scenario("b.xosc")
    key = store.begin_campaign(campaign(), scenarios=[first])
    store.add_outcome(key, first, outcome("a.xosc"))
    assert store.begin_campaign(campaign(), scenarios=[first, second]) == key
    assert store.begin_campaign(campaign(), run_key=key) == key
    assert len(store.campaigns()) == 1
    assert store.scenarios(key) == (first, second)
    assert len(store.outcomes(key)) == 1


def test_a_run_key_of_another_campaign_is_refused(store: results.Store) -> None:
    key = store.begin_campaign(campaign("smoke"))
    with pytest.raises(ResultsError, match="belongs to campaign 'smoke'"):
        store.begin_campaign(campaign("nightly"), run_key=key)


def test_non_finite_metrics_survive(store: results.Store) -> None:
    s = scenario("a.xosc")
    key = store.begin_campaign(campaign(), scenarios=[s])
    metrics = {"minTTC": math.inf, "minTHW": -math.inf, "maxDecel": math.nan}
    store.add_outcome(key, s, outcome("a.xosc", metrics=metrics))
    (stored,) = store.outcomes(key)
    assert stored.outcome.metrics["minTTC"] == math.inf
    assert stored.outcome.metrics["minTHW"] == -math.inf
    assert math.isnan(stored.outcome.metrics["maxDecel"])


def test_an_outcome_outside_the_frozen_list_joins_it(store: results.Store) -> None:
    listed, extra = scenario("a.xosc"), scenario("z.xosc")
    key = store.begin_campaign(campaign(), scenarios=[listed])
    store.add_outcome(key, extra, outcome("z.xosc", Verdict.INVALID, reason="no <Storyboard>"))
    assert store.scenarios(key) == (listed, extra)


def test_campaigns_are_listed_newest_first(store: results.Store) -> None:
    older = store.begin_campaign(campaign(started_at=T0))
    newer = store.begin_campaign(campaign(started_at=T0 + datetime.timedelta(seconds=1.5)))
    other = store.begin_campaign(campaign("nightly", started_at=T0 + datetime.timedelta(hours=1)))
    assert [c.run_key for c in store.campaigns()] == [other, newer, older]
    assert [c.run_key for c in store.campaigns(name="smoke")] == [newer, older]
    assert [c.run_key for c in store.campaigns(name="smoke", limit=1)] == [newer]
    assert store.campaigns(namespace="elsewhere") == ()
    unfinished = store.campaign(newer)
    assert unfinished is not None
    assert not unfinished.finished


def test_compare_two_runs_in_one_store(store: results.Store) -> None:
    names = ["fixed.xosc", "regressed.xosc", "still.xosc", "removed.xosc", "new.xosc", "ok.xosc"]
    s = {n: scenario(n) for n in names}
    base = store.begin_campaign(campaign(started_at=T0))
    other = store.begin_campaign(campaign(started_at=T0 + datetime.timedelta(days=1)))
    for name, verdict in [("fixed.xosc", Verdict.FAILED), ("regressed.xosc", Verdict.PASSED),
                          ("still.xosc", Verdict.TIMEOUT), ("removed.xosc", Verdict.PASSED),
                          ("ok.xosc", Verdict.PASSED)]:  # fmt: skip
        store.add_outcome(base, s[name], outcome(name, verdict))
    for name, verdict in [("fixed.xosc", Verdict.PASSED), ("regressed.xosc", Verdict.FAILED),
                          ("still.xosc", Verdict.FAILED), ("new.xosc", Verdict.ERROR),
                          ("ok.xosc", Verdict.PASSED)]:  # fmt: skip
        store.add_outcome(other, s[name], outcome(name, verdict))
    comparison = store.compare(base, other)
    by_id = {c.scenario_id: c.change for c in comparison.changes}
    assert by_id == {
        "fixed.xosc": results.Change.FIXED,
        "regressed.xosc": results.Change.REGRESSED,
        "still.xosc": results.Change.STILL_FAILING,
        "removed.xosc": results.Change.REMOVED,
        "new.xosc": results.Change.NEW,
        "ok.xosc": results.Change.UNCHANGED,
    }
    assert comparison.base == base


def test_errors_name_the_problem(store: results.Store) -> None:
    s = scenario("a.xosc")
    with pytest.raises(ResultsError, match="unknown campaign run"):
        store.add_outcome(results.RunKey("nope"), s, outcome("a.xosc"))
    with pytest.raises(ResultsError, match="unknown campaign run"):
        store.finish_campaign(results.RunKey("nope"), finished_at=T0, phase="Failed")
    with pytest.raises(ResultsError, match="timezone-aware"):
        store.begin_campaign(campaign(started_at=datetime.datetime(2025, 1, 1)))
    key = store.begin_campaign(campaign())
    with pytest.raises(ResultsError, match=r"outcome of 'b\.xosc' given for scenario 'a\.xosc'"):
        store.add_outcome(key, s, outcome("b.xosc"))
    assert store.outcomes(key) == ()
