"""The Init as CARLA ScenarioRunner reads it.

ScenarioRunner builds nothing from the Init's actions: it reads three things out of each entity's
``Private`` elements and ignores the rest (``OpenScenarioConfiguration._get_actor_transform``,
``_get_actor_speed``, ``OpenScenario._create_init_behavior``, ``_initialize_parameters``,
``_create_environment_behavior``):

- the start pose: the *last* ``Position`` element anywhere below the entity's Privates (document
  order: a TeleportAction's, but also an AcquirePositionAction's, a route's waypoints', a
  trajectory's vertices'; the positions inside a route or trajectory position are not searched);
- the start speed: the last ``AbsoluteTargetSpeed`` of a SpeedAction, set at once whatever the
  dynamics (``ChangeActorTargetSpeed(init_speed=True)``); a relative target sets none;
- the controller (``ControllerAction``), handled by the dispatcher as in a story.

Of the global actions it applies the environment (weather, friction) and ParameterActions. A
file written for ScenarioRunner that puts a lane change or a traffic-light state into its Init
gets neither there; running them here would judge a scene ScenarioRunner never builds.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

from simtest_operator.openscenario import model

_KEPT_PRIVATE = (
    model.AssignControllerAction,
    model.ActivateControllerAction,
    model.IgnoredAction,
)
"""Private Init actions that still run: controllers, and what is ignored anyway."""


def scenario_runner_init(init: model.Init) -> tuple[model.Init, tuple[str, ...]]:
    """``init`` reduced to what ScenarioRunner reads, and the actions it leaves out (labels for
    the run's ignored elements)."""
    ignored: list[str] = []
    privates: list[model.PrivateInit] = []
    for entity in dict.fromkeys(private.entity_ref for private in init.private):
        actions = [a for p in init.private if p.entity_ref == entity for a in p.actions]
        kept: list[model.PrivateAction] = []
        position = _last_position(actions)
        if position is not None:
            kept.append(_teleport_to(position, actions))
        speed = _last_absolute_speed(actions)
        if speed is not None:
            kept.append(_at_once(speed))
        for action in actions:
            if isinstance(action, _KEPT_PRIVATE):
                kept.append(action)
            elif not isinstance(action, model.TeleportAction | model.SpeedAction):
                ignored.append(_label(type(action).__name__, entity))
            elif isinstance(action, model.SpeedAction) and isinstance(
                action.target, model.RelativeTargetSpeed
            ):
                ignored.append(_label("SpeedAction to a relative speed", entity))
        privates.append(model.PrivateInit(entity_ref=entity, actions=tuple(kept)))
    global_actions: list[model.GlobalAction] = []
    for global_action in init.global_actions:
        if _global_read(global_action):
            global_actions.append(global_action)
        else:
            ignored.append(_label(type(global_action).__name__, None))
    reduced = dataclasses.replace(
        init, global_actions=tuple(global_actions), private=tuple(privates)
    )
    return reduced, tuple(dict.fromkeys(ignored))


def _label(kind: str, entity: str | None) -> str:
    of = f" of {entity!r}" if entity is not None else ""
    return f"Init {kind}{of} (ScenarioRunner reads only positions, speeds and controllers there)"


def _global_read(action: model.GlobalAction) -> bool:
    if isinstance(action, model.SetValueAction | model.ModifyValueAction):
        return action.scope is model.ValueScope.PARAMETER
    return isinstance(action, model.EnvironmentAction | model.IgnoredAction)


def _positions(node: object) -> Iterator[model.Position]:
    """Every ``position`` below ``node``, in field (document) order."""
    if isinstance(node, tuple):
        for item in node:
            yield from _positions(item)
        return
    if not dataclasses.is_dataclass(node) or isinstance(node, type):
        return
    for field in dataclasses.fields(node):
        value = getattr(node, field.name)
        if field.name == "position":
            yield value
        elif dataclasses.is_dataclass(value) or isinstance(value, tuple):
            yield from _positions(value)


def _last_position(actions: list[model.PrivateAction]) -> model.Position | None:
    found = [
        p for action in actions for p in _positions(action) if not isinstance(p, model.Unsupported)
    ]
    return found[-1] if found else None


def _teleport_to(
    position: model.Position, actions: list[model.PrivateAction]
) -> model.TeleportAction:
    for action in actions:
        if isinstance(action, model.TeleportAction) and action.position is position:
            return action
    return model.TeleportAction(position=position)


def _last_absolute_speed(actions: list[model.PrivateAction]) -> model.SpeedAction | None:
    """The SpeedAction whose absolute target ScenarioRunner starts the entity at (None when
    the last is zero: it then sets no speed)."""
    speeds = [
        a
        for a in actions
        if isinstance(a, model.SpeedAction) and isinstance(a.target, model.AbsoluteTargetSpeed)
    ]
    return speeds[-1] if speeds and speeds[-1].target.value > 0 else None


def _at_once(action: model.SpeedAction) -> model.SpeedAction:
    step = model.TransitionDynamics(
        shape=model.DynamicsShape.STEP, dimension=model.DynamicsDimension.TIME, value=0.0
    )
    return dataclasses.replace(action, dynamics=step)
