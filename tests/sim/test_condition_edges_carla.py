"""ScenarioRunner's condition rule for ``CARLA:`` files (``TriggerState(level=True)``): edges are
not looked at (a rising condition already true at its first evaluation fires there, where esmini's
rule does not), a condition that was true once stays true until its trigger fires (one-shot), the
latch is cleared when the trigger fires and on reset, delays still apply."""

from __future__ import annotations

from collections.abc import Sequence

from simtest_operator.openscenario import model
from simtest_operator.sim.triggers import TriggerState
from tests.sim import builders as b


def run(trigger: model.Trigger, columns: Sequence[Sequence[bool]], *, level: bool) -> list[bool]:
    """Evaluate ``trigger``; condition ``i`` (in document order) reports ``columns[i][k]`` at
    step k (t = k s)."""
    conditions = [c for g in trigger.condition_groups for c in g.conditions]
    index = {id(c.body): i for i, c in enumerate(conditions)}
    state = TriggerState(trigger, level=level)
    out = []
    for k in range(len(columns[0])):

        def raw(body: model.ByEntity | model.ByValue, k: int = k) -> tuple[bool, frozenset[str]]:
            return columns[index[id(body)]][k], frozenset()

        out.append(state.evaluate(float(k), raw)[0])
    return out


def test_rising_true_at_the_first_evaluation_fires_there() -> None:
    trigger = b.trigger((b.sim_time(0, edge="rising"),))
    values = [[True, True, False]]
    assert run(trigger, values, level=True) == [True, True, False]
    assert run(trigger, values, level=False) == [False, False, False]


def test_one_shot_conditions_in_a_group() -> None:
    # SimulationTime == 0 (true only at first) AND TraveledDistance > 1 (true from step 3).
    trigger = b.trigger(
        (b.sim_time(0, edge="rising", name="t0"), b.sim_time(1, edge="rising", name="moved"))
    )
    at_start = [True, False, False, False, False]
    moved = [False, False, False, True, True]
    assert run(trigger, [at_start, moved], level=True) == [False, False, False, True, False]
    # esmini: no rising edge of t0 ever, the group never holds.
    assert run(trigger, [at_start, moved], level=False) == [False] * 5


def test_latch_cleared_when_the_trigger_fires_and_on_reset() -> None:
    trigger = b.trigger((b.sim_time(0, name="a"), b.sim_time(0, name="b")))
    state = TriggerState(trigger, level=True)
    values = {"a": [True, False, False, True], "b": [False, True, True, True]}
    names = {id(c.body): c.name for c in trigger.condition_groups[0].conditions}
    fired = []
    for k in range(4):

        def raw(body: model.ByEntity | model.ByValue, k: int = k) -> tuple[bool, frozenset[str]]:
            return values[names[id(body)]][k], frozenset()

        fired.append(state.evaluate(float(k), raw)[0])
        if k == 1:
            assert fired == [False, True]  # a latched at 0, b true at 1
    # After firing at 1 the latch of a is gone: b alone does not fire at 2; both at 3 do.
    assert fired == [False, True, False, True]
    state.reset()
    assert state.evaluate(4.0, lambda body: (names[id(body)] == "b", frozenset()))[0] is False


def test_delay_applies_to_the_level_rule() -> None:
    trigger = b.trigger((b.sim_time(0, edge="rising", delay=2.0),))
    assert run(trigger, [[True, False, False, False]], level=True) == [False, False, True, False]
