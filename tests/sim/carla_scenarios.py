"""CARLA ScenarioRunner-style scenarios for the tests, written as ScenarioRunner's examples are.

:func:`follow_leading` is a FollowLeadingVehicle-like scenario on ``carla/avenue.xodr``: the hero
is handed to the system under test (``external_control``), the act starts once the hero has moved
(a group of ``TraveledDistance > 1`` and ``SimulationTime == 0`` with rising edges), the adversary
then drives ahead and brakes; the act stops after the hero drove ``act_distance`` metres and the
storyboard StopTrigger holds only ``criteria_*`` tests. Parts are swappable per test.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from simtest_operator import evaluation
from simtest_operator.drivermodel import SutConfig
from simtest_operator.runner import scenario_execution
from simtest_operator.sim.session import BackendChoice

HERE = Path(__file__).parent / "carla"

ALL_CRITERIA = (
    "RunningStopTest",
    "RunningRedLightTest",
    "WrongLaneTest",
    "OnSidewalkTest",
    "KeepLaneTest",
    "CollisionTest",
)


def criterion(name: str, ref: str = "", value: str = "") -> str:
    return f"""
        <Condition name="criteria_{name}" delay="0" conditionEdge="rising">
          <ByValueCondition>
            <ParameterCondition parameterRef="{ref}" value="{value}" rule="lessThan"/>
          </ByValueCondition>
        </Condition>"""


def criteria(*names: str, distance: float | None = 50.0) -> str:
    body = "".join(criterion(n) for n in names)
    if distance is not None:
        body += criterion("DrivenDistanceTest", "distance_success", f"{distance:g}")
    return body


HERO_CONTROL = """
          <PrivateAction>
            <ControllerAction>
              <AssignControllerAction>
                <Controller name="HeroAgent">
                  <Properties>
                    <Property name="module" value="external_control"/>
                  </Properties>
                </Controller>
              </AssignControllerAction>
              <OverrideControllerValueAction>
                <Throttle value="0" active="false"/>
                <Brake value="0" active="false"/>
                <Clutch value="0" active="false"/>
                <ParkingBrake value="0" active="false"/>
                <SteeringWheel value="0" active="false"/>
                <Gear number="0" active="false"/>
              </OverrideControllerValueAction>
            </ControllerAction>
          </PrivateAction>"""

HERO_AUTOPILOT = """
          <PrivateAction><ControllerAction><AssignControllerAction>
            <Controller name="Autopilot"><Properties>
              <Property name="module" value="carla_autopilot"/>
            </Properties></Controller>
          </AssignControllerAction></ControllerAction></PrivateAction>"""

HERO_ACTIVATE = """
          <PrivateAction><ActivateControllerAction longitudinal="true" lateral="true"/>
          </PrivateAction>"""

ENVIRONMENT = """
        <GlobalAction>
          <EnvironmentAction>
            <Environment name="Noon">
              <TimeOfDay animation="false" dateTime="2020-03-20T12:00:00"/>
              <Weather cloudState="free">
                <Sun intensity="0.85" azimuth="0" elevation="1.31"/>
                <Fog visualRange="100000.0"/>
                <Precipitation precipitationType="dry" intensity="0.0"/>
              </Weather>
              <RoadCondition frictionScaleFactor="1.0"/>
            </Environment>
          </EnvironmentAction>
        </GlobalAction>"""


def vehicle(name: str, kind: str) -> str:
    return f"""
    <ScenarioObject name="{name}">
      <Vehicle name="vehicle.lincoln.mkz" vehicleCategory="car">
        <ParameterDeclarations/>
        <Performance maxSpeed="69.444" maxAcceleration="200" maxDeceleration="10.0"/>
        <BoundingBox><Center x="1.5" y="0.0" z="0.9"/><Dimensions width="2.1" length="4.5" height="1.8"/></BoundingBox>
        <Axles>
          <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.8" positionX="3.1" positionZ="0.3"/>
          <RearAxle maxSteering="0.0" wheelDiameter="0.6" trackWidth="1.8" positionX="0.0" positionZ="0.3"/>
        </Axles>
        <Properties><Property name="type" value="{kind}"/></Properties>
      </Vehicle>
    </ScenarioObject>"""  # noqa: E501


ADVERSARY_AHEAD = """
          <PrivateAction>
            <TeleportAction><Position>
              <RelativeLanePosition entityRef="hero" dLane="0" ds="50" offset="0"/>
            </Position></TeleportAction>
          </PrivateAction>"""
"""The adversary's default start: 50 m ahead of the hero in its lane."""


def follow_leading(
    *,
    stop: str | None = None,
    hero_position: str = '<LanePosition roadId="1" laneId="-1" s="20" offset="0"/>',
    hero_control: str = HERO_CONTROL,
    init_globals: str = ENVIRONMENT,
    adversary_init: str | None = None,
    extra_entities: str = "",
    extra_events: str = "",
    act_distance: float = 120.0,
    brake_after: float = 40.0,
    description: str = "CARLA:FollowLeadingVehicle",
    logic_file: str = "avenue.xodr",
) -> str:
    stop_groups = stop if stop is not None else criteria(*ALL_CRITERIA)
    adversary = (
        adversary_init
        if adversary_init is not None
        else f"""
        <Private entityRef="adversary">{ADVERSARY_AHEAD}
        </Private>"""
    )
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2020-03-20T12:00:00" description="{description}" author=""/>
  <ParameterDeclarations>
    <ParameterDeclaration name="leadingSpeed" parameterType="double" value="6.0"/>
  </ParameterDeclarations>
  <CatalogLocations/>
  <RoadNetwork>
    <LogicFile filepath="{logic_file}"/>
    <SceneGraphFile filepath=""/>
  </RoadNetwork>
  <Entities>{vehicle("hero", "ego_vehicle")}{vehicle("adversary", "simulation")}{extra_entities}
  </Entities>
  <Storyboard>
    <Init>
      <Actions>{init_globals}
        <Private entityRef="hero">
          <PrivateAction>
            <TeleportAction><Position>{hero_position}</Position></TeleportAction>
          </PrivateAction>{hero_control}
        </Private>{adversary}
      </Actions>
    </Init>
    <Story name="MyStory">
      <Act name="Behavior">
        <ManeuverGroup name="ManeuverSequence" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false">
            <EntityRef entityRef="adversary"/>
          </Actors>
          <Maneuver name="FollowLeadingVehicleManeuver">
            <Event name="LeadingVehicleKeepsVelocity" priority="overwrite">
              <Action name="LeadingVehicleKeepsVelocity">
                <PrivateAction><LongitudinalAction><SpeedAction>
                  <SpeedActionDynamics dynamicsShape="step" value="20" dynamicsDimension="distance"/>
                  <SpeedActionTarget><AbsoluteTargetSpeed value="$leadingSpeed"/></SpeedActionTarget>
                </SpeedAction></LongitudinalAction></PrivateAction>
              </Action>
              <StartTrigger>
                <ConditionGroup>
                  <Condition name="Start" delay="0" conditionEdge="rising">
                    <ByValueCondition>
                      <SimulationTimeCondition value="0" rule="greaterThan"/>
                    </ByValueCondition>
                  </Condition>
                </ConditionGroup>
              </StartTrigger>
            </Event>
            <Event name="LeadingVehicleBrakes" priority="overwrite">
              <Action name="LeadingVehicleBrakes">
                <PrivateAction><LongitudinalAction><SpeedAction>
                  <SpeedActionDynamics dynamicsShape="linear" value="2" dynamicsDimension="rate"/>
                  <SpeedActionTarget><AbsoluteTargetSpeed value="0"/></SpeedActionTarget>
                </SpeedAction></LongitudinalAction></PrivateAction>
              </Action>
              <StartTrigger>
                <ConditionGroup>
                  <Condition name="AfterKeepsVelocity" delay="0" conditionEdge="rising">
                    <ByValueCondition>
                      <StoryboardElementStateCondition storyboardElementType="action" storyboardElementRef="LeadingVehicleKeepsVelocity" state="endTransition"/>
                    </ByValueCondition>
                  </Condition>
                  <Condition name="HeroWentFar" delay="0" conditionEdge="rising">
                    <ByEntityCondition>
                      <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="hero"/></TriggeringEntities>
                      <EntityCondition><TraveledDistanceCondition value="{brake_after:g}"/></EntityCondition>
                    </ByEntityCondition>
                  </Condition>
                </ConditionGroup>
              </StartTrigger>
            </Event>{extra_events}
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger>
          <ConditionGroup>
            <Condition name="OverallStartCondition" delay="0" conditionEdge="rising">
              <ByEntityCondition>
                <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="hero"/></TriggeringEntities>
                <EntityCondition><TraveledDistanceCondition value="1.0"/></EntityCondition>
              </ByEntityCondition>
            </Condition>
            <Condition name="StartTime" delay="0" conditionEdge="rising">
              <ByValueCondition><SimulationTimeCondition value="0" rule="equalTo"/></ByValueCondition>
            </Condition>
          </ConditionGroup>
        </StartTrigger>
        <StopTrigger>
          <ConditionGroup>
            <Condition name="EndCondition" delay="0" conditionEdge="rising">
              <ByEntityCondition>
                <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="hero"/></TriggeringEntities>
                <EntityCondition><TraveledDistanceCondition value="{act_distance:g}"/></EntityCondition>
              </ByEntityCondition>
            </Condition>
          </ConditionGroup>
        </StopTrigger>
      </Act>
    </Story>
    <StopTrigger>
      <ConditionGroup>{stop_groups}
      </ConditionGroup>
    </StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""  # noqa: E501


def write(tmp_path: Path, text: str, name: str = "scenario.xosc") -> Path:
    """Write ``text`` next to a copy of the test street and return the scenario path."""
    shutil.copy(HERE / "avenue.xodr", tmp_path / "avenue.xodr")
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def run(
    path: Path,
    *,
    sut: SutConfig | None = None,
    time_limit: float = 60.0,
    out: Path | None = None,
    overrides: dict[str, str] | None = None,
) -> scenario_execution.RunReport:
    """Run the scenario at ``path`` in-process on the in-memory backend."""
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=path,
            nets_dir=path.parent / "nets",
            sut=sut or SutConfig(),
            criteria=evaluation.Criteria(time_limit=time_limit),
            output_dir=out,
            record=out is not None,
            backend=BackendChoice.MEMORY,
            overrides=overrides or {},
        )
    )


def event(
    name: str, action: str, start: str, *, priority: str = "parallel", private: bool = True
) -> str:
    """An event with one action (``action``: the PrivateAction's body, or with ``private``
    false the whole Action body) and a start condition."""
    body = f"<PrivateAction>{action}</PrivateAction>" if private else action
    return f"""
            <Event name="{name}" priority="{priority}">
              <Action name="{name}">{body}</Action>
              <StartTrigger><ConditionGroup>
                <Condition name="{name}Start" delay="0" conditionEdge="rising">{start}</Condition>
              </ConditionGroup></StartTrigger>
            </Event>"""


def at(seconds: float) -> str:
    """A start condition: simulation time past ``seconds``."""
    return f"""<ByValueCondition>
                  <SimulationTimeCondition value="{seconds:g}" rule="greaterThan"/>
                </ByValueCondition>"""


def after(action: str, state: str = "endTransition") -> str:
    """A start condition: the action called ``action`` passed ``state``."""
    return f"""<ByValueCondition>
                  <StoryboardElementStateCondition storyboardElementType="action"
                    storyboardElementRef="{action}" state="{state}"/>
                </ByValueCondition>"""


def speed(value: float, *, shape: str = "step", dimension: str = "time", over: float = 0) -> str:
    """A SpeedAction body to ``value`` m/s."""
    return f"""<LongitudinalAction><SpeedAction>
                  <SpeedActionDynamics dynamicsShape="{shape}" value="{over:g}"
                    dynamicsDimension="{dimension}"/>
                  <SpeedActionTarget><AbsoluteTargetSpeed value="{value:g}"/></SpeedActionTarget>
                </SpeedAction></LongitudinalAction>"""


def lane_offset(value: float, *, continuous: bool = False) -> str:
    """A LaneOffsetAction body to an absolute offset of ``value`` m."""
    return f"""<LateralAction><LaneOffsetAction continuous="{str(continuous).lower()}">
                  <LaneOffsetActionDynamics dynamicsShape="linear" maxLateralAcc="1"/>
                  <LaneOffsetTarget><AbsoluteTargetLaneOffset value="{value:g}"/></LaneOffsetTarget>
                </LaneOffsetAction></LateralAction>"""


def maneuver(
    events: str,
    *,
    actor: str = "adversary",
    description: str = "CARLA:Rules",
    rev_minor: int = 0,
    hero_control: str = HERO_CONTROL,
    adversary_position: str = '<LanePosition roadId="1" laneId="-2" s="60" offset="0"/>',
    stop: str | None = None,
) -> str:
    """A ScenarioRunner-style file on ``avenue.xodr`` whose one maneuver (for ``actor``) holds
    ``events`` and one that never starts (so the run lasts to the time limit); the hero starts
    at s=20 in lane -1, the adversary stands at ``adversary_position``; the storyboard
    StopTrigger holds ``stop`` (default: CollisionTest)."""
    stop_groups = stop if stop is not None else criteria("CollisionTest", distance=None)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="{rev_minor}" date="2020-03-20T12:00:00" description="{description}" author=""/>
  <ParameterDeclarations/>
  <CatalogLocations/>
  <RoadNetwork><LogicFile filepath="avenue.xodr"/></RoadNetwork>
  <Entities>{vehicle("hero", "ego_vehicle")}{vehicle("adversary", "simulation")}
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
        <Private entityRef="hero">
          <PrivateAction><TeleportAction><Position>
            <LanePosition roadId="1" laneId="-1" s="20" offset="0"/>
          </Position></TeleportAction></PrivateAction>{hero_control}
        </Private>
        <Private entityRef="adversary">
          <PrivateAction><TeleportAction><Position>{adversary_position}</Position></TeleportAction>
          </PrivateAction>
        </Private>
      </Actions>
    </Init>
    <Story name="Story">
      <Act name="Act">
        <ManeuverGroup name="Group" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="{actor}"/></Actors>
          <Maneuver name="Maneuver">{events}{event("Never", speed(0.0), at(1000))}
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup>
          <Condition name="ActStart" delay="0" conditionEdge="rising">{at(0)}</Condition>
        </ConditionGroup></StartTrigger>
      </Act>
    </Story>
    <StopTrigger>
      <ConditionGroup>{stop_groups}
      </ConditionGroup>
    </StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""  # noqa: E501


TOWN01_LANE_Y = 199.14
"""CARLA-frame y of the centre of lane -1 of Town01 road 12 (OpenDRIVE y -199.14, along +x)."""


def traveled(entity: str, metres: float, name: str = "Traveled") -> str:
    return f"""
              <StartTrigger><ConditionGroup><Condition name="{name}" delay="0" conditionEdge="rising">
                <ByEntityCondition>
                  <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="{entity}"/></TriggeringEntities>
                  <EntityCondition><TraveledDistanceCondition value="{metres:g}"/></EntityCondition>
                </ByEntityCondition></Condition></ConditionGroup></StartTrigger>"""  # noqa: E501


def town01_drive(
    *,
    hero_left: float = 0.0,
    hero_x: float = 111.42,
    hero_control: str = HERO_CONTROL,
    entities: str = "",
    init: str = "",
    events: str = "",
    groups: str = "",
    stop: str | None = None,
    distance: float = 40.0,
) -> str:
    """A CARLA-frame drive on Town01 road 12: the hero ``hero_left`` metres left of the centre
    of lane -1 (a WorldPosition with y negated, as ScenarioRunner's authors write them), at rest;
    the story ends once the hero drove ``distance`` metres."""
    stop_groups = stop if stop is not None else criteria(*ALL_CRITERIA, distance=distance / 2)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2024-01-01T00:00:00" description="CARLA:Town01Drive" author=""/>
  <ParameterDeclarations/>
  <CatalogLocations/>
  <RoadNetwork><LogicFile filepath="Town01"/><SceneGraphFile filepath=""/></RoadNetwork>
  <Entities>{vehicle("hero", "ego_vehicle")}{entities}
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
        <Private entityRef="hero">
          <PrivateAction>
            <TeleportAction><Position>
              <WorldPosition x="{hero_x:g}" y="{TOWN01_LANE_Y - hero_left:g}" z="0" h="0"/>
            </Position></TeleportAction>
          </PrivateAction>{hero_control}
        </Private>{init}
      </Actions>
    </Init>
    <Story name="Drive">
      <Act name="Drive">
        <ManeuverGroup name="Hero" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="hero"/></Actors>
          <Maneuver name="Drive">
            <Event name="Arrived" priority="parallel">
              <Action name="Cruise">
                <PrivateAction>{speed(8.33)}</PrivateAction>
              </Action>{traveled("hero", distance)}
            </Event>{events}
          </Maneuver>
        </ManeuverGroup>{groups}
        <StartTrigger><ConditionGroup><Condition name="Start" delay="0" conditionEdge="none">
          <ByValueCondition><SimulationTimeCondition value="0" rule="greaterThan"/></ByValueCondition>
        </Condition></ConditionGroup></StartTrigger>
      </Act>
    </Story>
    <StopTrigger>
      <ConditionGroup>{stop_groups}
      </ConditionGroup>
    </StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""  # noqa: E501


def walker(name: str, *, width: float = 1.0) -> str:
    """A pedestrian whose file box (``width`` square) is not CARLA's walker size."""
    return f"""
    <ScenarioObject name="{name}">
      <Pedestrian model="walker.pedestrian.0001" mass="80" name="walker.pedestrian.0001" pedestrianCategory="pedestrian">
        <ParameterDeclarations/>
        <BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="{width:g}" length="{width:g}" height="1.8"/></BoundingBox>
        <Properties/>
      </Pedestrian>
    </ScenarioObject>"""  # noqa: E501


def walker_crossing(*, x: float, speed: float, after: float) -> tuple[str, str, str]:
    """(entities, init, maneuver group) of a walker on the right sidewalk of Town01 road 12 at
    ``x``, facing the road (CARLA frame: y and heading negated), who sets off at ``speed`` once
    the hero drove ``after`` metres."""
    init = f"""
        <Private entityRef="walker">
          <PrivateAction><TeleportAction><Position>
            <WorldPosition x="{x:g}" y="203.44" z="0" h="-1.5708"/>
          </Position></TeleportAction></PrivateAction>
        </Private>"""
    group = f"""
        <ManeuverGroup name="Walker" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="walker"/></Actors>
          <Maneuver name="Cross">
            <Event name="WalkerCrosses" priority="parallel">
              <Action name="Walk">
                <PrivateAction><LongitudinalAction><SpeedAction>
                  <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
                  <SpeedActionTarget><AbsoluteTargetSpeed value="{speed:g}"/></SpeedActionTarget>
                </SpeedAction></LongitudinalAction></PrivateAction>
              </Action>{traveled("hero", after, "HeroNear")}
            </Event>
          </Maneuver>
        </ManeuverGroup>"""
    return walker("walker"), init, group
