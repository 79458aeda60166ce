"""Accepted deviations: reported with code and line, collected per load, refused in strict mode.

Covers: ``parameterType="int"``/``"bool"`` read as integer/boolean with a deviation (global
parameters, VariableDeclarations, catalog entry parameters); strict mode turns the first one into
an Invalid-making StrictDeviationError at its element and line; a schema-conformant file has
none; deviation codes must be kebab-case.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.openscenario import LoadOptions, StrictDeviationError, load_scenario, model
from simtest_operator.openscenario.deviations import Deviation, Deviations
from tests.openscenario.conftest import ScenarioWriter

STRICT = LoadOptions(strict=True)


def test_int_parameter_is_an_integer_with_a_deviation(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters="""<ParameterDeclaration name="Lanes" parameterType="int" value="3"/>
        <ParameterDeclaration name="On" parameterType="bool" value="true"/>"""
    )
    scenario = load_scenario(path)
    lanes, on = scenario.parameter("Lanes"), scenario.parameter("On")
    assert lanes is not None and lanes.value == 3 and isinstance(lanes.value, int)
    assert on is not None and on.value is True
    assert [d.code for d in scenario.deviations] == ["parameter-type-int", "parameter-type-bool"]
    first = scenario.deviations[0]
    assert first.element == "ParameterDeclaration"
    assert first.line == 6
    assert first.file == str(path)
    assert "'int' read as 'integer'" in first.describe()
    assert f"{path}:6" in first.describe()


def test_strict_mode_refuses_the_deviation(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters='<ParameterDeclaration name="Lanes" parameterType="int" value="3"/>'
    )
    with pytest.raises(StrictDeviationError) as caught:
        load_scenario(path, options=STRICT)
    assert caught.value.line == 6
    assert caught.value.element == "ParameterDeclaration"
    assert "strict mode" in str(caught.value) and "parameter-type-int" in str(caught.value)


def test_conformant_file_has_no_deviations(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters='<ParameterDeclaration name="Lanes" parameterType="integer" value="3"/>'
    )
    assert load_scenario(path, options=STRICT).deviations == ()


def test_unknown_parameter_type_stays_an_error(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters='<ParameterDeclaration name="Lanes" parameterType="long" value="3"/>'
    )
    with pytest.raises(Exception, match="unknown parameterType 'long'"):
        load_scenario(path)


def test_int_in_a_catalog_entry_is_reported_in_the_catalog_file(
    write_scenario: ScenarioWriter, tmp_path: Path
) -> None:
    catalogs = tmp_path / "Vehicles"
    catalogs.mkdir()
    (catalogs / "cars.xosc").write_text(
        """<OpenSCENARIO><FileHeader revMajor="1" revMinor="0" date="2024-01-01T00:00:00"
  description="c" author="t"/>
<Catalog name="Cars">
  <Vehicle name="car" vehicleCategory="car">
    <ParameterDeclarations>
      <ParameterDeclaration name="MaxSpeed" parameterType="int" value="50"/>
    </ParameterDeclarations>
    <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="2" length="5" height="1.5"/>
    </BoundingBox>
    <Performance maxSpeed="$MaxSpeed" maxAcceleration="10" maxDeceleration="10"/>
    <Axles>
      <FrontAxle maxSteering="0.5" wheelDiameter="0.8" trackWidth="1.7" positionX="2.9"
                 positionZ="0.4"/>
      <RearAxle maxSteering="0" wheelDiameter="0.8" trackWidth="1.7" positionX="0" positionZ="0.4"/>
    </Axles>
  </Vehicle>
</Catalog></OpenSCENARIO>""",
        encoding="utf-8",
    )
    path = write_scenario(
        catalogs='<VehicleCatalog><Directory path="Vehicles"/></VehicleCatalog>',
        entities="""<ScenarioObject name="Ego"><CatalogReference catalogName="Cars" entryName="car">
        <ParameterAssignments><ParameterAssignment parameterRef="MaxSpeed" value="40"/>
        </ParameterAssignments></CatalogReference></ScenarioObject>""",
    )
    scenario = load_scenario(path)
    (deviation,) = scenario.deviations
    assert deviation.file == str(catalogs / "cars.xosc")
    assert deviation.line == 6
    ego = scenario.entity("Ego")
    assert ego is not None
    with pytest.raises(StrictDeviationError):
        load_scenario(path, options=STRICT)


def test_variable_declaration_int(tmp_path: Path, write_scenario: ScenarioWriter) -> None:
    path = write_scenario()
    text = path.read_text(encoding="utf-8").replace(
        "<CatalogLocations>",
        '<VariableDeclarations><VariableDeclaration name="n" variableType="int" value="1"/>'
        "</VariableDeclarations>\n  <CatalogLocations>",
    )
    path.write_text(text, encoding="utf-8")
    scenario = load_scenario(path)
    variable = scenario.variable("n")
    assert variable is not None and variable.value == 1
    assert [d.code for d in scenario.deviations] == ["parameter-type-int"]


def test_codes_are_kebab_case() -> None:
    deviations = Deviations()
    with pytest.raises(ValueError, match="kebab-case"):
        deviations.report(Deviation(code="Bad Code", message="m", file="f", element="E", line=1))
    deviations.report(Deviation(code="ok-code", message="m", file="f", element="E", line=None))
    assert deviations.found[0].describe() == "m [ok-code] (f:? <E>)"


OWNED_STORY = """<Story name="S">
  <ParameterDeclarations>
    <ParameterDeclaration name="$owner" parameterType="string" value="Ego"/>
  </ParameterDeclarations>
  <Act name="A">
    <ManeuverGroup name="G" maximumExecutionCount="1">
      <Actors selectTriggeringEntities="false"><EntityRef entityRef="$owner"/></Actors>
    </ManeuverGroup>
    <StartTrigger/>
  </Act>
</Story>"""


def test_story_parameter_named_with_its_prefix(write_scenario: ScenarioWriter) -> None:
    """OpenSCENARIO 1.0 files declare ``name="$owner"`` in a Story and refer to ``$owner``:
    esmini finds the declaration either way; we read the name without the ``$`` and report it."""
    path = write_scenario(minor=0, stories=OWNED_STORY)
    scenario = load_scenario(path)
    story = scenario.storyboard.stories[0]
    assert [d.name for d in story.parameters] == ["owner"]
    assert story.acts[0].maneuver_groups[0].actors.entity_refs == ("Ego",)
    assert [d.code for d in scenario.deviations] == ["parameter-name-with-prefix"]
    assert "'$owner' read as 'owner'" in scenario.deviations[0].message
    with pytest.raises(StrictDeviationError):
        load_scenario(path, options=STRICT)


def test_prefixed_global_and_variable_names(write_scenario: ScenarioWriter) -> None:
    path = write_scenario(
        parameters='<ParameterDeclaration name="$Lanes" parameterType="integer" value="3"/>'
    )
    text = path.read_text(encoding="utf-8").replace(
        "<CatalogLocations>",
        '<VariableDeclarations><VariableDeclaration name="$n" variableType="integer" value="1"/>'
        "</VariableDeclarations>\n  <CatalogLocations>",
    )
    path.write_text(text, encoding="utf-8")
    scenario = load_scenario(path)
    lanes, n = scenario.parameter("Lanes"), scenario.variable("n")
    assert lanes is not None and lanes.value == 3
    assert n is not None and n.value == 1
    assert [d.code for d in scenario.deviations] == ["parameter-name-with-prefix"] * 2


def test_relative_lane_position_without_ds_is_at_the_entitys_s(
    write_scenario: ScenarioWriter,
) -> None:
    """esmini's unit test traj-heading-trig writes a RelativeLanePosition with neither ``ds`` nor
    ``dsLane`` (the schema wants one): esmini reads ds 0, and so do we, reporting it."""
    init = """<Private entityRef="Ego"><PrivateAction><TeleportAction><Position>
      <RelativeLanePosition entityRef="Ego" dLane="0" offset="0.5"/>
    </Position></TeleportAction></PrivateAction></Private>"""
    path = write_scenario(minor=1, init=init)
    scenario = load_scenario(path)
    (action,) = scenario.storyboard.init.private[0].actions
    assert isinstance(action, model.TeleportAction)
    position = action.position
    assert isinstance(position, model.RelativeLanePosition)
    assert (position.ds, position.ds_lane) == (0.0, None)
    assert [d.code for d in scenario.deviations] == ["relative-lane-position-without-ds"]
    with pytest.raises(StrictDeviationError):
        load_scenario(path, options=STRICT)
