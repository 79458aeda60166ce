"""What the operator keeps per finished scenario stays small.

Covers: the cached views of finished batches, with the loop's tally of them, keep a few objects
per scenario (each verdict once, as its record), not the watch event's decoded status with its
results a second time and a typed status a third (counted objects, not bytes or RSS); a view
that drops the stored results writes them back exactly; the status as stored is kept whole when
its results do not read back exactly; the event rate limiter drops expired entries.
"""

from __future__ import annotations

import asyncio
import datetime
import gc
import json
from collections.abc import Iterable
from types import FunctionType, ModuleType
from typing import Any

from simtest_operator.operator import observed
from simtest_operator.operator.actions import Emit, Kind
from simtest_operator.operator.applying import Applier
from simtest_operator.operator.batches import Layout
from simtest_operator.operator.metrics import Metrics
from simtest_operator.operator.status.counting import Tally
from tests.operator.fakecluster import FakeCluster, campaign_body, frozen_list

BATCH = 10
BATCHES = 8
PER_SCENARIO = 10
"""Objects a finished scenario may keep: its record with what it holds (id, duration, a metric)
and its share of its batch's view and counters: 8.3 here. Views that kept the decoded status
with its results, beside the records and a typed status, and a counters dict per batch kept
13.6."""


def _finished_batches() -> tuple[list[dict[str, Any]], Layout]:
    """The batch objects of a finished campaign, as a watch event decodes them (JSON)."""
    cluster = FakeCluster(nodes={"n0": 3, "n1": 3, "n2": 3})
    frozen = frozen_list(BATCH * BATCHES)
    cluster.start_campaign(campaign_body(batchSize=BATCH), frozen, batch_size=BATCH)
    cluster.run()
    wire = [json.loads(json.dumps(b)) for b in cluster.of(Kind.BATCH)]
    assert all(len(b["status"]["results"]) == BATCH for b in wire)
    layout = Layout(ids=tuple(s.id for s in frozen.scenarios), batch_size=BATCH)
    return sorted(wire, key=lambda b: b["spec"]["index"]), layout


def _reachable(roots: Iterable[object]) -> set[int]:
    """Ids of the objects reachable from ``roots`` (classes, modules and functions are shared
    by every view and not followed)."""
    seen: set[int] = set()
    stack = list(roots)
    while stack:
        obj = stack.pop()
        if id(obj) in seen or isinstance(obj, type | ModuleType | FunctionType):
            continue
        seen.add(id(obj))
        stack.extend(gc.get_referents(obj))
    return seen


def _kept_per_scenario(wire: list[dict[str, Any]], layout: Layout) -> float:
    """Objects each further finished scenario adds to the cached views and the tally."""
    views = {b["spec"]["index"]: observed.batch_view(b) for b in wire}
    del wire[:]  # the decoded events are gone once kopf has indexed them
    tally = Tally().sync(views, layout)
    one = _reachable([views[0], tally.counts(0)])
    everything = _reachable([views, tally])
    shared = len(_reachable([{}, Tally()]))  # the containers themselves
    return (len(everything) - len(one) - shared) / ((len(views) - 1) * BATCH)


def test_a_finished_scenario_keeps_a_few_objects() -> None:
    wire, layout = _finished_batches()
    assert _kept_per_scenario(wire, layout) <= PER_SCENARIO


def test_the_dropped_results_write_back_exactly() -> None:
    wire, _ = _finished_batches()
    for body in wire:
        view = observed.batch_view(body)
        assert "results" not in view.stored_fields
        assert view.status_wire == body["status"]
        assert view.status.phase.value == body["status"]["phase"]
        assert view.scenario_ids == tuple(s["id"] for s in body["spec"]["scenarios"])


def test_results_that_do_not_read_back_exactly_are_kept_as_stored() -> None:
    wire, _ = _finished_batches()
    body = wire[0]
    body["status"]["results"][0]["extra"] = "a newer operator's field"
    view = observed.batch_view(body)
    assert view.status_wire is body["status"]
    assert len(view.results) == BATCH


class _Events:
    """A client that takes events."""

    def __init__(self) -> None:
        self.created: list[str] = []

    async def create(self, kind: str, namespace: str, body: dict[str, Any]) -> dict[str, Any]:
        self.created.append(body["involvedObject"]["name"])
        return body


def test_the_event_limiter_forgets_expired_entries() -> None:
    asyncio.run(_emit_one_per_batch())


async def _emit_one_per_batch() -> None:
    events = _Events()
    applier = Applier(
        client=events,  # type: ignore[arg-type]  # only events are created
        namespace="tests",
        campaign="camp",
        campaign_uid=lambda: "",
        metrics=Metrics(),
        event_interval=10.0,
    )
    start = datetime.datetime(2026, 1, 1, tzinfo=datetime.UTC)
    for i in range(2_000):  # one batch finishes per second, each with one event
        action = Emit(kind=Kind.BATCH, name=f"b{i}", uid="", reason="Succeeded", message="")
        await applier._emit(action, now=start + datetime.timedelta(seconds=i))
    repeat = Emit(kind=Kind.BATCH, name="b1999", uid="", reason="Succeeded", message="")
    await applier._emit(repeat, now=start + datetime.timedelta(seconds=2_000))
    assert len(events.created) == 2_000  # the repeat within the interval is still limited
    assert len(applier._last_event) <= 2 * 256
