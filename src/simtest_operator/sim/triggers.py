"""Triggers: condition edges, delays, condition groups and triggering-entity rules.

A trigger is an OR over condition groups, a group an AND over conditions (standard, 6.4). Each
condition turns a raw truth value (computed by :mod:`~simtest_operator.sim.condition_checks`)
into its result through

- its **edge**: ``none`` passes the value through; ``rising``/``falling``/``risingOrFalling`` are
  true only in the evaluation where the value changed that way since the previous evaluation (the
  first evaluation sets the reference: a condition already true then is no rising edge; esmini's
  traffic_lights waits for the light to turn green *again*);
- its **delay**: a result that became true at time t is reported at t + delay (every firing is
  queued, so a condition that fires twice within its delay fires twice later).

State lives per condition inside a :class:`TriggerState`, one per storyboard element trigger, and
is reset when the element goes back to standby for another execution.

Files under CARLA ScenarioRunner's rules (:mod:`~simtest_operator.openscenario.rulesets`) are
evaluated as ScenarioRunner does (``level=True``): conditions are level-triggered -- the edge is
not looked at, so a ``rising`` condition already true at its first evaluation fires there -- and
a condition that was true once stays true until its trigger fires (ScenarioRunner's one-shot
conditions), so ``SimulationTime == 0 AND TraveledDistance > 1`` in one group fires once the
entity has moved a metre.
"""

from __future__ import annotations

import collections
from collections.abc import Callable

from simtest_operator.openscenario import model

Truth = tuple[bool, frozenset[str]]
"""A condition's raw value and the triggering entities that satisfied it (for
``selectTriggeringEntities``)."""

RawCondition = Callable[[model.ByEntity | model.ByValue], Truth]
"""Computes a condition body's raw truth now (the engine's condition evaluator)."""

_EPSILON = 1e-9


class _ConditionState:
    __slots__ = ("fire_times", "latched", "previous")

    def __init__(self) -> None:
        self.previous: bool | None = None
        self.latched: Truth | None = None
        self.fire_times: collections.deque[tuple[float, frozenset[str]]] = collections.deque()


class TriggerState:
    """Evaluates one trigger over time, remembering edges and pending delays."""

    __slots__ = ("_level", "_states", "_trigger")

    def __init__(self, trigger: model.Trigger | None, *, level: bool = False) -> None:
        self._trigger = trigger
        self._level = level
        """ScenarioRunner semantics: edges ignored, conditions latch until the trigger fires."""
        self._states: dict[int, _ConditionState] = {}

    @property
    def trigger(self) -> model.Trigger | None:
        return self._trigger

    def reset(self) -> None:
        """Forget edges and pending delays (element back in standby)."""
        self._states.clear()

    def evaluate(self, now: float, raw: RawCondition) -> Truth:
        """Whether the trigger fires at ``now`` and which entities made it fire.

        Every condition is evaluated each call (not short-circuited) so edge and delay state stay
        correct for conditions in groups that are already decided.
        """
        trigger = self._trigger
        if trigger is None:
            return True, frozenset()
        fired = False
        entities: set[str] = set()
        for group in trigger.condition_groups:
            group_true = bool(group.conditions)
            group_entities: set[str] = set()
            for condition in group.conditions:
                value, who = self._condition(now, condition, raw)
                group_true = group_true and value
                group_entities |= who
            if group_true:
                fired = True
                entities |= group_entities
        if fired and self._level:
            for state in self._states.values():
                state.latched = None
        return fired, frozenset(entities)

    def _condition(self, now: float, condition: model.Condition, raw: RawCondition) -> Truth:
        state = self._states.get(id(condition))
        if state is None:
            state = self._states[id(condition)] = _ConditionState()
        truth = self._delayed(now, condition, state, raw)
        if not self._level:
            return truth
        if truth[0]:
            state.latched = truth
        return state.latched or truth

    def _delayed(
        self, now: float, condition: model.Condition, state: _ConditionState, raw: RawCondition
    ) -> Truth:
        value, who = raw(condition.body)
        edge = model.ConditionEdge.NONE if self._level else condition.edge
        if state.previous is None:
            state.previous = value  # the first evaluation has nothing to compare with
        if edge is model.ConditionEdge.NONE:
            result = value
        elif edge is model.ConditionEdge.RISING:
            result = value and not state.previous
        elif edge is model.ConditionEdge.FALLING:
            result = state.previous and not value
        else:
            result = value != state.previous
        state.previous = value
        if condition.delay <= 0.0:
            return result, who if result else frozenset()
        if result:
            state.fire_times.append((now + condition.delay, who))
        if state.fire_times and state.fire_times[0][0] <= now + _EPSILON:
            _, fired_who = state.fire_times.popleft()
            return True, fired_who
        return False, frozenset()
