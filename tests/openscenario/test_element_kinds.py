"""Loading a scenario that uses every supported element kind, and some unsupported ones.

Covers: header, road network (relative path) and variables; entities with bounding box,
performance and axles; triggers (groups OR, conditions AND, empty stop trigger); every supported
entity/value condition kind and every private/global action kind with their key fields; ignored
actions listed; unsupported elements kept in place (element, file, line, reason) and listed by
``scenario.unsupported()``; the model is immutable.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simtest_operator.openscenario import load_scenario, model
from tests.openscenario.conftest import CAR, ScenarioWriter


def _condition(body: str, *, name: str = "c", edge: str = "rising", delay: str = "0") -> str:
    return f'<Condition name="{name}" delay="{delay}" conditionEdge="{edge}">{body}</Condition>'


def _by_entity(inner: str, rule: str = "any") -> str:
    return _condition(
        f'<ByEntityCondition><TriggeringEntities triggeringEntitiesRule="{rule}">'
        f'<EntityRef entityRef="Ego"/></TriggeringEntities>'
        f"<EntityCondition>{inner}</EntityCondition></ByEntityCondition>"
    )


def _by_value(inner: str) -> str:
    return _condition(f"<ByValueCondition>{inner}</ByValueCondition>")


LANE = '<Position><LanePosition roadId="1" laneId="-1" s="50" offset="0.2"/></Position>'
ENTITY_CONDITIONS = [
    '<EndOfRoadCondition duration="1"/>',
    '<OffroadCondition duration="2"/>',
    '<CollisionCondition><EntityRef entityRef="Lead"/></CollisionCondition>',
    '<CollisionCondition><ByType type="pedestrian"/></CollisionCondition>',
    '<TimeHeadwayCondition entityRef="Lead" value="1.5" freespace="true" rule="lessThan"'
    ' coordinateSystem="road" relativeDistanceType="longitudinal"/>',
    '<TimeToCollisionCondition value="3" freespace="false" rule="lessOrEqual">'
    '<TimeToCollisionConditionTarget><EntityRef entityRef="Lead"/>'
    "</TimeToCollisionConditionTarget></TimeToCollisionCondition>",
    '<AccelerationCondition value="-5" rule="lessThan" direction="longitudinal"/>',
    '<StandStillCondition duration="3"/>',
    '<SpeedCondition value="10" rule="greaterOrEqual"/>',
    '<RelativeSpeedCondition entityRef="Lead" value="0" rule="notEqualTo"/>',
    '<TraveledDistanceCondition value="100"/>',
    f'<ReachPositionCondition tolerance="2">{LANE}</ReachPositionCondition>',
    f'<DistanceCondition value="5" freespace="false" rule="lessThan">{LANE}</DistanceCondition>',
    '<RelativeDistanceCondition entityRef="Lead" value="20" freespace="true" rule="lessThan"'
    ' relativeDistanceType="lateral" coordinateSystem="lane" routingAlgorithm="shortest"/>',
    '<RelativeClearanceCondition freeSpace="true" oppositeLanes="false" distanceForward="10"'
    ' distanceBackward="10"/>',
]
VALUE_CONDITIONS = [
    '<SimulationTimeCondition value="2" rule="greaterThan"/>',
    '<StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="E0"'
    ' state="endTransition"/>',
    '<ParameterCondition parameterRef="P" value="1" rule="equalTo"/>',
    '<VariableCondition variableRef="V" value="2" rule="lessThan"/>',
    '<TrafficSignalCondition name="sig" state="red"/>',
]


def _private(inner: str) -> str:
    return f"<PrivateAction>{inner}</PrivateAction>"


PRIVATE_ACTIONS = [
    f"<TeleportAction>{LANE}</TeleportAction>",
    "<LongitudinalAction><SpeedAction>"
    '<SpeedActionDynamics dynamicsShape="cubic" dynamicsDimension="distance" value="30"'
    ' followingMode="follow"/>'
    '<SpeedActionTarget><RelativeTargetSpeed entityRef="Lead" value="-2"'
    ' speedTargetValueType="delta" continuous="true"/></SpeedActionTarget>'
    "</SpeedAction></LongitudinalAction>",
    '<LongitudinalAction><LongitudinalDistanceAction entityRef="Lead" timeGap="1.2"'
    ' freespace="true" continuous="true" displacement="leadingReferencedEntity">'
    '<DynamicConstraints maxAcceleration="2" maxDeceleration="5" maxSpeed="30"/>'
    "</LongitudinalDistanceAction></LongitudinalAction>",
    '<LongitudinalAction><SpeedProfileAction followingMode="position">'
    '<SpeedProfileEntry speed="5" time="2"/><SpeedProfileEntry speed="0"/>'
    "</SpeedProfileAction></LongitudinalAction>",
    '<LateralAction><LaneChangeAction targetLaneOffset="0.3">'
    '<LaneChangeActionDynamics dynamicsShape="sinusoidal" dynamicsDimension="time" value="3"/>'
    '<LaneChangeTarget><RelativeTargetLane entityRef="Lead" value="1"/></LaneChangeTarget>'
    "</LaneChangeAction></LateralAction>",
    '<LateralAction><LaneChangeAction><LaneChangeActionDynamics dynamicsShape="linear"'
    ' dynamicsDimension="distance" value="50"/><LaneChangeTarget>'
    '<AbsoluteTargetLane value="-2"/></LaneChangeTarget></LaneChangeAction></LateralAction>',
    '<LateralAction><LaneOffsetAction continuous="false">'
    '<LaneOffsetActionDynamics dynamicsShape="step" maxLateralAcc="1"/>'
    '<LaneOffsetTarget><AbsoluteTargetLaneOffset value="-0.5"/></LaneOffsetTarget>'
    "</LaneOffsetAction></LateralAction>",
    '<LateralAction><LateralDistanceAction entityRef="Lead" distance="3" freespace="false"'
    ' continuous="true"/></LateralAction>',
    f"<RoutingAction><AcquirePositionAction>{LANE}</AcquirePositionAction></RoutingAction>",
    '<SynchronizeAction masterEntityRef="Lead" targetToleranceMaster="1" targetTolerance="1">'
    '<TargetPositionMaster><WorldPosition x="100" y="0"/></TargetPositionMaster>'
    '<TargetPosition><RelativeLanePosition entityRef="Lead" dLane="1" dsLane="-10"/>'
    '</TargetPosition><FinalSpeed><AbsoluteSpeed value="10"><SteadyState>'
    '<TargetDistanceSteadyState distance="20"/></SteadyState></AbsoluteSpeed></FinalSpeed>'
    "</SynchronizeAction>",
    '<ControllerAction><ActivateControllerAction longitudinal="true" lateral="false"/>'
    "</ControllerAction>",
    '<ControllerAction><AssignControllerAction activateLongitudinal="true">'
    '<Controller name="acc"><Properties><Property name="mode" value="acc"/></Properties>'
    "</Controller></AssignControllerAction></ControllerAction>",
    '<AppearanceAction><LightStateAction transitionTime="0"><LightType>'
    '<VehicleLight vehicleLightType="brakeLights"/></LightType><LightState mode="on"/>'
    "</LightStateAction></AppearanceAction>",
    '<VisibilityAction graphics="true" traffic="true" sensors="false"/>',
    "<TrailerAction><DisconnectTrailerAction/></TrailerAction>",
    "<RoutingAction><RandomRouteAction/></RoutingAction>",
    "<RoutingAction><FancyRouteAction/></RoutingAction>",
]
GLOBAL_ACTIONS = [
    '<ParameterAction parameterRef="P"><SetAction value="2"/></ParameterAction>',
    '<ParameterAction parameterRef="P"><ModifyAction><Rule><AddValue value="1"/></Rule>'
    "</ModifyAction></ParameterAction>",
    '<VariableAction variableRef="V"><ModifyAction><Rule><MultiplyByValue value="2"/></Rule>'
    "</ModifyAction></VariableAction>",
    '<EnvironmentAction><Environment name="e"/></EnvironmentAction>',
    '<InfrastructureAction><TrafficSignalAction><TrafficSignalStateAction name="s" state="r"/>'
    "</TrafficSignalAction></InfrastructureAction>",
]


def _event(index: int, action: str, condition: str) -> str:
    return (
        f'<Event name="E{index}" priority="parallel" maximumExecutionCount="2">'
        f'<Action name="A{index}">{action}</Action>'
        f"<StartTrigger><ConditionGroup>{condition}</ConditionGroup></StartTrigger></Event>"
    )


def _stories() -> str:
    conditions = [_by_entity(c) for c in ENTITY_CONDITIONS] + [
        _by_value(c) for c in VALUE_CONDITIONS
    ]
    actions = [_private(a) for a in PRIVATE_ACTIONS] + [
        f"<GlobalAction>{a}</GlobalAction>" for a in GLOBAL_ACTIONS
    ]
    count = max(len(conditions), len(actions))
    events = "".join(
        _event(i, actions[i % len(actions)], conditions[i % len(conditions)]) for i in range(count)
    )
    return (
        '<Story name="S"><Act name="Act"><ManeuverGroup name="G" maximumExecutionCount="3">'
        '<Actors selectTriggeringEntities="true"><EntityRef entityRef="Ego"/></Actors>'
        f'<Maneuver name="M">{events}</Maneuver></ManeuverGroup>'
        "<StartTrigger><ConditionGroup>"
        + _by_value('<SimulationTimeCondition value="0" rule="greaterThan"/>')
        + "</ConditionGroup><ConditionGroup>"
        + _by_value('<SimulationTimeCondition value="1" rule="greaterThan"/>')
        + _by_value('<SimulationTimeCondition value="2" rule="lessThan"/>')
        + "</ConditionGroup></StartTrigger><StopTrigger/></Act></Story>"
    )


STOP_AT_60 = _by_value('<SimulationTimeCondition value="60" rule="greaterThan"/>')


@pytest.fixture
def rich(write_scenario: ScenarioWriter, tmp_path: Path) -> model.Scenario:
    (tmp_path / "roads").mkdir()
    (tmp_path / "roads" / "r.xodr").write_text("<OpenDRIVE/>")
    path = write_scenario(
        minor=3,
        parameters='<ParameterDeclaration name="P" parameterType="integer" value="1"/>',
        road='<LogicFile filepath="roads/r.xodr"/><SceneGraphFile filepath="x.osgb"/>',
        entities=CAR.format(name="Ego") + CAR.format(name="Lead"),
        init='<GlobalAction><EnvironmentAction><Environment name="e"/></EnvironmentAction>'
        '</GlobalAction><Private entityRef="Lead">'
        + _private(f"<TeleportAction>{LANE}</TeleportAction>")
        + "</Private>",
        stories=_stories(),
        stop="<ConditionGroup>" + STOP_AT_60 + "</ConditionGroup>",
    )
    text = path.read_text().replace(
        "</ParameterDeclarations>",
        "</ParameterDeclarations><VariableDeclarations>"
        '<VariableDeclaration name="V" variableType="double" value="1.5"/>'
        "</VariableDeclarations>",
        1,
    )
    path.write_text(text)
    return load_scenario(path)


def test_header_road_entities(rich: model.Scenario, tmp_path: Path) -> None:
    assert (rich.header.rev_major, rich.header.rev_minor) == (1, 3)
    assert rich.road_network.logic_file == (tmp_path / "roads" / "r.xodr").resolve()
    assert rich.variable("V") == model.ParameterDeclaration(
        name="V", type=model.ParameterType.DOUBLE, value=1.5, line=rich.variables[0].line
    )
    ego = rich.entity("Ego")
    assert ego is not None and ego.bounding_box.length == 5.0 and ego.bounding_box.center_x == 1.4
    assert ego.performance is not None
    assert (ego.performance.max_speed, ego.performance.max_deceleration) == (69.0, 10.0)
    assert ego.axles is not None and ego.axles.front is not None
    assert ego.axles.front.position_x == 2.9
    assert rich.entity("Nobody") is None
    assert rich.ignored_kinds == (
        "EnvironmentAction",
        "LightStateAction",
        "SceneGraphFile",
        "VisibilityAction",
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        ego.name = "x"  # type: ignore[misc]


def test_triggers(rich: model.Scenario) -> None:
    act = rich.storyboard.stories[0].acts[0]
    assert act.start_trigger is not None
    first, second = act.start_trigger.condition_groups
    assert len(first.conditions) == 1 and len(second.conditions) == 2
    assert act.stop_trigger is not None and act.stop_trigger.condition_groups == ()
    group = act.maneuver_groups[0]
    assert group.maximum_execution_count == 3
    assert group.actors.select_triggering_entities is True
    assert rich.storyboard.stop_trigger is not None


def _events(scenario: model.Scenario) -> tuple[model.Event, ...]:
    return scenario.storyboard.stories[0].acts[0].maneuver_groups[0].maneuvers[0].events


def test_every_condition_kind(rich: model.Scenario) -> None:
    kinds = []
    for event in _events(rich):
        assert event.start_trigger is not None
        condition = event.start_trigger.condition_groups[0].conditions[0]
        assert condition.edge is model.ConditionEdge.RISING
        body = condition.body
        inner = body.condition
        kinds.append(
            type(inner).__name__
            if not isinstance(inner, model.Unsupported)
            else f"Unsupported:{inner.element}"
        )
        if isinstance(body, model.ByEntity):
            assert body.triggering_entities == ("Ego",)
            assert body.rule is model.TriggeringEntitiesRule.ANY
    assert kinds[: len(ENTITY_CONDITIONS) + len(VALUE_CONDITIONS)] == [
        "EndOfRoadCondition",
        "OffRoadCondition",
        "CollisionCondition",
        "CollisionCondition",
        "TimeHeadwayCondition",
        "TimeToCollisionCondition",
        "AccelerationCondition",
        "StandStillCondition",
        "SpeedCondition",
        "RelativeSpeedCondition",
        "TraveledDistanceCondition",
        "ReachPositionCondition",
        "DistanceCondition",
        "RelativeDistanceCondition",
        "RelativeClearanceCondition",
        "SimulationTimeCondition",
        "StoryboardElementStateCondition",
        "ParameterCondition",
        "VariableCondition",
        "TrafficSignalCondition",
    ]
    events = _events(rich)
    headway = events[4].start_trigger.condition_groups[0].conditions[0].body  # type: ignore[union-attr]
    assert isinstance(headway, model.ByEntity)
    assert headway.condition == model.TimeHeadwayCondition(
        entity_ref="Lead",
        value=1.5,
        rule=model.Rule.LESS_THAN,
        freespace=True,
        coordinate_system=model.CoordinateSystem.ROAD,
        relative_distance_type=model.RelativeDistanceType.LONGITUDINAL,
        line=headway.condition.line,
    )


def test_every_action_kind(rich: model.Scenario) -> None:
    bodies = [event.actions[0].body for event in _events(rich)]
    names = [
        f"Unsupported:{b.element}"
        if isinstance(b, model.Unsupported)
        else f"Ignored:{b.kind}"
        if isinstance(b, model.IgnoredAction)
        else type(b).__name__
        for b in bodies
    ]
    assert names == [
        "TeleportAction",
        "SpeedAction",
        "LongitudinalDistanceAction",
        "SpeedProfileAction",
        "LaneChangeAction",
        "LaneChangeAction",
        "LaneOffsetAction",
        "LateralDistanceAction",
        "AcquirePositionAction",
        "SynchronizeAction",
        "ActivateControllerAction",
        "AssignControllerAction",
        "Ignored:LightStateAction",
        "Ignored:VisibilityAction",
        "TrailerAction",
        "RandomRouteAction",
        "Unsupported:FancyRouteAction",
        "SetValueAction",
        "ModifyValueAction",
        "ModifyValueAction",
        "EnvironmentAction",
        "TrafficSignalStateAction",
    ]
    speed, distance, sync, modify = bodies[1], bodies[2], bodies[9], bodies[19]
    assert isinstance(speed, model.SpeedAction)
    assert speed.dynamics.following_mode is model.FollowingMode.FOLLOW
    assert speed.target == model.RelativeTargetSpeed(
        entity_ref="Lead",
        value=-2.0,
        value_type=model.SpeedTargetValueType.DELTA,
        continuous=True,
        line=speed.target.line,
    )
    assert isinstance(distance, model.LongitudinalDistanceAction)
    assert distance.time_gap == 1.2 and distance.distance is None
    assert distance.displacement is model.LongitudinalDisplacement.LEADING
    assert isinstance(sync, model.SynchronizeAction)
    assert isinstance(sync.target_position, model.RelativeLanePosition)
    assert sync.target_position.ds_lane == -10.0 and sync.target_position.ds is None
    assert isinstance(sync.final_speed, model.AbsoluteFinalSpeed)
    assert sync.final_speed.steady_state is not None
    assert sync.final_speed.steady_state.distance == 20.0
    assert modify == model.ModifyValueAction(
        scope=model.ValueScope.VARIABLE,
        ref="V",
        rule=model.ModifyRule.MULTIPLY,
        value=2.0,
        line=modify.line,
    )
    assert all(event.maximum_execution_count == 2 for event in _events(rich))
    line = rich.storyboard.init.global_actions[0].line
    assert rich.storyboard.init.global_actions == (
        model.EnvironmentAction(environment=model.Environment(name="e", line=line), line=line),
    )


def test_unsupported_listed_in_place(rich: model.Scenario) -> None:
    listed = {(u.element, u.reason) for u in rich.unsupported()}
    assert listed == {
        ("FancyRouteAction", "unknown routing action FancyRouteAction"),
    }
    for node in rich.unsupported():
        assert node.line is not None and node.file == str(rich.path)
        assert node.describe().startswith(f"<{node.element}> at {rich.path}:{node.line}")
