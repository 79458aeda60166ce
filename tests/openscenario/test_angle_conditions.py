"""Reading AngleCondition and RelativeAngleCondition (OpenSCENARIO 1.3): angle type, angle,
tolerance and coordinate system (absent: ``entity``); the frames the engine cannot measure
(trajectory, road pitch and roll) are unsupported, so the run is Invalid naming them."""

from __future__ import annotations

import pytest

from simtest_operator.openscenario import load_scenario, model
from tests.openscenario.conftest import ScenarioWriter


def _read(write_scenario: ScenarioWriter, inner: str) -> model.EntityCondition:
    path = write_scenario(
        minor=3,
        stop=(
            '<ConditionGroup><Condition name="c" delay="0" conditionEdge="none">'
            '<ByEntityCondition><TriggeringEntities triggeringEntitiesRule="any">'
            '<EntityRef entityRef="Ego"/></TriggeringEntities>'
            f"<EntityCondition>{inner}</EntityCondition></ByEntityCondition>"
            "</Condition></ConditionGroup>"
        ),
    )
    stop = load_scenario(path).storyboard.stop_trigger
    assert stop is not None
    body = stop.condition_groups[0].conditions[0].body
    assert isinstance(body, model.ByEntity)
    return body.condition


def test_angle_condition(write_scenario: ScenarioWriter) -> None:
    condition = _read(
        write_scenario, '<AngleCondition angleType="heading" angle="1.571" angleTolerance="0.01"/>'
    )
    assert condition == model.AngleCondition(
        angle_type=model.AngleType.HEADING,
        angle=1.571,
        tolerance=0.01,
        coordinate_system=model.CoordinateSystem.ENTITY,
        line=condition.line,
    )


def test_relative_angle_condition(write_scenario: ScenarioWriter) -> None:
    condition = _read(
        write_scenario,
        '<RelativeAngleCondition entityRef="Ego" angleType="roll" angle="0" angleTolerance="0.1"'
        ' coordinateSystem="world"/>',
    )
    assert condition == model.RelativeAngleCondition(
        entity_ref="Ego",
        angle_type=model.AngleType.ROLL,
        angle=0.0,
        tolerance=0.1,
        coordinate_system=model.CoordinateSystem.WORLD,
        line=condition.line,
    )


@pytest.mark.parametrize(
    ("attributes", "reason"),
    [
        ('angleType="heading" coordinateSystem="trajectory"', "trajectory coordinate system"),
        ('angleType="pitch" coordinateSystem="road"', "pitch angles in the road"),
        ('angleType="roll" coordinateSystem="lane"', "roll angles in the lane"),
    ],
)
def test_frames_that_cannot_be_measured_are_unsupported(
    write_scenario: ScenarioWriter, attributes: str, reason: str
) -> None:
    condition = _read(
        write_scenario, f'<AngleCondition {attributes} angle="0" angleTolerance="0.1"/>'
    )
    assert isinstance(condition, model.Unsupported)
    assert condition.element == "AngleCondition"
    assert reason in condition.reason
