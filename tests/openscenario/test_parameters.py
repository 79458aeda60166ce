"""Parameter declarations, references, types, scopes and caller overrides.

Covers: ``$name`` and ``${...}`` in attributes, declarations referring to earlier ones, every
parameterType (with range checks for unsigned types and ISO dateTime), integer rounding, story and
maneuver scopes shadowing globals, caller overrides (typed, unknown names rejected), undeclared
references naming file/element/line, mistyped literal declarations kept as text with a note, and
esmini's non-standard string expressions in names.
"""

from __future__ import annotations

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario, model, parameters
from simtest_operator.openscenario.model.common import ParameterType
from tests.openscenario.conftest import ScenarioWriter

TELEPORT = """<Private entityRef="Ego">
  <PrivateAction><TeleportAction><Position>
    <WorldPosition x="${{$X + 1}}" y="$Y" h="{h}"/>
  </Position></TeleportAction></PrivateAction>
  <PrivateAction><LongitudinalAction><SpeedAction>
    <SpeedActionDynamics dynamicsShape="step" dynamicsDimension="time" value="0"/>
    <SpeedActionTarget><AbsoluteTargetSpeed value="${{$Speed / 3.6}}"/></SpeedActionTarget>
  </SpeedAction></LongitudinalAction></PrivateAction>
</Private>"""

GLOBALS = """<ParameterDeclaration name="X" parameterType="double" value="10"/>
<ParameterDeclaration name="Y" parameterType="double" value="${$X * 2}"/>
<ParameterDeclaration name="Speed" parameterType="double" value="36"/>
<ParameterDeclaration name="Lane" parameterType="integer" value="-1"/>
"""


def test_references_expressions_and_chained_declarations(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(parameters=GLOBALS, init=TELEPORT.format(h="${pi / 2}"))
    scenario = load_scenario(path)
    init = scenario.storyboard.init.private[0]
    teleport, speed = init.actions
    assert isinstance(teleport, model.TeleportAction)
    assert isinstance(teleport.position, model.WorldPosition)
    assert (teleport.position.x, teleport.position.y) == (11.0, 20.0)
    assert teleport.position.h == pytest.approx(1.5707963)
    assert isinstance(speed, model.SpeedAction)
    assert speed.target == model.AbsoluteTargetSpeed(value=10.0, line=speed.target.line)
    declared = {d.name: d for d in scenario.parameters}
    assert declared["Y"].value == 20.0
    assert declared["Lane"].type is ParameterType.INTEGER
    assert declared["Lane"].value == -1
    assert scenario.parameter("Speed") is not None


def test_overrides_replace_globals_and_are_typed(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(parameters=GLOBALS, init=TELEPORT.format(h="0"))
    scenario = load_scenario(path, overrides={"X": "100", "Speed": "72"})
    teleport, speed = scenario.storyboard.init.private[0].actions
    assert isinstance(teleport, model.TeleportAction)
    assert isinstance(teleport.position, model.WorldPosition)
    assert (teleport.position.x, teleport.position.y) == (101.0, 200.0)
    assert isinstance(speed, model.SpeedAction)
    assert isinstance(speed.target, model.AbsoluteTargetSpeed)
    assert speed.target.value == pytest.approx(20.0)
    with pytest.raises(ScenarioError, match="not declared: Nope"):
        load_scenario(path, overrides={"Nope": "1"})
    with pytest.raises(ScenarioError, match=r"parameter 'X'.*not a number"):
        load_scenario(path, overrides={"X": "fast"})


def test_undeclared_reference_names_place(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(parameters=GLOBALS, init=TELEPORT.format(h="$Heading"))
    with pytest.raises(ScenarioError, match="'Heading' is not declared") as info:
        load_scenario(path)
    assert info.value.element == "WorldPosition"
    assert info.value.file == str(path.resolve())
    assert info.value.line is not None


@pytest.mark.parametrize(
    ("kind", "raw", "expected"),
    [
        ("double", "1.5", 1.5),
        ("double", "${1 + 1}", 2.0),
        ("integer", "${7 / 2}", 4),
        ("integer", "-2.5", -3),
        ("int", "12", 12),
        ("unsignedInt", "4000000000", 4000000000),
        ("unsignedShort", "65535", 65535),
        ("boolean", "true", True),
        ("boolean", "${1 > 2}", False),
        ("boolean", "0", False),
        ("string", "hello world", "hello world"),
        ("string", "${2 * 2}", "4"),
        ("dateTime", "2024-01-01T10:00:00", "2024-01-01T10:00:00"),
    ],
)
def test_declared_types(kind: str, raw: str, expected: object) -> None:
    kind = "integer" if kind == "int" else kind
    _, (decl,) = parameters.declare([("P", kind, raw, 1)], parameters.EMPTY)
    assert decl.value == expected
    assert type(decl.value) is type(expected)


@pytest.mark.parametrize(
    ("kind", "raw", "message"),
    [
        ("unsignedInt", "-1", "out of range"),
        ("unsignedShort", "70000", "out of range"),
        ("boolean", "maybe", "not a boolean"),
        ("double", "fast", "not a number"),
        ("dateTime", "yesterday", "dateTime"),
        ("float", "1", "unknown parameterType"),
    ],
)
def test_declared_type_errors(kind: str, raw: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        parameters.declare([("P", kind, raw, 1)], parameters.EMPTY)


def test_mistyped_literal_is_kept_as_text_with_note(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters='<ParameterDeclaration name="Mode" parameterType="double" value="time"/>'
    )
    scenario = load_scenario(path)
    assert scenario.parameter("Mode") is not None
    assert scenario.parameters[0].value == "time"
    assert len(scenario.notes) == 1
    assert "'Mode' kept as text" in scenario.notes[0]


STORY = """<Story name="S">
  <ParameterDeclarations>
    <ParameterDeclaration name="Actor" parameterType="string" value="Ego"/>
    <ParameterDeclaration name="T" parameterType="double" value="${$T0 + 1}"/>
  </ParameterDeclarations>
  <Act name="A">
    <ManeuverGroup name="G" maximumExecutionCount="1">
      <Actors selectTriggeringEntities="false"><EntityRef entityRef="$Actor"/></Actors>
      <Maneuver name="M">
        <ParameterDeclarations>
          <ParameterDeclaration name="T" parameterType="double" value="${$T * 10}"/>
        </ParameterDeclarations>
        <Event name="${$Actor + brakes}" priority="overwrite">
          <Action name="Stop">
            <PrivateAction><LongitudinalAction><SpeedAction>
              <SpeedActionDynamics dynamicsShape="linear" dynamicsDimension="rate" value="${-$T0}"/>
              <SpeedActionTarget><AbsoluteTargetSpeed value="0"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction></PrivateAction>
          </Action>
          <StartTrigger><ConditionGroup>
            <Condition name="C" delay="0" conditionEdge="rising"><ByValueCondition>
              <SimulationTimeCondition value="$T" rule="greaterThan"/>
            </ByValueCondition></Condition>
          </ConditionGroup></StartTrigger>
        </Event>
      </Maneuver>
    </ManeuverGroup>
    <StartTrigger/>
  </Act>
</Story>"""


def test_story_and_maneuver_scopes(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters='<ParameterDeclaration name="T0" parameterType="double" value="2"/>',
        stories=STORY,
    )
    scenario = load_scenario(path)
    story = scenario.storyboard.stories[0]
    assert [d.name for d in story.parameters] == ["Actor", "T"]
    group = story.acts[0].maneuver_groups[0]
    assert group.actors.entity_refs == ("Ego",)
    maneuver = group.maneuvers[0]
    assert maneuver.parameters[0].value == 30.0  # inner T shadows the story's T (3)
    event = maneuver.events[0]
    assert event.priority is model.Priority.OVERRIDE
    # esmini-style string expression in a name: kept as text with parameters substituted
    assert event.name == "${Ego + brakes}"
    assert event.start_trigger is not None
    condition = event.start_trigger.condition_groups[0].conditions[0]
    assert isinstance(condition.body, model.ByValue)
    assert condition.body.condition == model.SimulationTimeCondition(
        value=30.0, rule=model.Rule.GREATER_THAN, line=condition.body.condition.line
    )
    action = event.actions[0].body
    assert isinstance(action, model.SpeedAction)
    assert action.dynamics.value == -2.0
