"""The cost of a planning step does not grow with the campaign.

Covers: a step of a campaign with 10,000 scenarios and one with 1,000, each with every batch
before the window closed (all results in the status) and the same window running, builds the
same number of scenario states, and with the loop's tally re-reads no unchanged batch (counted
operations, not time); both steps still count every closed scenario in the campaign's status;
the tally moves by the difference when a batch changes and forgets a deleted one.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from simtest_operator.operator import batches, bodies, observed, planning
from simtest_operator.operator.actions import Kind, Plan
from simtest_operator.operator.status import counting
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.render import render_environment
from simtest_operator.verdicts import Verdict
from tests.operator.fakecluster import FakeCluster, campaign_body, frozen_list

BATCH = 10
OPEN = 10
"""Batches at the end of the list that are not closed when the window is measured."""


def _mid_run(count: int) -> FakeCluster:
    """A campaign whose batches are all closed but the last ``OPEN``, then a few steps, so the
    window runs in those."""
    cluster = FakeCluster(nodes={"n0": 3, "n1": 3, "n2": 3})
    frozen = frozen_list(count)
    cluster.start_campaign(campaign_body(batchSize=BATCH), frozen, batch_size=BATCH)
    campaign = cluster.get(Kind.CAMPAIGN, "camp")
    assert campaign is not None
    for index in range(count // BATCH - OPEN):
        scenarios = frozen.scenarios[index * BATCH : (index + 1) * BATCH]
        body: dict[str, Any] = bodies.batch(
            campaign="camp",
            namespace="tests",
            campaign_uid=campaign["metadata"]["uid"],
            index=index,
            scenarios=scenarios,
        )
        verdicts = [Verdict.FAILED if i % 7 == 0 else Verdict.PASSED for i in range(BATCH)]
        body["status"] = {
            "phase": "Failed" if Verdict.FAILED in verdicts else "Succeeded",
            "results": [
                ResultRecord(id=s.id, verdict=v, duration_seconds=1.0).to_wire()
                for s, v in zip(scenarios, verdicts, strict=True)
            ],
        }
        cluster.add(Kind.BATCH, body)
    for _ in range(3):
        cluster.step()
    return cluster


def _measured(cluster: FakeCluster, monkeypatch: pytest.MonkeyPatch) -> tuple[int, int, Plan]:
    """(scenario states built, batches read for their counters) of one step after a first one
    that filled the tally, and that step's plan."""
    tally = counting.Tally()
    inputs = dataclasses.replace(cluster.inputs(), tally=tally)
    cluster.apply(_plan(cluster, inputs))
    built = [0]
    read = [0]
    state_class = batches.ScenarioState
    closed_counts = counting._closed_counts

    def counted_state(**fields: Any) -> batches.ScenarioState:
        built[0] += 1
        return state_class(**fields)

    def counted_read(*args: Any) -> dict[str, int] | None:
        read[0] += 1
        return closed_counts(*args)

    monkeypatch.setattr(batches, "ScenarioState", counted_state)
    monkeypatch.setattr(counting, "_closed_counts", counted_read)
    plan = _plan(cluster, dataclasses.replace(cluster.inputs(), tally=tally))
    monkeypatch.undo()
    return built[0], read[0], plan


def _plan(cluster: FakeCluster, inputs: planning.Inputs) -> Plan:
    return planning.plan(
        inputs,
        config=cluster.config,
        render=lambda request: render_environment(request, cluster.library),
    )


def test_a_step_builds_as_many_states_at_ten_thousand_as_at_one_thousand(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    small_built, small_read, _ = _measured(_mid_run(1_000), monkeypatch)
    large_built, large_read, _ = _measured(_mid_run(10_000), monkeypatch)
    assert small_built == large_built
    assert small_built <= (OPEN + 1) * BATCH  # the open batches' scenarios, no more
    assert small_read == large_read  # only batches whose resourceVersion moved


def test_the_closed_batches_still_count() -> None:
    cluster = _mid_run(1_000)
    closed = 1_000 - OPEN * BATCH
    failed = (closed // BATCH) * len(range(0, BATCH, 7))
    status = cluster.status()
    assert status["total"] == 1_000
    assert status["failed"] == failed
    assert status["passed"] >= closed - failed
    assert status["queued"] + status["running"] <= OPEN * BATCH


def _batch(index: int, verdicts: list[Verdict], version: str) -> observed.BatchView:
    ids = [f"s{index * BATCH + i:03d}.xosc" for i in range(BATCH)]
    return observed.batch_view(
        {
            "metadata": {
                "name": f"camp-b{index:05d}",
                "uid": f"u{index}",
                "resourceVersion": version,
            },
            "spec": {"campaign": "camp", "index": index, "scenarios": [{"id": i} for i in ids]},
            "status": {
                "results": [
                    ResultRecord(id=i, verdict=v).to_wire()
                    for i, v in zip(ids, verdicts, strict=False)
                ]
            },
        }
    )


def test_the_tally_moves_by_the_difference_and_forgets_deleted_batches() -> None:
    layout = batches.Layout(ids=tuple(f"s{i:03d}.xosc" for i in range(3 * BATCH)), batch_size=BATCH)
    tally = counting.Tally()
    passed, failed = [Verdict.PASSED] * BATCH, [Verdict.FAILED] * BATCH
    first = {0: _batch(0, passed, "1"), 1: _batch(1, passed[:4], "1")}
    tally.sync(first, layout)
    assert (tally.total["total"], tally.total["passed"], set(tally.open)) == (10, 10, {1})
    second = {0: first[0], 1: _batch(1, failed, "2"), 2: _batch(2, passed, "1")}
    tally.sync(second, layout)
    assert (tally.total["passed"], tally.total["failed"], set(tally.open)) == (20, 10, set())
    tally.sync({1: second[1]}, layout)  # batches 0 and 2 deleted
    assert (tally.total["total"], tally.total["passed"], tally.counts(0)) == (10, 0, None)
