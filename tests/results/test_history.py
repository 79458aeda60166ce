"""History and flakiness over a known database, on SQLite and PostgreSQL (``store_target``)."""

from __future__ import annotations

from simtest_operator import results
from simtest_operator.results import history
from simtest_operator.results.querying import ReadOnlyDatabase
from tests.results.historydata import fill, started


def _summaries(target: str) -> dict[str, history.Summary]:
    with results.open_store(target) as store:
        fill(store)
    with ReadOnlyDatabase(target) as db:
        ordered = history.summaries(db)
    assert [s.scenario_id for s in ordered][:2] == ["nondet.xosc", "seedy.xosc"], "flaky first"
    return {s.scenario_id: s for s in ordered}


def test_flakiness_is_classified_by_family(store_target: str) -> None:
    found = _summaries(store_target)
    assert {name: s.flakiness.value for name, s in found.items()} == {
        "nondet.xosc": "nondeterministic",
        "seedy.xosc": "seed-sensitive",
        "once.xosc": "unconfirmed",
        "retry.xosc": "retried",
        "steady.xosc": "stable",
        "regress.xosc": "stable",
    }


def test_counts_first_failure_last_pass(store_target: str) -> None:
    found = _summaries(store_target)
    regress = found["regress.xosc"]
    assert (regress.runs, regress.passed, regress.failing) == (5, 3, 2)
    assert regress.first_failure == started(5)
    assert regress.last_pass == started(3)
    assert regress.last_verdict == "Failed"
    assert regress.pass_rate == 0.6
    steady = found["steady.xosc"]
    assert (steady.runs, steady.first_failure, steady.last_pass) == (6, None, started(6))
    retry = found["retry.xosc"]
    assert (retry.runs, retry.passed, retry.retried_passes, retry.last_verdict) == (
        3,
        3,
        1,
        "Passed",
    )


def test_scenario_history_lists_runs_newest_first(store_target: str) -> None:
    with results.open_store(store_target) as store:
        keys = fill(store)
    with ReadOnlyDatabase(store_target) as db:
        found = history.scenario_history(db, "nondet.xosc")
        missing = history.scenario_history(db, "no/such.xosc")
    assert [e.run_key for e in found.entries] == [keys[7], keys[4], keys[3], keys[2], keys[1]]
    assert [e.verdict for e in found.entries] == ["Failed", "Passed", "Passed", "Failed", "Passed"]
    assert found.entries[0].seed == "1" and found.entries[0].sut == "idm-driver 1.0"
    assert found.entries[0].recording == f"{7:064x}"
    same_seed = next(f for f in found.families if f.seed == "1")
    assert (same_seed.runs, same_seed.passed, same_seed.failed, same_seed.recordings) == (
        3,
        2,
        1,
        3,
    )
    assert found.summary.flakiness is history.Flakiness.NONDETERMINISTIC
    assert missing.entries == () and missing.summary.runs == 0


def test_classify_rules() -> None:
    def family(seed: str | None, passed: int, failed: int, sut: str = "s 1") -> history.Family:
        return history.Family(
            scenario_id="x", sha256="a", sut=sut, simulator="sumo", seed=seed,
            runs=passed + failed, passed=passed, failed=failed, recordings=1,
        )  # fmt: skip

    assert history.classify([]) is history.Flakiness.STABLE
    assert history.classify([family("1", 2, 0), family("2", 0, 2)]).value == "seed-sensitive"
    assert history.classify([family("1", 2, 0), family("2", 0, 1)]).value == "unconfirmed"
    assert history.classify([family(None, 1, 1)]).value == "unconfirmed"
    assert history.classify([family("1", 1, 1), family("2", 0, 2)]).value == "nondeterministic"
    assert history.classify([family("1", 2, 0, "s 1"), family("1", 0, 2, "s 2")]).value == "stable"
    assert history.classify([family("1", 3, 0)], retried_passes=1).value == "retried"
    assert history.Flakiness.NONDETERMINISTIC.flaky and not history.Flakiness.STABLE.flaky


def test_cluster_campaigns_record_their_seed() -> None:
    """Flakiness needs the seed: the operator's campaign record carries it with the settings."""
    from simtest_operator.operator import observed, recording_results

    view = observed.campaign_view({
        "apiVersion": "simtest.dev/v1alpha1", "kind": "TestCampaign",
        "metadata": {"name": "nightly", "namespace": "team-a", "uid": "0b1c"},
        "spec": {"scenarios": {"sources": [{"path": "scenarios"}]},
                 "environment": {"sut": {"name": "idm-driver", "version": "2.0.0"},
                                 "simulator": {"seed": 7}}},
    })  # fmt: skip
    info = recording_results.campaign_info(view, now=started(1))
    assert info.settings["seed"] == 7
