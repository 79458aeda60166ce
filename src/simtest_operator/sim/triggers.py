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
entity has moved a metre. ScenarioRunner builds a condition as an atomic that starts when its
trigger is first checked (``OpenScenarioParser.convert_condition_to_atomic``), so there

- a ``delay`` is a wait before the condition's first check (a ``TimeOut`` ahead of the atomic),
  not a postponement of its firing;
- a ``SimulationTimeCondition`` measures the time since its own first check (its atomic's
  ``initialise``), not since the start of the scenario;
- an act's StopTrigger fires on any one condition of any group (``success_on_all=False``).
"""

from __future__ import annotations

import collections
import dataclasses
from collections.abc import Callable

from simtest_operator.openscenario import model

Truth = tuple[bool, frozenset[str]]
"""A condition's raw value and the triggering entities that satisfied it (for
``selectTriggeringEntities``)."""

RawCondition = Callable[[model.ByEntity | model.ByValue], Truth]
"""Computes a condition body's raw truth now (the engine's condition evaluator)."""

_EPSILON = 1e-9
_Body = model.ByEntity | model.ByValue


class _ConditionState:
    __slots__ = ("body", "fire_times", "first", "latched", "previous")

    def __init__(self) -> None:
        self.previous: bool | None = None
        self.latched: Truth | None = None
        self.fire_times: collections.deque[tuple[float, frozenset[str]]] = collections.deque()
        self.first: float | None = None
        """ScenarioRunner's rules: when the condition was first checked (its atomic started)."""
        self.body: _Body | None = None
        """ScenarioRunner's rules: the body as checked (a SimulationTimeCondition shifted to its
        own start)."""


class TriggerState:
    """Evaluates one trigger over time, remembering edges and pending delays."""

    __slots__ = ("_any", "_level", "_states", "_trigger")

    def __init__(
        self, trigger: model.Trigger | None, *, level: bool = False, any_condition: bool = False
    ) -> None:
        self._trigger = trigger
        self._level = level
        """ScenarioRunner semantics: edges ignored, conditions latch until the trigger fires,
        delays wait before the first check, simulation time counts from the first check."""
        self._any = any_condition
        """A group holds when any of its conditions does (ScenarioRunner's act StopTrigger)."""
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
            values: list[bool] = []
            group_entities: set[str] = set()
            for condition in group.conditions:
                value, who = self._condition(now, condition, raw)
                values.append(value)
                group_entities |= who
            group_true = any(values) if self._any else bool(values) and all(values)
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
        if not self._level:
            return self._delayed(now, condition, state, raw)
        truth = self._started(now, condition, state, raw)
        if truth[0]:
            state.latched = truth
        return state.latched or truth

    def _started(
        self, now: float, condition: model.Condition, state: _ConditionState, raw: RawCondition
    ) -> Truth:
        """ScenarioRunner's reading: wait ``delay`` from the first check, then check the level."""
        if state.first is None:
            state.first = now
        start = state.first + condition.delay
        if now < start - _EPSILON:
            return False, frozenset()
        if state.body is None:
            state.body = _from_start(condition.body, start)
        value, who = raw(state.body)
        return value, who if value else frozenset()

    def _delayed(
        self, now: float, condition: model.Condition, state: _ConditionState, raw: RawCondition
    ) -> Truth:
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


def _from_start(body: _Body, start: float) -> _Body:
    """``body`` with a SimulationTimeCondition counted from ``start`` (ScenarioRunner's atomic
    compares the time since it started); any other body unchanged."""
    condition = body.condition if isinstance(body, model.ByValue) else None
    if isinstance(body, model.ByValue) and isinstance(condition, model.SimulationTimeCondition):
        shifted = dataclasses.replace(condition, value=condition.value + start)
        return dataclasses.replace(body, condition=shifted)
    return body
