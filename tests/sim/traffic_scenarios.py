"""Scenario files with TrafficActions for the traffic tests, and a runner collecting snapshots."""

from __future__ import annotations

from pathlib import Path

from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig, Takeover, open_simulation
from simtest_operator.snapshots import WorldSnapshot

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini" / "resources"
STRAIGHT = CORPUS / "xodr" / "straight_500m.xodr"
"""Road 1 along +x from 0 to 500 m; lane -1 (centre y = -1.535) drives +x, lane 1 drives -x."""
E6MINI = CORPUS / "xodr" / "e6mini.xodr"
"""A long curved road with 4 lanes each way."""

_CAR = """<ScenarioObject name="{name}"><Vehicle name="car" vehicleCategory="car">
<BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="1.8" length="4.5" height="1.5"/>
</BoundingBox><Performance maxSpeed="69" maxAcceleration="10" maxDeceleration="10"/>
<Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.8" trackWidth="1.7" positionX="2.9"
positionZ="0.4"/><RearAxle maxSteering="0" wheelDiameter="0.8" trackWidth="1.7" positionX="0"
positionZ="0.4"/></Axles><Properties/></Vehicle></ScenarioObject>"""

_PLACE = """<Private entityRef="{name}"><PrivateAction><TeleportAction><Position>
<LanePosition roadId="{road}" laneId="{lane}" offset="0" s="{s}"/></Position></TeleportAction>
</PrivateAction><PrivateAction><LongitudinalAction><SpeedAction>
<SpeedActionDynamics dynamicsShape="step" dynamicsDimension="time" value="0"/>
<SpeedActionTarget><AbsoluteTargetSpeed value="{speed}"/></SpeedActionTarget></SpeedAction>
</LongitudinalAction></PrivateAction></Private>"""

_SCENARIO = """<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
<FileHeader revMajor="1" revMinor="{minor}" date="2024-01-01T00:00:00" description="traffic"
 author="tests"/>
<ParameterDeclarations/>
<CatalogLocations/>
<RoadNetwork>{road}</RoadNetwork>
<Entities>{entities}</Entities>
<Storyboard><Init><Actions>
{places}
{init_traffic}
</Actions></Init>
{stories}
<StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="none">
<ByValueCondition><SimulationTimeCondition value="{end}" rule="greaterThan"/></ByValueCondition>
</Condition></ConditionGroup></StopTrigger>
</Storyboard>
</OpenSCENARIO>
"""


def traffic_event(name: str, body: str, at: float) -> str:
    """A story with one event running the global action ``body`` at time ``at``."""
    return f"""<Story name="S_{name}"><Act name="A_{name}"><ManeuverGroup
maximumExecutionCount="1" name="G_{name}"><Actors selectTriggeringEntities="false"/>
<Maneuver name="M_{name}"><Event name="{name}" priority="parallel"><Action name="{name}">
<GlobalAction>{body}</GlobalAction></Action><StartTrigger><ConditionGroup>
<Condition name="t_{name}" delay="0" conditionEdge="rising"><ByValueCondition>
<SimulationTimeCondition value="{at}" rule="greaterThan"/></ByValueCondition></Condition>
</ConditionGroup></StartTrigger></Event></Maneuver></ManeuverGroup><StartTrigger>
<ConditionGroup><Condition name="go_{name}" delay="0" conditionEdge="none"><ByValueCondition>
<SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition></Condition>
</ConditionGroup></StartTrigger></Act></Story>"""


def write(
    directory: Path,
    *,
    road: Path | None,
    entities: dict[str, tuple[str, int, float, float]],
    init_traffic: str = "",
    stories: str = "",
    end: float = 10.0,
    minor: int = 2,
    name: str = "traffic.xosc",
) -> Path:
    """A scenario on ``road``; ``entities`` maps names to (road id, lane id, s, speed)."""
    text = _SCENARIO.format(
        minor=minor,
        road=f'<LogicFile filepath="{road}"/>' if road is not None else "",
        entities="".join(_CAR.format(name=n) for n in entities),
        places="".join(
            _PLACE.format(name=n, road=r, lane=lane, s=s, speed=v)
            for n, (r, lane, s, v) in entities.items()
        ),
        init_traffic=f"<GlobalAction>{init_traffic}</GlobalAction>" if init_traffic else "",
        stories=stories,
        end=end,
    )
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path


def run(
    path: Path,
    nets: Path,
    *,
    seed: int = 42,
    backend: BackendChoice = BackendChoice.SUMO,
    limit: float = 60.0,
) -> list[WorldSnapshot]:
    """Run ``path`` to its end (scripted ego) and return every snapshot."""
    opened = open_simulation(
        path,
        sut=SutConfig(takeover=Takeover.NEVER),
        settings=SimulationSettings(seed=seed),
        nets_dir=nets,
        backend=backend,
    )
    simulation = opened.simulation
    try:
        snapshots = [simulation.start()]
        while not simulation.complete and simulation.time < limit:
            snapshots.append(simulation.step())
    finally:
        simulation.close()
    return snapshots


def traffic_of(snapshot: WorldSnapshot) -> dict[str, tuple[float, float]]:
    """Positions of the anonymous traffic vehicles in a snapshot."""
    return {e.name: (e.x, e.y) for e in snapshot.entities if e.name.startswith("traffic_")}
