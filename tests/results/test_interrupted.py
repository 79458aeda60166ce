"""A run killed mid-campaign leaves a consistent results database (SQLite and PostgreSQL).

Covers: an interrupt raised inside ``add_outcome`` after the attempt row was written rolls the
whole attempt back; a real writer process stopped with SIGINT or SIGKILL while recording outcomes
back to back leaves only whole attempts (each with all its metrics), an unfinished campaign, a
sound SQLite file, and a run that can be resumed with the same key.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator, Mapping

import pytest

from simtest_operator import results
from simtest_operator.results import sqlite
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import campaign, outcome, scenario

METRICS_PER_OUTCOME = 40

WRITER = textwrap.dedent(
    """
    import datetime, signal, sys
    # Ctrl-C as a terminal delivers it, whatever the test runner was started with (a shell
    # without job control starts background jobs with SIGINT ignored, and Python keeps that).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    from simtest_operator import results
    from simtest_operator.verdicts import ScenarioOutcome, Verdict

    store = results.open_store(sys.argv[1])
    info = results.CampaignInfo(
        name="killed", started_at=datetime.datetime(2025, 3, 1, tzinfo=datetime.UTC)
    )
    scenarios = [
        results.ScenarioInfo(scenario_id=f"s{i:05d}.xosc", sha256=f"{i:064x}")
        for i in range(100_000)
    ]
    key = store.begin_campaign(info, scenarios=scenarios[:1000])
    print(key, flush=True)
    for i, s in enumerate(scenarios):
        metrics = {f"m{j:02d}": float(i * j) for j in range(int(sys.argv[2]))}
        verdict = Verdict.FAILED if i % 7 == 0 else Verdict.PASSED
        store.add_outcome(key, s, ScenarioOutcome(
            scenario_id=s.scenario_id, verdict=verdict, reason=f"r{i}", metrics=metrics
        ))
        print(i, flush=True)
    """
)


class _InterruptingMetrics(Mapping[str, float]):
    """Metrics whose reading is interrupted, as if Ctrl-C arrived mid-transaction."""

    def __getitem__(self, key: str) -> float:
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        raise KeyboardInterrupt

    def __len__(self) -> int:
        return 1


def test_interrupt_inside_add_outcome_rolls_the_attempt_back(store: results.Store) -> None:
    s = scenario("a.xosc")
    key = store.begin_campaign(campaign(), scenarios=[s])
    store.add_outcome(key, s, outcome("a.xosc", Verdict.ERROR, metrics={"minTTC": 1.0}))
    with pytest.raises(KeyboardInterrupt):
        store.add_outcome(key, s, outcome("a.xosc", Verdict.PASSED, metrics=_InterruptingMetrics()))
    (kept,) = store.outcomes(key, final_only=False)
    assert (kept.verdict, kept.outcome.metrics) == (Verdict.ERROR, {"minTTC": 1.0})
    store.add_outcome(key, s, outcome("a.xosc", Verdict.PASSED))  # the store is still usable
    assert store.outcomes(key)[0].verdict is Verdict.PASSED


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGKILL], ids=["sigint", "sigkill"])
def test_killed_writer_leaves_whole_attempts(store_target: str, stop: signal.Signals) -> None:
    with subprocess.Popen(
        [sys.executable, "-c", WRITER, store_target, str(METRICS_PER_OUTCOME)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    ) as writer:
        try:
            assert writer.stdout is not None
            key = results.RunKey(writer.stdout.readline().strip())
            for _ in range(40):  # let it get well into the campaign
                assert writer.stdout.readline(), writer.stderr.read() if writer.stderr else ""
            writer.send_signal(stop)
            _, stderr = writer.communicate(timeout=60)
        finally:
            writer.kill()
    assert writer.returncode != 0
    if stop is signal.SIGINT:
        assert "KeyboardInterrupt" in stderr

    with results.open_store(store_target) as store:
        if isinstance(store, sqlite.SqliteStore):
            assert store.integrity_problems() == ()
        record = store.campaign(key)
        assert record is not None
        assert not record.finished
        stored = store.outcomes(key, final_only=False)
        assert len(stored) >= 40
        for entry in stored:
            index = int(entry.scenario.scenario_id[1:6])
            assert entry.outcome.reason == f"r{index}"
            assert entry.outcome.metrics == {
                f"m{j:02d}": float(index * j) for j in range(METRICS_PER_OUTCOME)
            }
        done = sorted(int(e.scenario.scenario_id[1:6]) for e in stored)
        assert done == list(range(len(done)))  # written in order, no holes
        assert len(store.scenarios(key)) == max(1000, len(done))
        # Resuming the same run continues where it stopped.
        next_one = results.ScenarioInfo(
            scenario_id=f"s{len(done):05d}.xosc", sha256=f"{len(done):064x}"
        )
        assert store.begin_campaign(record.info, run_key=key) == key
        store.add_outcome(key, next_one, outcome(next_one.scenario_id))
        assert len(store.outcomes(key)) == len(done) + 1
