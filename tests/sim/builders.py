"""Terse builders of scenario-model objects for the storyboard and trigger tests."""

from __future__ import annotations

from simtest_operator.openscenario import model


def value(condition: model.ValueCondition, *, edge: str = "none", delay: float = 0.0,
          name: str = "c") -> model.Condition:  # fmt: skip
    return model.Condition(
        name=name,
        delay=delay,
        edge=model.ConditionEdge(edge),
        body=model.ByValue(condition=condition),
    )


def sim_time(threshold: float, rule: str = "greaterThan", **kw: object) -> model.Condition:
    cond = model.SimulationTimeCondition(value=threshold, rule=model.Rule(rule))
    return value(cond, **kw)  # type: ignore[arg-type]


def state(kind: str, ref: str, state_name: str, **kw: object) -> model.Condition:
    cond = model.StoryboardElementStateCondition(
        element_type=model.StoryboardElementType(kind),
        element_ref=ref,
        state=model.StoryboardElementState(state_name),
    )
    return value(cond, **kw)  # type: ignore[arg-type]


def trigger(*groups: tuple[model.Condition, ...]) -> model.Trigger:
    return model.Trigger(condition_groups=tuple(model.ConditionGroup(conditions=g) for g in groups))


def action(name: str, body: model.AnyAction | None = None, *, private: bool = True) -> model.Action:
    return model.Action(
        name=name, body=body or model.IgnoredAction(kind="LightStateAction"), is_private=private
    )


def event(name: str, *actions: model.Action, start: model.Trigger | None = None,
          priority: str = "parallel", max_count: int = 1) -> model.Event:  # fmt: skip
    return model.Event(
        name=name,
        priority=model.Priority(priority),
        maximum_execution_count=max_count,
        actions=actions or (action(f"{name}-action"),),
        start_trigger=start,
    )


def storyboard(*events: model.Event, act_start: model.Trigger | None = None,
               act_stop: model.Trigger | None = None, stop: model.Trigger | None = None,
               actors: tuple[str, ...] = ("Car",), group_max: int = 1,
               select_triggering: bool = False) -> model.Storyboard:  # fmt: skip
    maneuver = model.Maneuver(name="M", events=events)
    group = model.ManeuverGroup(
        name="G",
        maximum_execution_count=group_max,
        maneuvers=(maneuver,),
        actors=model.Actors(select_triggering_entities=select_triggering, entity_refs=actors),
    )
    act = model.Act(
        name="A", maneuver_groups=(group,), start_trigger=act_start, stop_trigger=act_stop
    )
    story = model.Story(name="S", acts=(act,))
    return model.Storyboard(init=model.Init(), stories=(story,), stop_trigger=stop)
