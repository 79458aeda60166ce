"""The pod's ``resultsStored: false`` reaches the ScenarioBatch status and a Warning event.

Covers: the flag is read from single-scenario and warm-worker (``{"results": [...]}``) termination
messages (a missing ``scenarioId`` taking the environment's only id), carried by the result record
through the SimEnvironment and ScenarioBatch status (wire form only when false, so status writes
of stored results do not grow), and a whole campaign on the in-memory cluster ends with the flag
on exactly the unstored scenarios and one ``ResultsNotStored`` Warning per environment, emitted
when its results are folded, with the verdicts unchanged.
"""

from __future__ import annotations

import json

from simtest_operator.operator.actions import Kind
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.render import messages
from simtest_operator.verdicts import Verdict
from tests.operator.fakecluster import FakeCluster, Script, campaign_body, frozen_list


def unstored(text: str, *, default_id: str | None = None) -> frozenset[str]:
    return messages.flagged(text, messages.RESULTS_STORED, False, default_id=default_id)


def test_unstored_ids_from_single_and_warm_worker_messages() -> None:
    single = json.dumps({"verdict": "Passed", "resultsStored": False})
    assert unstored(single, default_id="a.xosc") == {"a.xosc"}
    warm = json.dumps(
        {
            "results": [
                {"scenarioId": "a", "verdict": "Passed", "resultsStored": False},
                {"scenarioId": "b", "verdict": "Failed"},
                {"scenarioId": "c", "verdict": "Passed", "resultsStored": True},
            ]
        }
    )
    assert unstored(warm) == {"a"}
    assert unstored("Traceback (most recent call last)") == frozenset()
    assert unstored('{"results": 3}') == frozenset()


def test_the_flag_is_in_the_wire_form_only_when_false() -> None:
    stored = ResultRecord(id="a", verdict=Verdict.PASSED)
    assert "resultsStored" not in stored.to_wire()
    assert ResultRecord.from_wire(stored.to_wire()).results_stored
    unstored = ResultRecord(id="a", verdict=Verdict.FAILED, results_stored=False)
    assert unstored.to_wire()["resultsStored"] is False
    assert ResultRecord.from_wire(unstored.to_wire()) == unstored


def test_a_campaign_carries_the_flag_into_batch_status_and_warns_once_per_environment() -> None:
    def script(scenario: str, attempt: int) -> Script:
        entry: dict[str, object] = {"scenarioId": scenario, "verdict": "Passed"}
        if scenario == "s001.xosc":
            entry = {**entry, "verdict": "Failed", "reason": "minTTC 0.4 s < 1.0 s"}
        if scenario in ("s001.xosc", "s003.xosc"):
            entry["resultsStored"] = False
        return Script(seconds=2, message=json.dumps(entry))

    cluster = FakeCluster(script=script)
    cluster.start_campaign(campaign_body(batchSize=3), frozen_list(5), batch_size=3)
    cluster.run()
    results = cluster.results()
    assert {k: r["verdict"] for k, r in results.items()} == {
        "s000.xosc": "Passed",
        "s001.xosc": "Failed",
        "s002.xosc": "Passed",
        "s003.xosc": "Passed",
        "s004.xosc": "Passed",
    }
    flagged = {k for k, r in results.items() if "resultsStored" in r}
    assert flagged == {"s001.xosc", "s003.xosc"}
    assert all(results[k]["resultsStored"] is False for k in flagged)
    warnings = [e for e in cluster.events if e.reason == "ResultsNotStored"]
    assert len(warnings) == 2 and all(e.warning and e.kind is Kind.BATCH for e in warnings)
    assert warnings[0].message.startswith("camp-b00000-e001-a1: ")  # names the environment
    assert "s001.xosc" in warnings[0].message and "s003.xosc" in warnings[1].message
    assert warnings[0].name != warnings[1].name  # each on its own batch
    assert cluster.status()["phase"] == "Failed"
