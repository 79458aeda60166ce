"""Small authored scenarios on ``data/straight.xodr`` for the OpenSCENARIO coverage tests, and
a helper that runs one on the in-memory backend with a scripted ego."""

from __future__ import annotations

import shutil
from pathlib import Path

from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig, Takeover

DATA = Path(__file__).parent / "data"

CAR = """<ScenarioObject name="{name}"><Vehicle name="car" vehicleCategory="car">
  <BoundingBox><Center x="1.4" y="0" z="0.9"/><Dimensions width="2" length="4.5" height="1.5"/>
  </BoundingBox><Performance maxSpeed="60" maxAcceleration="5" maxDeceleration="10"/>
  <Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.7" positionX="2.8"
  positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.7" positionX="0"
  positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject>"""

WALKER = """<ScenarioObject name="{name}"><Pedestrian name="walker" mass="80" model="p"
  pedestrianCategory="pedestrian"><BoundingBox><Center x="0" y="0" z="0.9"/>
  <Dimensions width="0.5" length="0.5" height="1.8"/></BoundingBox><Properties/></Pedestrian>
  </ScenarioObject>"""


def place(name: str, *, lane: int = -1, s: float = 20.0, speed: float = 10.0) -> str:
    """An Init ``Private`` putting ``name`` on road 1 at ``s`` driving at ``speed``."""
    return (
        f'<Private entityRef="{name}"><PrivateAction><TeleportAction><Position>'
        f'<LanePosition roadId="1" laneId="{lane}" offset="0" s="{s}"/></Position>'
        "</TeleportAction></PrivateAction><PrivateAction><LongitudinalAction><SpeedAction>"
        '<SpeedActionDynamics dynamicsShape="step" dynamicsDimension="time" value="0"/>'
        f'<SpeedActionTarget><AbsoluteTargetSpeed value="{speed}"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction></Private>"
    )


def by_value(inner: str, *, name: str = "c", edge: str = "rising") -> str:
    """A ``Condition`` around a ByValueCondition child."""
    return (
        f'<Condition name="{name}" delay="0" conditionEdge="{edge}">'
        f"<ByValueCondition>{inner}</ByValueCondition></Condition>"
    )


def at_time(seconds: float, *, name: str = "c", edge: str = "rising") -> str:
    """A condition true once the simulation time is past ``seconds``."""
    condition = f'<SimulationTimeCondition value="{seconds}" rule="greaterThan"/>'
    return by_value(condition, name=name, edge=edge)


def story(actors: str, action: str, start: str, *, event: str = "E") -> str:
    """One story, act and maneuver group for ``actors`` (EntityRef elements) running ``action``
    (an ``<Action>`` body) when ``start`` (Condition elements) holds."""
    return (
        '<Story name="S"><Act name="A"><ManeuverGroup name="G" maximumExecutionCount="1">'
        f'<Actors selectTriggeringEntities="false">{actors}</Actors><Maneuver name="M">'
        f'<Event name="{event}" priority="override"><Action name="{event}Action">{action}</Action>'
        f"<StartTrigger><ConditionGroup>{start}</ConditionGroup></StartTrigger></Event>"
        "</Maneuver></ManeuverGroup><StartTrigger><ConditionGroup>"
        + at_time(-1, name="go", edge="none")
        + "</ConditionGroup></StartTrigger></Act></Story>"
    )


def speed_action(value: float) -> str:
    """A PrivateAction stepping the actor's speed to ``value``."""
    return (
        "<PrivateAction><LongitudinalAction><SpeedAction>"
        '<SpeedActionDynamics dynamicsShape="step" dynamicsDimension="time" value="0"/>'
        f'<SpeedActionTarget><AbsoluteTargetSpeed value="{value}"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction>"
    )


def scenario(
    *,
    entities: str,
    init: str,
    stories: str = "",
    stop: str = "",
    minor: int = 3,
    declarations: str = "",
    environment: str = "",
) -> str:
    """A whole scenario on ``straight.xodr``; ``declarations`` go after the (empty)
    ParameterDeclarations (VariableDeclarations, MonitorDeclarations), ``environment`` is a
    GlobalAction in Init."""
    stop_trigger = f"<StopTrigger><ConditionGroup>{stop}</ConditionGroup></StopTrigger>"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="{minor}" date="2026-01-01T00:00:00" description="t"
              author="simtest"/>
  <ParameterDeclarations/>
  {declarations}
  <CatalogLocations/>
  <RoadNetwork><LogicFile filepath="straight.xodr"/></RoadNetwork>
  <Entities>{entities}</Entities>
  <Storyboard>
    <Init><Actions>{environment}{init}</Actions></Init>
    {stories}
    {stop_trigger if stop else ""}
  </Storyboard>
</OpenSCENARIO>
"""


def write(tmp_path: Path, text: str, name: str = "scenario.xosc") -> Path:
    """Write ``text`` next to a copy of ``straight.xodr``; return its path."""
    shutil.copy(DATA / "straight.xodr", tmp_path / "straight.xodr")
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def run(
    path: Path,
    tmp_path: Path,
    *,
    seed: int | None = None,
    takeover: Takeover = Takeover.NEVER,
) -> scenario_execution.RunReport:
    """Run ``path`` on the in-memory backend, the ego scripted unless ``takeover`` says."""
    simulation = SimulationSettings() if seed is None else SimulationSettings(seed=seed)
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=path,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(takeover=takeover),
            simulation=simulation,
        )
    )


def with_controller(text: str, entity: str, properties: str) -> str:
    """``text`` with an ObjectController ``ctrl`` of ``properties`` on vehicle ``entity``."""
    controller = (
        f'<ObjectController><Controller name="ctrl"><Properties>{properties}</Properties>'
        "</Controller></ObjectController>"
    )
    marker = f'<ScenarioObject name="{entity}">'
    head, tail = text.split(marker)
    end = tail.index("</Vehicle>") + len("</Vehicle>")
    return head + marker + tail[:end] + controller + tail[end:]
