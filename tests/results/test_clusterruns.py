"""Cluster campaign runs: pods record attempts, the operator finishes the run (SQLite and PG).

Covers: the run key of a TestCampaign (stable, differs per uid, carries the creation time that
:func:`key_time` reads back); a pod's attempt creating a provisional run record and re-recording
without duplicates; ``finish_campaign_run`` creating the record when no pod could, completing a
provisional one (namespace, manifest digest, SUT, settings), appending unlisted scenarios and
storing phase and counters, idempotently; the operator's label-less frozen list never erasing the
tags, category and road a pod read from the file; and a key of another campaign refused.
"""

from __future__ import annotations

import dataclasses
import datetime

import pytest

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, campaign, outcome, scenario

CREATED = datetime.datetime(2025, 3, 1, 11, 59, 30, tzinfo=datetime.UTC)
KEY = results.cluster_run_key(namespace="team-a", name="smoke", uid="uid-1", created=CREATED)


def _finish(**changes: object) -> results.Finish:
    finish = results.Finish(
        phase="Failed",
        counts={"total": 3, "passed": 1, "failed": 1, "errored": 0, "skipped": 0},
        finished_at=T0 + datetime.timedelta(minutes=5),
    )
    return dataclasses.replace(finish, **changes)  # type: ignore[arg-type]


def _bare(s: results.ScenarioInfo) -> results.ScenarioInfo:
    """The scenario as the operator knows it: id, source and digest, no header labels."""
    return results.ScenarioInfo(scenario_id=s.scenario_id, sha256=s.sha256, source=s.source)


def test_the_run_key_is_one_per_campaign_object() -> None:
    again = results.cluster_run_key(namespace="team-a", name="smoke", uid="uid-1", created=CREATED)
    recreated = results.cluster_run_key(
        namespace="team-a", name="smoke", uid="uid-2", created=CREATED
    )
    assert again == KEY
    assert recreated != KEY
    assert KEY.startswith("smoke-20250301T115930Z-")
    assert results.key_time(KEY) == CREATED
    bare = results.cluster_run_key(namespace="team-a", name="smoke", uid="uid-1", created=None)
    assert results.key_time(bare) is None
    assert results.key_time(results.derive_run_key(campaign())) == T0


def test_a_pod_creates_a_provisional_run_and_rewrites_its_attempt(store: results.Store) -> None:
    s = scenario("cut-in/a.xosc", tags=("highway",), road="A9.xodr")
    first = outcome("cut-in/a.xosc", Verdict.PASSED, metrics={"minTTC": 2.5}, attempts=2)
    for _ in range(2):  # a runner that records twice (or a pod retried with the same attempt)
        results.record_pod_attempt(
            store, KEY, campaign="smoke", scenario=s, outcome=first, now=T0, sut_name="idm-driver"
        )
    record = store.campaign(KEY)
    assert record is not None
    assert (record.info.name, record.info.namespace) == ("smoke", "")
    assert record.info.started_at == CREATED  # from the key, not the pod's clock
    assert record.info.sut_name == "idm-driver"
    assert not record.finished
    stored = store.outcomes(KEY, final_only=False)
    assert [(o.scenario.scenario_id, o.outcome.attempts) for o in stored] == [("cut-in/a.xosc", 2)]
    assert stored[0].outcome.metrics == {"minTTC": 2.5}
    assert stored[0].recorded_at == T0


def test_finishing_completes_a_provisional_record_and_lists_what_never_ran(
    store: results.Store,
) -> None:
    ran = scenario("cut-in/a.xosc", tags=("highway",), road="A9.xodr")
    never = scenario("ped/b.xosc", category="pedestrian")
    results.record_pod_attempt(
        store, KEY, campaign="smoke", scenario=ran, outcome=outcome("cut-in/a.xosc"), now=T0
    )
    info = campaign(started_at=CREATED)
    record = results.finish_campaign_run(
        store, KEY, info=info, finish=_finish(), scenarios=[_bare(ran), _bare(never)]
    )
    assert record.info == info
    assert record.phase == "Failed"
    assert record.finished_at == T0 + datetime.timedelta(minutes=5)
    assert record.counts == {"total": 3, "passed": 1, "failed": 1, "errored": 0, "skipped": 0}
    listed = store.scenarios(KEY)
    assert [s.scenario_id for s in listed] == ["cut-in/a.xosc", "ped/b.xosc"]
    assert listed[0] == ran  # the operator's blank labels did not erase the pod's
    assert listed[1].category == results.UNCATEGORIZED  # nobody read that file on this run

    again = results.finish_campaign_run(
        store, KEY, info=info, finish=_finish(), scenarios=[_bare(ran), _bare(never)]
    )
    assert again == record
    assert len(store.scenarios(KEY)) == 2
    assert len(store.outcomes(KEY, final_only=False)) == 1


def test_finishing_without_any_pod_row_creates_the_record(store: results.Store) -> None:
    listed = [scenario("a.xosc"), scenario("b.xosc")]
    results.start_campaign_run(store, KEY, info=campaign(started_at=CREATED), scenarios=listed)
    results.start_campaign_run(store, KEY, info=campaign(started_at=CREATED), scenarios=listed)
    record = results.finish_campaign_run(
        store, KEY, info=campaign(started_at=CREATED), finish=_finish(phase="Cancelled")
    )
    assert record.phase == "Cancelled"
    assert [s.scenario_id for s in store.scenarios(KEY)] == ["a.xosc", "b.xosc"]
    assert store.outcomes(KEY) == ()
    listed_again = store.campaigns(name="smoke")
    assert [r.run_key for r in listed_again] == [KEY]


def test_a_local_run_keeps_empty_counts(store: results.Store) -> None:
    key = store.begin_campaign(campaign())
    store.finish_campaign(key, finished_at=T0, phase="Succeeded")
    record = store.campaign(key)
    assert record is not None
    assert record.counts == {}


def test_a_key_of_another_campaign_is_refused(store: results.Store) -> None:
    results.record_pod_attempt(
        store, KEY, campaign="smoke", scenario=scenario("a.xosc"), outcome=outcome("a.xosc"), now=T0
    )
    with pytest.raises(ResultsError, match="belongs to campaign 'smoke'"):
        results.finish_campaign_run(
            store, KEY, info=campaign("nightly", started_at=CREATED), finish=_finish()
        )
    with pytest.raises(ResultsError, match="belongs to campaign 'smoke'"):
        store.finish_campaign(
            KEY, finished_at=T0, phase="Failed", info=campaign("nightly", started_at=CREATED)
        )
    with pytest.raises(ResultsError, match="unknown campaign run"):
        store.finish_campaign(results.RunKey("nope"), finished_at=T0, phase="Failed", counts={})
