"""Catalog resolution with parameter assignments.

Covers: vehicle, pedestrian, misc-object, controller, maneuver, route and trajectory catalogs
resolved by entry name from CatalogLocations relative to the scenario; ParameterAssignments
(including esmini's ``$``-prefixed parameterRef) overriding entry defaults, evaluated in the
referencing scope; catalog entries seeing the scenario's globals; nested references (a maneuver
entry referencing a trajectory entry); a catalogName that differs from the catalog's declared
name; and errors naming catalog, entry, file and line for missing entries, missing directories,
missing CatalogLocations and assignments to undeclared parameters.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import LoadOptions, StrictDeviationError, load_scenario, model
from simtest_operator.snapshots import EntityKind
from tests.openscenario.conftest import ScenarioWriter

VEHICLES = """<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="1" date="2024-01-01T00:00:00" description="v" author="t"/>
  <Catalog name="DeclaredVehicleName">
    <Vehicle name="truck" vehicleCategory="truck">
      <ParameterDeclarations>
        <ParameterDeclaration name="MaxSpeed" parameterType="double" value="25"/>
        <ParameterDeclaration name="Length" parameterType="double" value="${$MaxSpeed / 2.5}"/>
      </ParameterDeclarations>
      <BoundingBox><Center x="3" y="0" z="1.5"/>
        <Dimensions width="2.5" length="$Length" height="3"/></BoundingBox>
      <Performance maxSpeed="$MaxSpeed" maxAcceleration="2" maxDeceleration="$GlobalDecel"/>
      <Axles>
        <RearAxle maxSteering="0" wheelDiameter="1" trackWidth="2" positionX="0" positionZ="0.5"/>
      </Axles>
    </Vehicle>
  </Catalog>
</OpenSCENARIO>
"""

OTHERS = """<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="1" date="2024-01-01T00:00:00" description="o" author="t"/>
  <Catalog name="Misc">
    <Pedestrian name="walker" model="m" mass="80" pedestrianCategory="pedestrian">
      <BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.5" height="1.8"/>
      </BoundingBox>
      <Properties><Property name="kind" value="adult"/></Properties>
    </Pedestrian>
    <MiscObject name="cone" miscObjectCategory="obstacle" mass="1">
      <BoundingBox><Center x="0" y="0" z="0.3"/><Dimensions width="0.3" length="0.3" height="0.6"/>
      </BoundingBox>
    </MiscObject>
    <Controller name="driver">
      <ParameterDeclarations>
        <ParameterDeclaration name="Gap" parameterType="double" value="1.0"/>
      </ParameterDeclarations>
      <Properties><Property name="timeGap" value="$Gap"/></Properties>
    </Controller>
    <Route name="loop" closed="false">
      <Waypoint routeStrategy="shortest"><Position><LanePosition roadId="1" laneId="-1" s="0"/>
      </Position></Waypoint>
      <Waypoint routeStrategy="fastest"><Position><LanePosition roadId="2" laneId="-1" s="5"/>
      </Position></Waypoint>
    </Route>
    <Trajectory name="wiggle" closed="false">
      <ParameterDeclarations>
        <ParameterDeclaration name="Dy" parameterType="double" value="1"/>
      </ParameterDeclarations>
      <Shape><Polyline>
        <Vertex time="0"><Position><WorldPosition x="0" y="0"/></Position></Vertex>
        <Vertex time="2"><Position><WorldPosition x="20" y="$Dy"/></Position></Vertex>
      </Polyline></Shape>
    </Trajectory>
    <Maneuver name="follow">
      <ParameterDeclarations>
        <ParameterDeclaration name="Offset" parameterType="double" value="0"/>
      </ParameterDeclarations>
      <Event name="E" priority="parallel">
        <Action name="Follow">
          <PrivateAction><RoutingAction><FollowTrajectoryAction>
            <TrajectoryRef>
              <CatalogReference catalogName="Misc" entryName="wiggle">
                <ParameterAssignments>
                  <ParameterAssignment parameterRef="Dy" value="${$Offset * 2}"/>
                </ParameterAssignments>
              </CatalogReference>
            </TrajectoryRef>
            <TimeReference><Timing domainAbsoluteRelative="relative" scale="1" offset="0"/>
            </TimeReference>
            <TrajectoryFollowingMode followingMode="position"/>
          </FollowTrajectoryAction></RoutingAction></PrivateAction>
        </Action>
      </Event>
    </Maneuver>
  </Catalog>
</OpenSCENARIO>
"""

LOCATIONS = """<VehicleCatalog><Directory path="catalogs/vehicles"/></VehicleCatalog>
<PedestrianCatalog><Directory path="catalogs/others"/></PedestrianCatalog>
<MiscObjectCatalog><Directory path="catalogs/others"/></MiscObjectCatalog>
<ControllerCatalog><Directory path="catalogs/others"/></ControllerCatalog>
<RouteCatalog><Directory path="catalogs/others"/></RouteCatalog>
<TrajectoryCatalog><Directory path="catalogs/others"/></TrajectoryCatalog>
<ManeuverCatalog><Directory path="catalogs/others"/></ManeuverCatalog>
"""

ENTITIES = """<ScenarioObject name="Truck">
  <CatalogReference catalogName="VehicleCatalog" entryName="$TruckEntry">
    <ParameterAssignments>
      <ParameterAssignment parameterRef="$MaxSpeed" value="${$Base * 2}"/>
    </ParameterAssignments>
  </CatalogReference>
  <ObjectController>
    <CatalogReference catalogName="Misc" entryName="driver">
      <ParameterAssignments><ParameterAssignment parameterRef="Gap" value="2.5"/>
      </ParameterAssignments>
    </CatalogReference>
  </ObjectController>
</ScenarioObject>
<ScenarioObject name="Walker"><CatalogReference catalogName="Misc" entryName="walker"/>
</ScenarioObject>
<ScenarioObject name="Cone"><CatalogReference catalogName="Misc" entryName="cone"/>
</ScenarioObject>"""

STORY = """<Story name="S"><Act name="A">
  <ManeuverGroup name="G" maximumExecutionCount="1">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Truck"/></Actors>
    <CatalogReference catalogName="Misc" entryName="follow">
      <ParameterAssignments><ParameterAssignment parameterRef="Offset" value="3"/>
      </ParameterAssignments>
    </CatalogReference>
  </ManeuverGroup>
</Act></Story>"""

INIT = """<Private entityRef="Truck"><PrivateAction><RoutingAction><AssignRouteAction>
  <CatalogReference catalogName="Misc" entryName="loop"/>
</AssignRouteAction></RoutingAction></PrivateAction></Private>"""

GLOBALS = """<ParameterDeclaration name="TruckEntry" parameterType="string" value="truck"/>
<ParameterDeclaration name="Base" parameterType="double" value="15"/>
<ParameterDeclaration name="GlobalDecel" parameterType="double" value="6"/>"""


@pytest.fixture
def catalog_dirs(tmp_path: Path) -> Path:
    (tmp_path / "catalogs" / "vehicles").mkdir(parents=True)
    (tmp_path / "catalogs" / "others").mkdir()
    (tmp_path / "catalogs" / "vehicles" / "VehicleCatalog.xosc").write_text(VEHICLES)
    (tmp_path / "catalogs" / "others" / "Others.xosc").write_text(OTHERS)
    return tmp_path


def test_resolves_every_catalog_kind(write_scenario: ScenarioWriter, catalog_dirs: Path) -> None:
    path = write_scenario(
        parameters=GLOBALS, catalogs=LOCATIONS, entities=ENTITIES, init=INIT, stories=STORY
    )
    scenario = load_scenario(path)
    truck, walker, cone = scenario.entities
    assert truck.kind is EntityKind.VEHICLE
    assert truck.category == "truck"
    assert truck.catalog_entry == "truck"
    assert truck.performance is not None
    assert truck.performance.max_speed == 30.0  # assigned ${$Base * 2}
    assert truck.performance.max_deceleration == 6.0  # entry sees the scenario's globals
    assert truck.bounding_box.length == 12.0  # default derived from the assigned MaxSpeed
    assert truck.axles is not None and truck.axles.front is None
    assert isinstance(truck.controller, model.Controller)
    assert truck.controller.property("timeGap") == "2.5"
    assert walker.kind is EntityKind.PEDESTRIAN
    assert walker.mass == 80.0
    assert walker.property("kind") == "adult"
    assert cone.kind is EntityKind.MISC_OBJECT and cone.category == "obstacle"

    (assign,) = scenario.storyboard.init.private[0].actions
    assert isinstance(assign, model.AssignRouteAction)
    assert isinstance(assign.route, model.Route)
    assert [w.route_strategy for w in assign.route.waypoints] == [
        model.RouteStrategy.SHORTEST,
        model.RouteStrategy.FASTEST,
    ]

    (maneuver,) = scenario.storyboard.stories[0].acts[0].maneuver_groups[0].maneuvers
    assert maneuver.name == "follow"
    follow = maneuver.events[0].actions[0].body
    assert isinstance(follow, model.FollowTrajectoryAction)
    assert follow.timing is not None
    assert follow.timing.domain is model.ReferenceContext.RELATIVE
    assert (follow.timing.scale, follow.timing.offset) == (1.0, 0.0)
    assert follow.following_mode is model.FollowingMode.POSITION
    assert isinstance(follow.trajectory, model.Trajectory)
    assert isinstance(follow.trajectory.shape, model.Polyline)
    last = follow.trajectory.shape.vertices[-1]
    assert isinstance(last.position, model.WorldPosition)
    assert last.position.y == 6.0  # nested assignment ${$Offset * 2} with Offset=3
    assert last.time == 2.0
    assert scenario.unsupported() == ()


def test_missing_entry_names_catalog_entry_file_line(
    write_scenario: ScenarioWriter, catalog_dirs: Path
) -> None:
    path = write_scenario(
        parameters=GLOBALS.replace('value="truck"', 'value="bus"'),
        catalogs=LOCATIONS,
        entities=ENTITIES,
    )
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    error = info.value
    assert "catalog 'VehicleCatalog' has no Vehicle/Pedestrian/MiscObject entry 'bus'" in str(error)
    assert error.file == str(path.resolve())
    assert error.element == "CatalogReference"
    assert error.line is not None
    assert path.read_text().splitlines()[error.line - 1].lstrip().startswith("<CatalogReference")


def test_missing_directory_and_locations(write_scenario: ScenarioWriter, tmp_path: Path) -> None:
    path = write_scenario(parameters=GLOBALS, catalogs=LOCATIONS, entities=ENTITIES)
    with pytest.raises(ScenarioError, match="missing directories"):
        load_scenario(path)
    path = write_scenario(parameters=GLOBALS, entities=ENTITIES)
    with pytest.raises(ScenarioError, match="declares no CatalogLocations"):
        load_scenario(path)


def test_assignment_to_undeclared_parameter(
    write_scenario: ScenarioWriter, catalog_dirs: Path
) -> None:
    # esmini ignores the assignment; we too, with a warning (a typo is refused under --strict)
    entities = ENTITIES.replace('parameterRef="Gap"', 'parameterRef="Gpa"')
    path = write_scenario(parameters=GLOBALS, catalogs=LOCATIONS, entities=entities)
    deviations = load_scenario(path).deviations
    assert [d.code for d in deviations] == ["parameter-assignment-undeclared"]
    assert deviations[0].message.endswith("ignored: Gpa")
    assert deviations[0].file.endswith("Others.xosc")
    with pytest.raises(StrictDeviationError, match="Gpa"):
        load_scenario(path, options=LoadOptions(strict=True))


def test_hostile_catalog_file_is_rejected(
    write_scenario: ScenarioWriter, catalog_dirs: Path
) -> None:
    evil = catalog_dirs / "catalogs" / "vehicles" / "Evil.xosc"
    evil.write_text('<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY e "e">]>\n<OpenSCENARIO/>')
    path = write_scenario(parameters=GLOBALS, catalogs=LOCATIONS, entities=ENTITIES)
    with pytest.raises(ScenarioError, match="not allowed") as info:
        load_scenario(path)
    assert info.value.file == str(evil)
