"""Batch planning and start order: slices keep list order and indices, the window policy hands
out everything at once, the barrier policy opens a batch only after the previous one is done,
and dropping finished scenarios keeps the original batch indices."""

from __future__ import annotations

import pytest

from simtest_operator.scenarios import Dispatcher, PinnedScenario, StartPolicy, batching


def scenarios(n: int) -> list[PinnedScenario]:
    return [PinnedScenario(id=f"s{i}", source="file:///x", sha256="0" * 64) for i in range(n)]


def test_plan_slices() -> None:
    batches = batching.plan(scenarios(7), batch_size=3)
    assert [b.index for b in batches] == [0, 1, 2]
    assert [[s.id for s in b.scenarios] for b in batches] == [
        ["s0", "s1", "s2"], ["s3", "s4", "s5"], ["s6"],
    ]  # fmt: skip
    assert batching.plan([], batch_size=3) == ()
    with pytest.raises(ValueError, match="at least 1"):
        batching.plan(scenarios(1), batch_size=0)


def test_window_hands_out_everything() -> None:
    dispatcher = Dispatcher(batching.plan(scenarios(5), batch_size=2))
    handed = []
    while (item := dispatcher.next()) is not None:
        handed.append(item)
    assert [(b, s.id) for b, s in handed] == [(0, "s0"), (0, "s1"), (1, "s2"), (1, "s3"), (2, "s4")]
    assert dispatcher.exhausted


def test_barrier_waits_for_the_whole_batch() -> None:
    dispatcher = Dispatcher(batching.plan(scenarios(4), batch_size=2), StartPolicy.BARRIER)
    first = [dispatcher.next(), dispatcher.next()]
    assert [item[1].id for item in first if item] == ["s0", "s1"]
    assert dispatcher.next() is None
    dispatcher.done(0)
    assert dispatcher.next() is None, "one of batch 0 still running"
    dispatcher.done(0)
    nxt = dispatcher.next()
    assert nxt is not None and nxt[1].id == "s2"
    assert not dispatcher.exhausted
    assert dispatcher.next() is not None
    assert dispatcher.exhausted


def test_without_finished_keeps_indices() -> None:
    batches = batching.plan(scenarios(6), batch_size=2)
    remaining = batching.without(batches, {"s0", "s1", "s3"})
    assert [(b.index, [s.id for s in b.scenarios]) for b in remaining] == [
        (1, ["s2"]), (2, ["s4", "s5"]),
    ]  # fmt: skip
