"""Files written for CARLA: town names, CARLA's frame, degrees, and references kept in their tree.

Covers: ``<LogicFile filepath="Town01"/>`` resolves to the shipped CARLA town, a user map library
(``LoadOptions.maps``, ``SIMTEST_MAP_PATH``) resolves ``MyTrack`` and overrides a shipped town, an
unknown name is an error listing the folders searched; a ``CARLA:`` file's WorldPosition y and
heading, RoadPosition t and a TrajectoryPosition's polyline are negated into OpenDRIVE's frame
and the engine places the entities on the intended lanes of Town01; ``h="180"`` is read as
degrees (deviation), fractional headings beyond a turn stay radians; TrajectoryPosition ``s``/``t``
along a polyline; strict mode refuses the CARLA file; a 0.9 catalog header is a deviation; the
rule set each of ScenarioRunner's conventions chooses while the frame follows the header alone;
a LaneOffsetAction's target positive to the right under ScenarioRunner's rules.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simtest_operator import maps
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import (
    LoadOptions,
    StrictDeviationError,
    load_scenario,
    model,
    rulesets,
)
from simtest_operator.runner import scenario_execution
from simtest_operator.settings import Settings
from simtest_operator.sim import BackendChoice
from tests.openscenario.conftest import ScenarioWriter

CARLA_DIR = Path(__file__).resolve().parent / "carla"
TOWN01_FILE = CARLA_DIR / "town01_carla_frame.xosc"
LANE_MINUS_ONE_Y = -199.14
"""OpenDRIVE y of lane -1 of Town01 road 12 (see carla/README.md)."""


def _teleport(scenario: model.Scenario, entity: str) -> model.Position:
    for private in scenario.storyboard.init.private:
        if private.entity_ref == entity:
            action = private.actions[0]
            assert isinstance(action, model.TeleportAction)
            return action.position
    raise AssertionError(entity)


def test_town_name_resolves_to_the_shipped_carla_map() -> None:
    scenario = load_scenario(TOWN01_FILE)
    assert scenario.road_network.logic_file == maps.SHIPPED / "Town01.xodr"
    assert (maps.SHIPPED / "LICENSE").is_file() and (maps.SHIPPED / "README.md").is_file()
    assert maps.MapLibraries.with_user().names() == (
        "Town01",
        "Town02",
        "Town04",
        "Town06",
        "Town07",
        "Town10HD",
    )


def test_carla_frame_is_negated_into_opendrive() -> None:
    scenario = load_scenario(TOWN01_FILE)
    ego = _teleport(scenario, "Ego")
    assert isinstance(ego, model.WorldPosition)
    assert (ego.x, ego.y, ego.h) == (111.42, LANE_MINUS_ONE_Y, 0.0)
    oncoming = _teleport(scenario, "Oncoming")
    assert isinstance(oncoming, model.RoadPosition)
    assert oncoming.t == 2.0  # t="-2" is to the left in CARLA's frame
    assert oncoming.orientation is not None
    assert oncoming.orientation.h == pytest.approx(-math.pi)  # h="180" degrees, negated
    parked = _teleport(scenario, "Parked")
    assert isinstance(parked, model.TrajectoryPosition)
    assert isinstance(parked.trajectory, model.Trajectory)
    shape = parked.trajectory.shape
    assert isinstance(shape, model.Polyline)
    first = shape.vertices[0].position
    assert isinstance(first, model.WorldPosition) and first.y == LANE_MINUS_ONE_Y
    assert [d.code for d in scenario.deviations] == ["parameter-type-int", "heading-in-degrees"]
    assert any("CARLA's left-handed frame" in note for note in scenario.notes)


def test_engine_places_carla_entities_on_their_lanes(tmp_path: Path) -> None:
    settings = Settings.from_env({"SIMTEST_CACHE_DIR": str(tmp_path)})
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=TOWN01_FILE,
            nets_dir=settings.cache.nets,
            backend=BackendChoice.MEMORY,
            record=False,
            loading=LoadOptions(source_root=CARLA_DIR),
        )
    )
    assert report.outcome.verdict.value == "Passed", report.outcome.reason
    first = {name: samples[0] for name, samples in report.samples.items()}
    _, x, y, heading, _ = first["Ego"]
    assert (x, y) == pytest.approx((111.42, LANE_MINUS_ONE_Y), abs=0.01)
    assert heading == pytest.approx(0.0, abs=1e-3)
    _, x, y, heading, _ = first["Oncoming"]  # lane 1 at s=90, facing -x
    assert (x, y) == pytest.approx((191.42, -195.15), abs=0.01)
    assert abs(math.remainder(heading - math.pi, 2 * math.pi)) < 1e-3
    _, x, y, heading, _ = first["Parked"]  # 80 m along the polyline
    assert (x, y) == pytest.approx((191.42, LANE_MINUS_ONE_Y), abs=0.01)
    _, x, _, _, speed = report.samples["Ego"][-1]
    assert speed == pytest.approx(10.0)  # the int parameter
    assert [d.code for d in report.deviations] == ["parameter-type-int", "heading-in-degrees"]


def test_strict_mode_refuses_the_carla_file() -> None:
    with pytest.raises(StrictDeviationError, match="parameter-type-int"):
        load_scenario(TOWN01_FILE, options=LoadOptions(strict=True))


def test_user_map_library_resolves_names_and_overrides_towns(
    tmp_path: Path, write_scenario: ScenarioWriter
) -> None:
    library = tmp_path / "maps"
    library.mkdir()
    track = (maps.SHIPPED / "Town02.xodr").read_bytes()
    (library / "MyTrack.xodr").write_bytes(track)
    (library / "Town01.xodr").write_bytes(track)
    path = write_scenario(name="mine.xosc", road='<LogicFile filepath="MyTrack"/>')
    options = LoadOptions(maps=(library,))
    assert load_scenario(path, options=options).road_network.logic_file == library / "MyTrack.xodr"
    town = write_scenario(name="town.xosc", road='<LogicFile filepath="Town01.xodr"/>')
    assert load_scenario(town, options=options).road_network.logic_file == library / "Town01.xodr"
    assert load_scenario(town).road_network.logic_file == maps.SHIPPED / "Town01.xodr"
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path)
    message = str(caught.value)
    assert "road network file 'MyTrack' not found" in message
    assert str(maps.SHIPPED) in message and "which hold Town01, Town02" in message
    assert caught.value.element == "LogicFile"


def test_map_path_setting() -> None:
    settings = Settings.from_env({"SIMTEST_MAP_PATH": "/a/maps::/b/maps", "HOME": "/h"})
    assert settings.maps == (Path("/a/maps"), Path("/b/maps"))
    assert Settings.from_env({"HOME": "/h"}).maps == ()


def test_map_names_never_leave_a_library(tmp_path: Path) -> None:
    library = maps.MapLibraries.with_user((tmp_path,))
    (tmp_path / "link.xodr").symlink_to(maps.SHIPPED / "Town01.xodr")
    assert library.find("link") is None  # a symlink out of the library folder
    assert library.find("../carla/Town01") is None
    assert library.find("..") is None
    assert library.find("Town01") == maps.SHIPPED / "Town01.xodr"


def test_fractional_headings_beyond_a_turn_stay_radians(write_scenario: ScenarioWriter) -> None:
    init = """<Private entityRef="Ego"><PrivateAction><TeleportAction><Position>
    <WorldPosition x="0" y="0" h="7.853981633974483"/></Position></TeleportAction>
    </PrivateAction></Private>"""
    scenario = load_scenario(write_scenario(init=init))
    position = _teleport(scenario, "Ego")
    assert isinstance(position, model.WorldPosition) and position.h == 7.853981633974483
    assert scenario.deviations == ()
    in_degrees = init.replace('h="7.853981633974483"', 'h="93"')
    degrees = load_scenario(write_scenario(name="d.xosc", init=in_degrees))
    position = _teleport(degrees, "Ego")
    assert isinstance(position, model.WorldPosition)
    assert position.h == pytest.approx(math.radians(93))
    assert [d.code for d in degrees.deviations] == ["heading-in-degrees"]


def test_old_catalog_header_is_a_deviation(tmp_path: Path, write_scenario: ScenarioWriter) -> None:
    folder = tmp_path / "Controllers"
    folder.mkdir()
    (folder / "old.xosc").write_text(
        """<OpenSCENARIO><FileHeader revMajor="0" revMinor="9" date="2019-01-01T00:00:00"
  description="0.9" author="t"/>
<Catalog name="Ctl"><Controller name="drv"><Properties/></Controller></Catalog></OpenSCENARIO>""",
        encoding="utf-8",
    )
    entities = """<ScenarioObject name="Ego"><Vehicle name="car" vehicleCategory="car">
    <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="2" length="5" height="1.5"/>
    </BoundingBox><Performance maxSpeed="69" maxAcceleration="10" maxDeceleration="10"/>
    <Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.8" trackWidth="1.7" positionX="2.9"
    positionZ="0.4"/><RearAxle maxSteering="0" wheelDiameter="0.8" trackWidth="1.7"
    positionX="0" positionZ="0.4"/></Axles></Vehicle>
    <ObjectController><CatalogReference catalogName="Ctl" entryName="drv"/></ObjectController>
    </ScenarioObject>"""
    path = write_scenario(
        catalogs='<ControllerCatalog><Directory path="Controllers"/></ControllerCatalog>',
        entities=entities,
    )
    scenario = load_scenario(path)
    (deviation,) = scenario.deviations
    assert deviation.code == "catalog-revision-0"
    assert deviation.file == str(folder / "old.xosc")
    assert "0.9 catalog header read as 1.0" in deviation.message


def _controller(module: str) -> str:
    return f"""
        <Private entityRef="Ego"><PrivateAction><ControllerAction><AssignControllerAction>
          <Controller name="Driver"><Properties>
            <Property name="module" value="{module}"/>
          </Properties></Controller>
        </AssignControllerAction></ControllerAction></PrivateAction></Private>"""


_CRITERION = """
    <ConditionGroup>
      <Condition name="criteria_CollisionTest" delay="0" conditionEdge="rising">
        <ByValueCondition><ParameterCondition parameterRef="" value="" rule="lessThan"/>
        </ByValueCondition>
      </Condition>
    </ConditionGroup>"""


@pytest.mark.parametrize(
    ("parts", "header", "rules"),
    [
        ({}, "test", "OpenSCENARIO (esmini)"),
        ({}, "CARLA:Mine", "ScenarioRunner (description 'CARLA:')"),
        ({"stop": _CRITERION}, "test", "ScenarioRunner (criteria_* conditions)"),
        (
            {"init": _controller("srunner/actorcontrols/carla_autopilot.py")},
            "test",
            "ScenarioRunner (controller module carla_autopilot)",
        ),
        ({"init": _controller("my_own_driver")}, "test", "OpenSCENARIO (esmini)"),
        ({"road": '<LogicFile filepath="Town01"/>'}, "test", "ScenarioRunner (CARLA town Town01)"),
    ],
)
def test_rule_set_follows_scenario_runners_conventions(
    write_scenario: ScenarioWriter, parts: dict[str, str], header: str, rules: str
) -> None:
    path = write_scenario(**parts)
    path.write_text(
        path.read_text(encoding="utf-8").replace('description="test"', f'description="{header}"'),
        encoding="utf-8",
    )
    scenario = load_scenario(path)
    assert rulesets.rules_of(scenario).describe() == rules
    # The frame is the header's alone (ScenarioRunner's use_carla_coordinate_system).
    assert any("CARLA's left-handed frame" in note for note in scenario.notes) == (
        header.startswith("CARLA:")
    )


_OFFSETS = """
    <Story name="S"><Act name="A">
      <ManeuverGroup name="G" maximumExecutionCount="1">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
        <Maneuver name="M"><Event name="E" priority="parallel">
          <Action name="Absolute"><PrivateAction><LateralAction>
            <LaneOffsetAction continuous="false">
              <LaneOffsetActionDynamics dynamicsShape="linear" maxLateralAcc="1"/>
              <LaneOffsetTarget><AbsoluteTargetLaneOffset value="0.5"/></LaneOffsetTarget>
            </LaneOffsetAction>
          </LateralAction></PrivateAction></Action>
          <Action name="Relative"><PrivateAction><LateralAction>
            <LaneOffsetAction continuous="false">
              <LaneOffsetActionDynamics dynamicsShape="linear" maxLateralAcc="1"/>
              <LaneOffsetTarget><RelativeTargetLaneOffset entityRef="Ego" value="0.3"/>
              </LaneOffsetTarget>
            </LaneOffsetAction>
          </LateralAction></PrivateAction></Action>
        </Event></Maneuver>
      </ManeuverGroup>
    </Act></Story>"""


@pytest.mark.parametrize(
    ("header", "stop", "side"),
    [("CARLA:Mine", "", -1.0), ("test", _CRITERION, -1.0), ("test", "", 1.0)],
)
def test_lane_offset_action_target_is_positive_to_the_right_for_scenario_runner(
    write_scenario: ScenarioWriter, header: str, stop: str, side: float
) -> None:
    # Positive is to the right in a CARLA: file, as its other lateral offsets, and in any file
    # under ScenarioRunner's rules (it measures offsets from the waypoint in CARLA's frame).
    path = write_scenario(stories=_OFFSETS, stop=stop)
    path.write_text(
        path.read_text(encoding="utf-8").replace('description="test"', f'description="{header}"'),
        encoding="utf-8",
    )
    event = load_scenario(path).storyboard.stories[0].acts[0].maneuver_groups[0]
    targets = []
    for action in event.maneuvers[0].events[0].actions:
        assert isinstance(action.body, model.LaneOffsetAction)
        targets.append(action.body.target.value)
    assert targets == [side * 0.5, side * 0.3]
