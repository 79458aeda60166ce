"""ScenarioRunner's condition rule for ``CARLA:`` files (``TriggerState(level=True)``): edges are
not looked at (a rising condition already true at its first evaluation fires there, where
esmini's rule does not), a condition that was true once stays true until its trigger fires (one-
shot), the latch is cleared when the trigger fires and on reset; a delay is a wait before the
first check (ScenarioRunner's TimeOut ahead of the atomic), not a postponed firing; a
SimulationTimeCondition counts from its own first check, a TraveledDistanceCondition likewise
(strictly more); an act StopTrigger's group holds on any one condition. The stand-in conditions
are StoryboardElementState conditions whose values the test dictates."""

from __future__ import annotations

from collections.abc import Sequence

from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import Conditions, compare
from simtest_operator.sim.triggers import TriggerState
from tests.sim import builders as b
from tests.sim.worlds import Bench, lane, teleport


def stand_in(**kw: object) -> model.Condition:
    """A condition whose value :func:`run` dictates (the body itself is never computed)."""
    return b.state("event", "any", "completeState", **kw)


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
    trigger = b.trigger((stand_in(edge="rising"),))
    values = [[True, True, False]]
    assert run(trigger, values, level=True) == [True, True, False]
    assert run(trigger, values, level=False) == [False, False, False]


def test_one_shot_conditions_in_a_group() -> None:
    # SimulationTime == 0 (true only at first) AND TraveledDistance > 1 (true from step 3).
    trigger = b.trigger((stand_in(edge="rising", name="t0"), stand_in(edge="rising", name="moved")))
    at_start = [True, False, False, False, False]
    moved = [False, False, False, True, True]
    assert run(trigger, [at_start, moved], level=True) == [False, False, False, True, False]
    # esmini: no rising edge of t0 ever, the group never holds.
    assert run(trigger, [at_start, moved], level=False) == [False] * 5


def test_latch_cleared_when_the_trigger_fires_and_on_reset() -> None:
    trigger = b.trigger((stand_in(name="a"), stand_in(name="b")))
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


def test_a_delay_waits_before_the_first_check() -> None:
    # ScenarioRunner: checked from t=2 on, so a value true only at t=0 is never seen; esmini
    # reports the t=0 edge two seconds later.
    trigger = b.trigger((stand_in(edge="rising", delay=2.0),))
    assert run(trigger, [[True, False, False, False]], level=True) == [False] * 4
    assert run(trigger, [[False, True, False, False]], level=False) == [False, False, False, True]
    # From its first check on, the level is read at once (no second wait).
    assert run(trigger, [[False, False, False, True, True]], level=True) == [
        False,
        False,
        False,
        True,
        True,
    ]


def _timed(
    trigger: model.Trigger, times: Sequence[float], *, any_condition: bool = False
) -> list[bool]:
    """Evaluate ``trigger`` at ``times`` with real SimulationTimeConditions (absolute time)."""
    state = TriggerState(trigger, level=True, any_condition=any_condition)
    out = []
    for now in times:

        def raw(
            body: model.ByEntity | model.ByValue, now: float = now
        ) -> tuple[bool, frozenset[str]]:
            assert isinstance(body, model.ByValue)
            condition = body.condition
            assert isinstance(condition, model.SimulationTimeCondition)
            return compare(now, condition.rule, condition.value), frozenset()

        out.append(state.evaluate(now, raw)[0])
    return out


def test_simulation_time_counts_from_the_first_check() -> None:
    # First checked at t=5 (say, when its act started): "> 2" holds from t=7.5 on, not at once.
    trigger = b.trigger((b.sim_time(2.0),))
    assert _timed(trigger, [5.0, 6.0, 7.0, 7.5]) == [False, False, False, True]
    # "== 0" holds at the first check, whenever that is.
    assert _timed(b.trigger((b.sim_time(0.0, "equalTo"),)), [5.0]) == [True]
    # With a delay the clock starts when the wait is over.
    delayed = b.trigger((b.sim_time(1.0, delay=2.0),))
    assert _timed(delayed, [0.0, 1.0, 2.0, 3.0, 3.5]) == [False, False, False, False, True]


def test_an_act_stop_trigger_group_holds_on_any_condition() -> None:
    group = (b.sim_time(1.0), b.sim_time(100.0))
    assert _timed(b.trigger(group), [0.0, 2.0]) == [False, False]
    assert _timed(b.trigger(group), [0.0, 2.0], any_condition=True) == [False, True]


def test_traveled_distance_counts_from_the_first_check() -> None:
    # ScenarioRunner's DriveDistance: metres since the condition's first check, strictly more.
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.world.refresh()
    car = bench.actor("Car")
    condition = model.TraveledDistanceCondition(value=10.0)
    body = model.ByEntity(
        triggering_entities=("Car",), rule=model.TriggeringEntitiesRule.ANY, condition=condition
    )
    esmini = Conditions(bench.world, lambda *args: False)
    carla = Conditions(bench.world, lambda *args: False, scenario_runner=True)
    dt = bench.world.dt
    car.odometer = 50.0  # driven before the condition's first check (say, before its act)
    assert esmini(body)[0] is True
    assert carla(body)[0] is False
    for k, (odometer, expected) in enumerate(((55.0, False), (60.0, False), (60.5, True)), 1):
        bench.world.time = k * dt
        car.odometer = odometer
        assert carla(body)[0] is expected, odometer
