"""Which reference player's rules a scenario runs under: OpenSCENARIO as esmini reads it, or CARLA
ScenarioRunner's.

Files are written for one player and rely on its reading of the standard (docs/simulator.md,
"Rule sets"). ScenarioRunner's rules apply to a file that shows it was written for ScenarioRunner
by any of (first match named):

- a FileHeader ``description`` starting with ``CARLA:`` (ScenarioRunner's own marker);
- ``criteria_<Test>`` conditions in a StopTrigger (ScenarioRunner's pass/fail tests);
- a controller whose ``module`` property names one of ScenarioRunner's controller modules
  (``external_control``, ``carla_autopilot``, ...), assigned to an entity or by an action;
- a CARLA town (``Town01``, ``Town10HD``, ...) as the road network's ``LogicFile``.

Every other file runs under OpenSCENARIO's rules, as esmini reads it. CARLA's left-handed
coordinate frame is a separate matter: ScenarioRunner applies it only after the ``CARLA:`` header
(:data:`CARLA_PREFIX`), and so does the reader.
"""

from __future__ import annotations

import dataclasses
import enum
import re
from collections.abc import Iterator

from simtest_operator.openscenario import model as m
from simtest_operator.openscenario.model.actions import AnyAction
from simtest_operator.openscenario.model.controls import AssignControllerAction
from simtest_operator.openscenario.model.entities import Controller
from simtest_operator.openscenario.model.scenarios import Scenario

CARLA_PREFIX = "CARLA:"
"""FileHeader description prefix of ScenarioRunner's files; it also puts positions in CARLA's
frame."""

SCENARIO_RUNNER_MODULES = frozenset(
    {
        "external_control",
        "carla_autopilot",
        "npc_vehicle_control",
        "simple_vehicle_control",
        "vehicle_longitudinal_control",
        "vehicle_velocity_control",
        "vehicle_teleport_control",
        "pedestrian_control",
    }
)
"""ScenarioRunner's controller modules (``srunner/scenariomanager/actorcontrols``), by stem."""

_TOWN = re.compile(r"town\d+[a-z_]*", re.IGNORECASE)
"""A CARLA town's map name (``Town01``, ``Town10HD``, ``Town04_Opt``)."""


class RuleSet(enum.StrEnum):
    """The reference player whose rules a scenario runs under."""

    OPENSCENARIO = "OpenSCENARIO (esmini)"
    SCENARIO_RUNNER = "ScenarioRunner"


@dataclasses.dataclass(frozen=True, slots=True)
class Rules:
    """A scenario's rule set and what in the file chose it."""

    rule_set: RuleSet
    because: str = ""
    """The first ScenarioRunner convention found (empty for OpenSCENARIO's rules)."""

    @property
    def scenario_runner(self) -> bool:
        return self.rule_set is RuleSet.SCENARIO_RUNNER

    def describe(self) -> str:
        """``ScenarioRunner (criteria_* conditions)`` or ``OpenSCENARIO (esmini)``."""
        return f"{self.rule_set} ({self.because})" if self.because else str(self.rule_set)


OPENSCENARIO = Rules(RuleSet.OPENSCENARIO)


def module_name(controller: Controller) -> str | None:
    """The stem of ``controller``'s ``module`` property (``external_control``), lower case: a
    module is named or given as the path of its Python file; None without the property."""
    name = controller.property("module")
    if name is None:
        return None
    return name.strip().replace("\\", "/").rsplit("/", 1)[-1].lower().removesuffix(".py")


def rules_of(scenario: Scenario) -> Rules:
    """The rule set ``scenario`` runs under (see the module docstring)."""
    if scenario.header.description.startswith(CARLA_PREFIX):
        return Rules(RuleSet.SCENARIO_RUNNER, f"description {CARLA_PREFIX!r}")
    if scenario.criteria:
        return Rules(RuleSet.SCENARIO_RUNNER, "criteria_* conditions")
    for controller in _controllers(scenario):
        module = module_name(controller)
        if module in SCENARIO_RUNNER_MODULES:
            return Rules(RuleSet.SCENARIO_RUNNER, f"controller module {module}")
    logic = scenario.road_network.logic_file
    if logic is not None and _TOWN.fullmatch(logic.stem):
        return Rules(RuleSet.SCENARIO_RUNNER, f"CARLA town {logic.stem}")
    return OPENSCENARIO


def _controllers(scenario: Scenario) -> Iterator[Controller]:
    for obj in scenario.entities:
        if isinstance(obj.controller, Controller):
            yield obj.controller
    board = scenario.storyboard
    bodies: list[AnyAction] = [body for p in board.init.private for body in p.actions]
    for story in board.stories:
        for act in story.acts:
            for group in act.maneuver_groups:
                for maneuver in group.maneuvers:
                    for event in maneuver.events:
                        bodies.extend(action.body for action in event.actions)
    for body in bodies:
        if isinstance(body, AssignControllerAction) and isinstance(body.controller, Controller):
            yield body.controller


_NOT_BUILT: dict[type, str] = {
    m.UserDefinedValueCondition: "ByValue UserDefinedValue conditions are not yet supported",
    m.TrafficSignalControllerCondition: (
        "ByValue TrafficSignalController conditions are not yet supported"
    ),
    m.VariableCondition: "Unknown ByValue condition",
    m.RelativeClearanceCondition: "it builds no atomic for a RelativeClearanceCondition",
    m.AngleCondition: "it builds no atomic for an AngleCondition",
    m.RelativeAngleCondition: "it builds no atomic for a RelativeAngleCondition",
}
"""Conditions ScenarioRunner's ``OpenScenarioParser.convert_condition_to_atomic`` raises on (its
messages), or builds nothing for (which its behaviour tree cannot take either)."""
_BUILT_STATES = frozenset(
    {
        m.StoryboardElementState.START_TRANSITION,
        m.StoryboardElementState.STOP_TRANSITION,
        m.StoryboardElementState.END_TRANSITION,
        m.StoryboardElementState.COMPLETE_STATE,
    }
)


def _not_built(condition: m.Condition) -> str | None:
    inner = condition.body.condition
    if isinstance(inner, m.DistanceCondition) and inner.freespace:
        return "DistanceCondition: freespace attribute is currently not implemented"
    if isinstance(inner, m.StoryboardElementStateCondition) and inner.state not in _BUILT_STATES:
        return "Only start, stop, endTransitions and completeState are currently supported"
    for kind, why in _NOT_BUILT.items():
        if isinstance(inner, kind):
            return why
    return None


_ACTION_NOT_BUILT: dict[type, str] = {
    m.SpeedProfileAction: "Unknown longitudinal action",
    m.LateralDistanceAction: "Unknown lateral action",
    m.FollowTrajectoryAction: "Private FollowTrajectory actions are not yet supported",
    m.RandomRouteAction: "Unknown private routing action",
    m.TrailerAction: "Unknown private action",
    m.TrafficSignalControllerAction: (
        "TrafficLights can only be influenced via TrafficSignalStateAction"
    ),
    m.AddEntityAction: "Global actions are not yet supported",
    m.DeleteEntityAction: "Global actions are not yet supported",
    m.SetMonitorAction: "Global actions are not yet supported",
    m.TrafficSwarmAction: "Global actions are not yet supported",
    m.TrafficSourceAction: "Global actions are not yet supported",
    m.TrafficSinkAction: "Global actions are not yet supported",
    m.TrafficStopAction: "Global actions are not yet supported",
}
"""Story actions ScenarioRunner's ``OpenScenarioParser.convert_maneuver_to_atomic`` raises on, by
kind (its messages)."""
_IGNORED_NOT_BUILT = {
    "VisibilityAction": "Visibility actions are not yet supported",
    "LightStateAction": "Unknown private action",
    "AnimationAction": "Unknown private action",
    "OverrideControllerValueAction": (
        "a ControllerAction without an AssignControllerAction (get_controller: StopIteration)"
    ),
}
"""Actions the stand-in accepts without simulating them that ScenarioRunner cannot build."""
_SIGNAL_STATES = frozenset({"GREEN", "RED", "YELLOW", "OFF"})
"""``OpenScenarioParser.tl_states``: the light states CARLA has (compared upper-cased)."""


def _action_not_built(body: AnyAction) -> str | None:
    if isinstance(body, m.LongitudinalDistanceAction):
        if body.time_gap is not None and body.distance is None:
            return "LongitudinalDistanceAction: timeGap is not implemented"
        if (body.time_gap is None) == (body.distance is None):
            return (
                "LongitudinalDistanceAction: Please specify any one attribute of "
                "[distance, timeGap]"
            )
    if isinstance(body, m.LaneChangeAction) and isinstance(body.target, m.AbsoluteTargetLane):
        return "it reads a RelativeTargetLane only ('NoneType' object has no attribute 'attrib')"
    if isinstance(body, m.SynchronizeAction) and body.final_speed is None:
        return (
            "it reads the FinalSpeed, which is missing ('NoneType' object has no attribute 'find')"
        )
    if isinstance(body, m.TrafficSignalStateAction) and body.state.upper() not in _SIGNAL_STATES:
        return "CARLA only supports Green, Red, Yellow or Off"
    if isinstance(body, m.SetValueAction | m.ModifyValueAction):
        # a ParameterAction is built (ChangeParameter, in current releases), a VariableAction not
        variable = body.scope is m.ValueScope.VARIABLE
        return "Global actions are not yet supported" if variable else None
    if isinstance(body, m.IgnoredAction):
        return _IGNORED_NOT_BUILT.get(body.kind)
    for kind, why in _ACTION_NOT_BUILT.items():
        if isinstance(body, kind):
            return why
    return None


def _where(line: int | None) -> str:
    return f" (line {line})" if line is not None else ""


def scenario_runner_refusal(scenario: Scenario) -> str | None:
    """Why ScenarioRunner refuses to load ``scenario`` for a condition or an action it builds its
    behaviour from (the acts' start and stop triggers, the events' start triggers and actions: it
    raises while building them and ``scenario_runner.py`` prints "The scenario cannot be
    loaded"), or None. It builds every Story (since 0.9.12: ``OpenScenarioConfiguration.stories``);
    the storyboard's StopTrigger not beyond its ``criteria_*`` conditions; Init actions are read
    for positions, speeds and controllers, never built."""
    triggers: list[m.Trigger | None] = []
    actions: list[m.Action] = []
    for story in scenario.storyboard.stories:
        for act in story.acts:
            triggers += [act.start_trigger, act.stop_trigger]
            for maneuver_group in act.maneuver_groups:
                for maneuver in maneuver_group.maneuvers:
                    for event in maneuver.events:
                        triggers.append(event.start_trigger)
                        actions += event.actions
    for trigger in triggers:
        for group in trigger.condition_groups if trigger is not None else ():
            for condition in group.conditions:
                why = _not_built(condition)
                if why is not None:
                    return (
                        f"ScenarioRunner cannot load the file: condition {condition.name!r}"
                        f"{_where(condition.line)}: {why}"
                    )
    for action in actions:
        why = _action_not_built(action.body)
        if why is not None:
            return (
                f"ScenarioRunner cannot load the file: action {action.name!r}"
                f"{_where(action.line)}: {why}"
            )
    return None
