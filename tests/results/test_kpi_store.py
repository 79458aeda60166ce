"""Evaluations in the results store (schema v4), against SQLite and a real PostgreSQL.

Covers: an evaluation's round trip (criteria document and digest, evaluated attempts with
evidence, quality, issues, metrics incl. +-inf and NaN, base scenarios with checked and unchecked
metrics, in order); the original ``runs`` rows stay as they were; storing an attempt again
replaces it with its base scenarios; two evaluations of one run, newest first; deleting the run
cascades; and the errors for an unknown run, evaluation or attempt, and a bad evidence value.
"""

from __future__ import annotations

import datetime
import math

import pytest

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.results import evaluations as ev
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, campaign, outcome, scenario


def _info(key: results.RunKey, name: str = "strict", minutes: int = 1) -> ev.EvaluationInfo:
    return ev.EvaluationInfo(
        run_key=key,
        criteria_name=name,
        criteria={"name": name, "baseScenarios": {"cut-in": {"minTTC": 1.2}}},
        created_at=T0 + datetime.timedelta(minutes=minutes),
        versions={"simtest": "0.1.0"},
    )


def _evaluated(scenario_id: str, *, ttc: float = 0.8) -> ev.EvaluatedRun:
    return ev.EvaluatedRun(
        scenario_id=scenario_id,
        attempt=1,
        verdict=Verdict.FAILED,
        reason="cut-in with object 1 at t=2.0-7.0 s: minTTC 0.80 < 1.2",
        evidence="complete",
        quality={"rateHz": 10.0, "temporalCompleteness": 100.0},
        issues=(),
        metrics={"minTTC": ttc, "PET": math.inf, "odd": math.nan},
        base_scenarios=(
            ev.StoredBaseScenario(
                kind="free-driving", actor=None, start=0.0, end=2.0, verdict=Verdict.PASSED,
                metrics={"maxDecel": ev.MetricCheck(value=0.5, threshold=4.0, passed=True),
                         "minTTC": ev.MetricCheck(value=math.inf)},
            ),
            ev.StoredBaseScenario(
                kind="cut-in", actor=1, start=2.0, end=7.0, verdict=Verdict.FAILED,
                reason="minTTC 0.80 < 1.2", detail="from the right",
                metrics={"minTTC": ev.MetricCheck(value=ttc, threshold=1.2, passed=False)},
            ),
        ),
        recording="scenarios/a/recording.mcap",
    )  # fmt: skip


def _run(store: results.Store) -> results.RunKey:
    listed = [scenario("cut-in/a.xosc"), scenario("ped/b.xosc", category="pedestrian")]
    key = store.begin_campaign(campaign(), scenarios=listed)
    store.add_outcome(key, listed[0], outcome("cut-in/a.xosc", Verdict.PASSED, metrics={"x": 1}))
    store.add_outcome(key, listed[1], outcome("ped/b.xosc", Verdict.PASSED))
    return key


def test_an_evaluation_round_trips_and_leaves_the_original_runs(store: results.Store) -> None:
    key = _run(store)
    before = store.outcomes(key)
    evaluation_id = store.begin_evaluation(_info(key))
    assert evaluation_id.startswith("strict-") and key not in evaluation_id
    store.add_evaluated_run(evaluation_id, _evaluated("cut-in/a.xosc"))
    store.finish_evaluation(evaluation_id, finished_at=T0 + datetime.timedelta(minutes=2))
    assert store.outcomes(key) == before
    record = store.evaluation(evaluation_id)
    assert record is not None and record.finished_at == T0 + datetime.timedelta(minutes=2)
    assert record.info.criteria == _info(key).criteria
    assert record.info.criteria_sha256 == _info(key).criteria_sha256
    (stored,) = store.evaluated_runs(evaluation_id)
    expected = _evaluated("cut-in/a.xosc")
    assert stored.metrics["PET"] == math.inf and math.isnan(stored.metrics["odd"])
    assert stored.base_scenarios == expected.base_scenarios
    assert (stored.verdict, stored.reason, stored.evidence, stored.recording) == (
        expected.verdict, expected.reason, expected.evidence, expected.recording,
    )  # fmt: skip
    assert stored.quality == expected.quality


def test_storing_an_attempt_again_replaces_it(store: results.Store) -> None:
    key = _run(store)
    evaluation_id = store.begin_evaluation(_info(key))
    store.add_evaluated_run(evaluation_id, _evaluated("cut-in/a.xosc", ttc=0.8))
    store.add_evaluated_run(
        evaluation_id,
        ev.EvaluatedRun(scenario_id="cut-in/a.xosc", attempt=1, verdict=Verdict.PASSED,
                        reason="", evidence="incomplete", issues=("frame gap",)),
    )  # fmt: skip
    (stored,) = store.evaluated_runs(evaluation_id)
    assert stored.verdict is Verdict.PASSED and stored.base_scenarios == ()
    assert stored.issues == ("frame gap",) and stored.evidence == "incomplete"


def test_a_run_keeps_every_evaluation_newest_first(store: results.Store) -> None:
    key = _run(store)
    first = store.begin_evaluation(_info(key, "default", minutes=1))
    second = store.begin_evaluation(_info(key, "strict", minutes=5))
    assert [e.evaluation_id for e in store.evaluations(key)] == [second, first]
    store.add_evaluated_run(first, _evaluated("cut-in/a.xosc", ttc=2.0))
    store.add_evaluated_run(second, _evaluated("cut-in/a.xosc", ttc=0.8))
    assert store.evaluated_runs(first)[0].metrics["minTTC"] == 2.0
    assert store.evaluated_runs(second)[0].metrics["minTTC"] == 0.8


def test_errors_name_what_is_unknown(store: results.Store) -> None:
    key = _run(store)
    with pytest.raises(ResultsError, match="unknown campaign run 'nope'"):
        store.begin_evaluation(_info(results.RunKey("nope")))
    with pytest.raises(ResultsError, match="unknown evaluation 'x'"):
        store.add_evaluated_run(ev.EvaluationId("x"), _evaluated("cut-in/a.xosc"))
    evaluation_id = store.begin_evaluation(_info(key))
    with pytest.raises(ResultsError, match=r"has no attempt 1 of 'other\.xosc'"):
        store.add_evaluated_run(evaluation_id, _evaluated("other.xosc"))
    bad = ev.EvaluatedRun(
        scenario_id="cut-in/a.xosc", attempt=1, verdict=Verdict.PASSED, reason="", evidence="?"
    )
    with pytest.raises(ResultsError, match="evidence must be one of"):
        store.add_evaluated_run(evaluation_id, bad)
    with pytest.raises(ResultsError, match="timezone-aware"):
        store.finish_evaluation(evaluation_id, finished_at=datetime.datetime(2025, 1, 1))
    assert store.evaluation(ev.EvaluationId("missing")) is None
