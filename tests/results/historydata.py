"""A database with a known history: six scenarios over eight campaign runs (both stores).

* ``steady`` passes every run;
* ``nondet`` passed and failed with the same seed, SUT and simulator;
* ``seedy`` always passes with seed 1 and always fails with seed 2 (twice each);
* ``once`` passed with seed 1 and failed with seed 2, each run once (cannot tell yet);
* ``retry`` errored, then passed on attempt 2 in run 8;
* ``regress`` passed under SUT 1.0 and fails under 2.0 (a regression, not a flake).
"""

from __future__ import annotations

import datetime

from simtest_operator import results
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, outcome, scenario

P, F, E = Verdict.PASSED, Verdict.FAILED, Verdict.ERROR
# run number -> (seed, SUT version, {scenario: verdict or (verdicts of attempts)})
RUNS: dict[int, tuple[int, str, dict[str, object]]] = {
    1: (1, "1.0", {"steady": P, "nondet": P, "seedy": P, "once": P, "regress": P, "retry": P}),
    2: (2, "1.0", {"steady": P, "nondet": F, "seedy": F, "once": F, "regress": P, "retry": P}),
    3: (1, "1.0", {"steady": P, "nondet": P, "seedy": P, "regress": P}),
    4: (2, "1.0", {"steady": P, "nondet": P, "seedy": F}),
    5: (1, "2.0", {"steady": P, "regress": F}),
    6: (1, "2.0", {"steady": P, "regress": F}),
    7: (1, "1.0", {"nondet": F}),
    8: (1, "1.0", {"retry": (E, P)}),
}
REQUIREMENTS = {"steady": ("req:UN-R157-5.2.5.2", "highway"), "nondet": ("req:EuroNCAP-CCRs",)}


def started(number: int) -> datetime.datetime:
    """When run ``number`` started (one day apart)."""
    return T0 + datetime.timedelta(days=number)


def fill(store: results.Store) -> dict[int, results.RunKey]:
    """Write the runs; returns their keys."""
    keys = {}
    for number, (seed, sut_version, verdicts) in RUNS.items():
        info = results.CampaignInfo(
            name="nightly", namespace="team-a", started_at=started(number),
            sut_name="idm-driver", sut_version=sut_version, simulator_version="sumo-1.20",
            settings={"seed": seed},
        )  # fmt: skip
        listed = [
            scenario(f"{name}.xosc", tags=REQUIREMENTS.get(name, ()), road="A9.xodr")
            for name in verdicts
        ]
        key = store.begin_campaign(info, scenarios=listed)
        for info_s, name in zip(listed, verdicts, strict=True):
            attempts = verdicts[name]
            sequence = attempts if isinstance(attempts, tuple) else (attempts,)
            for attempt, verdict in enumerate(sequence, start=1):
                store.add_outcome(
                    key, info_s,
                    outcome(info_s.scenario_id, verdict, attempts=attempt,
                            reason="" if verdict is P else f"{verdict.value} in run {number}",
                            metrics={"minTtc": 1.5 + number}),
                    content_hashes={"scenario": info_s.sha256,
                                    "recording": f"{number:064x}"},
                    recorded_at=started(number),
                )  # fmt: skip
        store.finish_campaign(key, finished_at=started(number) + datetime.timedelta(minutes=5),
                              phase="Succeeded")  # fmt: skip
        keys[number] = key
    return keys
