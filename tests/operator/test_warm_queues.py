"""Warm queues (``isolation: Reuse``) sized by guided self-scheduling.

Covers: a queue takes at most the remaining scenarios over the slots, and a batch's rest is split
into equal parts, so the tail evens out (18 scenarios, batch size 9, 3 slots: 5 + 4 | 3 + 2 ...,
where a fixed queue of 8 gave 8 + 1 | 8 + 1 and left two slots idle behind one long queue); a
large campaign still gets full queues; queues never cross a batch; one slot runs a short batch as
one queue (what the warm-pod tests on the real node rely on).
"""

from __future__ import annotations

from simtest_operator.operator.batches import Layout, ScenarioState, Selection, State, select


def _sizes(count: int, *, batch: int, chunk: int, spread: int, free: int) -> list[int]:
    ids = tuple(f"s{i:03d}.xosc" for i in range(count))
    states = [ScenarioState(position=i, id=s, state=State.PENDING) for i, s in enumerate(ids)]
    units = select(
        states,
        Layout(ids=ids, batch_size=batch),
        Selection(
            free_slots=free,
            barrier=False,
            barrier_limit=None,
            in_flight=0,
            chunk=chunk,
            spread=spread,
            suspended=False,
        ),
    )
    assert all(len({p // batch for p in u.positions}) == 1 for u in units), (
        "a queue crossed a batch"
    )
    return [len(u.positions) for u in units]


def test_the_last_queues_shrink_so_the_slots_finish_together() -> None:
    assert _sizes(18, batch=9, chunk=8, spread=3, free=4) == [5, 4, 3, 2]
    assert _sizes(18, batch=9, chunk=8, spread=2, free=3) == [5, 4, 5]
    assert _sizes(18, batch=9, chunk=8, spread=1, free=4) == [5, 4, 5, 4]
    assert _sizes(3, batch=3, chunk=8, spread=1, free=2) == [3]


def test_a_large_campaign_still_gets_full_queues() -> None:
    assert _sizes(2000, batch=200, chunk=8, spread=6, free=7) == [8] * 7


def test_the_tail_goes_one_scenario_per_slot() -> None:
    assert _sizes(3, batch=9, chunk=8, spread=3, free=4) == [1, 1, 1]
    assert _sizes(5, batch=9, chunk=8, spread=3, free=4) == [2, 1, 1, 1]
