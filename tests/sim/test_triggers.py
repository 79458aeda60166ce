"""Trigger layer: condition edges (none/rising/falling/risingOrFalling; the first evaluation
only sets the reference, so a condition true from the start is no rising edge), delays (queued
firings), AND within and OR across condition groups, the empty trigger, triggering entities
reported, reset."""

from __future__ import annotations

from simtest_operator.openscenario import model
from simtest_operator.sim.triggers import TriggerState
from tests.sim import builders as b


def run(trigger: model.Trigger, values: list[bool], dt: float = 1.0) -> list[bool]:
    """Evaluate ``trigger`` whose every condition reports values[k] at step k."""
    state = TriggerState(trigger)
    out = []
    for k, v in enumerate(values):
        out.append(
            state.evaluate(k * dt, lambda body, v=v: (v, frozenset({"Car"}) if v else frozenset()))[
                0
            ]
        )
    return out


def test_edges() -> None:
    pattern = [True, True, False, False, True, False]
    assert run(b.trigger((b.sim_time(0, edge="none"),)), pattern) == pattern
    assert run(b.trigger((b.sim_time(0, edge="rising"),)), pattern) == [
        False,
        False,
        False,
        False,
        True,
        False,
    ]
    assert run(b.trigger((b.sim_time(0, edge="falling"),)), pattern) == [
        False,
        False,
        True,
        False,
        False,
        True,
    ]
    assert run(b.trigger((b.sim_time(0, edge="risingOrFalling"),)), pattern) == [
        False,
        False,
        True,
        False,
        True,
        True,
    ]


def test_delay_queues_each_firing() -> None:
    trig = b.trigger((b.sim_time(0, edge="rising", delay=2.0),))
    assert run(trig, [False, True, False, True, False, False, False]) == [
        False,
        False,
        False,
        True,
        False,
        True,
        False,
    ]


def test_groups_and_within_or_across() -> None:
    state = TriggerState(
        b.trigger(
            (b.sim_time(1, name="a"), b.sim_time(2, name="b")),
            (b.sim_time(10, name="c"),),
        )
    )

    def raw_at(now: float):
        def raw(body: model.ByEntity | model.ByValue) -> tuple[bool, frozenset[str]]:
            assert isinstance(body, model.ByValue)
            assert isinstance(body.condition, model.SimulationTimeCondition)
            return now > body.condition.value, frozenset()

        return raw

    assert [state.evaluate(t, raw_at(t))[0] for t in (0.5, 1.5, 2.5, 11.0)] == [
        False,
        False,
        True,
        True,
    ]


def test_empty_and_missing_trigger() -> None:
    assert TriggerState(None).evaluate(0.0, lambda body: (False, frozenset()))[0] is True
    assert (
        TriggerState(model.Trigger(condition_groups=())).evaluate(
            0.0, lambda body: (True, frozenset())
        )[0]
        is False
    )


def test_triggering_entities_and_reset() -> None:
    state = TriggerState(b.trigger((b.sim_time(0, edge="rising"),)))
    assert state.evaluate(0, lambda body: (False, frozenset()))[0] is False
    assert state.evaluate(1, lambda body: (True, frozenset({"A"}))) == (True, frozenset({"A"}))
    assert state.evaluate(2, lambda body: (True, frozenset({"A"})))[0] is False
    state.reset()
    assert state.evaluate(3, lambda body: (True, frozenset({"A"})))[0] is False
    assert state.evaluate(4, lambda body: (False, frozenset()))[0] is False
    assert state.evaluate(5, lambda body: (True, frozenset({"A"})))[0] is True
