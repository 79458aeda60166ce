"""Triggers: condition edges, delays, condition groups and triggering-entity rules.

A trigger is an OR over condition groups, a group an AND over conditions (standard, 6.4). Each
condition turns a raw truth value (computed by :mod:`~simtest_operator.sim.conditions`) into its
result through

- its **edge**: ``none`` passes the value through; ``rising``/``falling``/``risingOrFalling`` are
  true only in the evaluation where the value changed that way since the previous evaluation (the
  first evaluation sets the reference: a condition already true then is no rising edge; esmini's
  traffic_lights waits for the light to turn green *again*);
- its **delay**: a result that became true at time t is reported at t + delay (every firing is
  queued, so a condition that fires twice within its delay fires twice later).

State lives per condition inside a :class:`TriggerState`, one per storyboard element trigger, and
is reset when the element goes back to standby for another execution.
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
    __slots__ = ("fire_times", "previous")

    def __init__(self) -> None:
        self.previous: bool | None = None
        self.fire_times: collections.deque[tuple[float, frozenset[str]]] = collections.deque()


class TriggerState:
    """Evaluates one trigger over time, remembering edges and pending delays."""

    __slots__ = ("_states", "_trigger")

    def __init__(self, trigger: model.Trigger | None) -> None:
        self._trigger = trigger
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
        return fired, frozenset(entities)

    def _condition(self, now: float, condition: model.Condition, raw: RawCondition) -> Truth:
        state = self._states.get(id(condition))
        if state is None:
            state = self._states[id(condition)] = _ConditionState()
        value, who = raw(condition.body)
        edge = condition.edge
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
