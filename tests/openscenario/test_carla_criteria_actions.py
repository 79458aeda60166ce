"""Reading CARLA ScenarioRunner's conventions and the world-changing actions.

Covers: ``criteria_<Test>`` conditions taken out of the storyboard's and the acts' StopTriggers as
criteria (with ``parameterRef=""`` and undeclared argument parameters, which are not Invalid), an
unknown criterion reported as a deviation (refused under strict mode), both spellings of
OnSidewalkTest; AddEntityAction/DeleteEntityAction; EnvironmentAction inline and from an
environment catalog entry chosen by a parameter; an Action without a child; an inactive
OverrideControllerValueAction alone.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.openscenario import LoadOptions, StrictDeviationError, load_scenario, model

from .conftest import CAR, ScenarioWriter

STRICT = LoadOptions(strict=True)


def _criterion(name: str, ref: str = "", value: str = "") -> str:
    return f"""<Condition name="criteria_{name}" delay="0" conditionEdge="rising">
      <ByValueCondition><ParameterCondition parameterRef="{ref}" value="{value}" rule="lessThan"/>
      </ByValueCondition></Condition>"""


_TIME_STOP = """<Condition name="TimeOut" delay="0" conditionEdge="rising">
  <ByValueCondition><SimulationTimeCondition value="30" rule="greaterThan"/></ByValueCondition>
</Condition>"""


def _story(actions: str) -> str:
    return f"""<Story name="S"><Act name="A">
      <ManeuverGroup name="G" maximumExecutionCount="1">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
        <Maneuver name="M"><Event name="E" priority="parallel">{actions}</Event></Maneuver>
      </ManeuverGroup>
      <StartTrigger><ConditionGroup><Condition name="go" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="0" rule="greaterThan"/>
        </ByValueCondition></Condition></ConditionGroup></StartTrigger>
    </Act></Story>"""


def test_criteria_leave_the_stop_trigger(write_scenario: ScenarioWriter) -> None:
    stop = (
        "<ConditionGroup>"
        + _criterion("CollisionTest")
        + _criterion("KeepLaneTest")
        + _criterion("DrivenDistanceTest", "distance_success", "100")
        + "</ConditionGroup><ConditionGroup>"
        + _TIME_STOP
        + _criterion("OnSidewalkTest")
        + "</ConditionGroup>"
    )
    scenario = load_scenario(write_scenario(stop=stop), options=STRICT)
    trigger = scenario.storyboard.stop_trigger
    assert trigger is not None
    assert [c.test for c in trigger.criteria] == [
        "CollisionTest",
        "KeepLaneTest",
        "DrivenDistanceTest",
        "OnSidewalkTest",
    ]
    assert all(c.known for c in trigger.criteria)
    assert trigger.criteria[0].arguments == ()
    assert trigger.criteria[2].argument("distance_success") == "100"
    # The criteria-only group is gone; the mixed one keeps its real stop condition.
    (group,) = trigger.condition_groups
    assert [c.name for c in group.conditions] == ["TimeOut"]
    assert scenario.deviations == ()


def test_unknown_criterion_is_a_warning_not_invalid(write_scenario: ScenarioWriter) -> None:
    stop = "<ConditionGroup>" + _criterion("FlyingCarTest") + "</ConditionGroup>"
    path = write_scenario(stop=stop)
    scenario = load_scenario(path)
    trigger = scenario.storyboard.stop_trigger
    assert trigger is not None and trigger.condition_groups == ()
    (criterion,) = trigger.criteria
    assert criterion.test == "FlyingCarTest" and not criterion.known
    (deviation,) = scenario.deviations
    assert deviation.code == "carla-criterion-unknown"
    assert deviation.element == "Condition" and "'FlyingCarTest'" in deviation.message
    with pytest.raises(StrictDeviationError):
        load_scenario(path, options=STRICT)


def test_criterion_argument_may_be_a_parameter(write_scenario: ScenarioWriter) -> None:
    stop = (
        "<ConditionGroup>"
        + _criterion("DrivenDistanceTest", "distance_success", "$Far")
        + "</ConditionGroup>"
    )
    scenario = load_scenario(
        write_scenario(
            stop=stop,
            parameters='<ParameterDeclaration name="Far" parameterType="double" value="250"/>',
        )
    )
    trigger = scenario.storyboard.stop_trigger
    assert trigger is not None and trigger.criteria[0].argument("distance_success") == "250"


def test_entity_actions(write_scenario: ScenarioWriter) -> None:
    init = """<GlobalAction><EntityAction entityRef="Other">
        <AddEntityAction><Position><WorldPosition x="10" y="2" h="0"/></Position></AddEntityAction>
      </EntityAction></GlobalAction>"""
    story = _story(
        """<Action name="gone"><GlobalAction><EntityAction entityRef="Other">
          <DeleteEntityAction/></EntityAction></GlobalAction></Action>"""
    )
    scenario = load_scenario(
        write_scenario(
            entities=CAR.format(name="Ego") + CAR.format(name="Other"), init=init, stories=story
        ),
        options=STRICT,
    )
    (added,) = scenario.storyboard.init.global_actions
    assert isinstance(added, model.AddEntityAction) and added.entity_ref == "Other"
    assert isinstance(added.position, model.WorldPosition) and added.position.x == 10.0
    action = scenario.storyboard.stories[0].acts[0].maneuver_groups[0].maneuvers[0].events[0]
    assert action.actions[0].body == model.DeleteEntityAction(
        entity_ref="Other", line=action.actions[0].body.line
    )
    assert scenario.unsupported() == ()


def test_environment_inline_and_from_a_catalog_chosen_by_parameter(
    tmp_path: Path, write_scenario: ScenarioWriter
) -> None:
    catalogs = tmp_path / "catalogs"
    catalogs.mkdir()
    (catalogs / "EnvironmentCatalog.xosc").write_text(
        """<?xml version="1.0"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="0" date="2020-01-01T00:00:00" description="e"
  author="t"/>
  <Catalog name="EnvironmentCatalog">
    <Environment name="Rain"><TimeOfDay animation="false" dateTime="2020-01-01T18:00:00"/>
      <Weather cloudState="rainy"><Sun intensity="0.1" azimuth="0" elevation="0.2"/>
        <Fog visualRange="800"/><Precipitation precipitationType="rain" intensity="0.8"/>
      </Weather><RoadCondition frictionScaleFactor="0.7"/></Environment>
    <Environment name="Sun"><TimeOfDay animation="false" dateTime="2020-01-01T12:00:00"/>
      <Weather cloudState="free"/><RoadCondition frictionScaleFactor="1.0"/></Environment>
  </Catalog></OpenSCENARIO>""",
        encoding="utf-8",
    )
    init = """<GlobalAction><EnvironmentAction><Environment name="Noon">
        <TimeOfDay animation="false" dateTime="2020-01-01T12:00:00"/>
        <Weather cloudState="free"><Sun intensity="0.85" azimuth="0" elevation="1.31"/>
          <Fog visualRange="100000"/><Precipitation precipitationType="dry" intensity="0"/>
        </Weather><RoadCondition frictionScaleFactor="1.0"/>
      </Environment></EnvironmentAction></GlobalAction>"""
    story = _story(
        """<Action name="weather"><GlobalAction><EnvironmentAction>
          <CatalogReference catalogName="EnvironmentCatalog" entryName="$Weather"/>
        </EnvironmentAction></GlobalAction></Action>"""
    )
    scenario = load_scenario(
        write_scenario(
            minor=0,
            parameters='<ParameterDeclaration name="Weather" parameterType="string" value="Sun"/>',
            catalogs='<EnvironmentCatalog><Directory path="catalogs"/></EnvironmentCatalog>',
            init=init,
            stories=story,
        ),
        overrides={"Weather": "Rain"},
    )
    (noon,) = scenario.storyboard.init.global_actions
    assert isinstance(noon, model.EnvironmentAction)
    settings = dict(noon.environment.settings)
    assert settings["Weather.cloudState"] == "free"
    assert settings["Weather.Sun.elevation"] == "1.31"
    assert settings["Weather.Precipitation.precipitationType"] == "dry"
    assert settings["RoadCondition.frictionScaleFactor"] == "1.0"
    assert settings["TimeOfDay.dateTime"] == "2020-01-01T12:00:00"
    event = scenario.storyboard.stories[0].acts[0].maneuver_groups[0].maneuvers[0].events[0]
    rain = event.actions[0].body
    assert isinstance(rain, model.EnvironmentAction) and rain.environment.name == "Rain"
    assert dict(rain.environment.settings)["Weather.Precipitation.intensity"] == "0.8"
    assert "EnvironmentAction" in scenario.ignored_kinds  # recorded, never rendered


def test_action_without_child_is_a_placeholder(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(stories=_story('<Action name="todo"/>'))
    scenario = load_scenario(path)
    event = scenario.storyboard.stories[0].acts[0].maneuver_groups[0].maneuvers[0].events[0]
    assert isinstance(event.actions[0].body, model.IgnoredAction)
    assert [d.code for d in scenario.deviations] == ["empty-action"]
    with pytest.raises(StrictDeviationError):
        load_scenario(path, options=STRICT)


def test_inactive_override_alone_is_accepted(write_scenario: ScenarioWriter) -> None:
    init = """<Private entityRef="Ego"><PrivateAction><ControllerAction>
        <OverrideControllerValueAction>
          <Throttle value="0" active="false"/><Brake value="0" active="false"/>
          <Clutch value="0" active="false"/><ParkingBrake value="0" active="false"/>
          <SteeringWheel value="0" active="false"/><Gear number="0" active="false"/>
        </OverrideControllerValueAction>
      </ControllerAction></PrivateAction></Private>"""
    scenario = load_scenario(write_scenario(minor=1, init=init), options=STRICT)
    (private,) = scenario.storyboard.init.private
    assert private.actions[0] == model.IgnoredAction(
        kind="OverrideControllerValueAction", line=private.actions[0].line
    )
    assert scenario.unsupported() == ()


def test_criteria_in_an_act_stop_trigger_are_criteria_too(write_scenario: ScenarioWriter) -> None:
    # ScenarioRunner collects criteria_* from every StopTrigger under the storyboard
    # (OpenScenario._create_test_criteria iterates storyboard.iter("StopTrigger")).
    act_stop = (
        "<StopTrigger><ConditionGroup>"
        + _criterion("MaxVelocityTest", "max_velocity", "20")
        + _TIME_STOP
        + "</ConditionGroup></StopTrigger></Act>"
    )
    stories = _story(
        """<Action name="gone"><GlobalAction><EntityAction entityRef="Ego">
          <DeleteEntityAction/></EntityAction></GlobalAction></Action>"""
    ).replace("</Act>", act_stop)
    stop = "<ConditionGroup>" + _criterion("CollisionTest") + "</ConditionGroup>"
    scenario = load_scenario(write_scenario(stories=stories, stop=stop))
    assert [c.test for c in scenario.criteria] == ["CollisionTest", "MaxVelocityTest"]
    assert scenario.criteria[1].arguments == (("max_velocity", "20"),)
    act = scenario.storyboard.stories[0].acts[0]
    assert act.stop_trigger is not None
    assert [c.name for g in act.stop_trigger.condition_groups for c in g.conditions] == ["TimeOut"]
