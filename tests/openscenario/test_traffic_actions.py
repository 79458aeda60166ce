"""Reading TrafficActions: swarm with the 1.0 ``velocity``, the 1.2 ``SpeedRange`` and the 1.3
``InitialSpeedRange`` + DirectionOfTravelDistribution and without a TrafficDefinition; source
``velocity`` (1.0) and ``speed`` (1.3); sink without a rate (infinite) and with its definition;
TrafficStopAction taking the enclosing ``trafficName``; the ControllerDistribution kept by name
and listed as ignored; line numbers; TrafficAreaAction and TrafficDistribution unsupported;
negative values rejected."""

from __future__ import annotations

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario, model
from tests.openscenario.conftest import ScenarioWriter

DEFINITION = """<TrafficDefinition name="mix"><VehicleCategoryDistribution>
<VehicleCategoryDistributionEntry category="car" weight="0.7"/>
<VehicleCategoryDistributionEntry category="truck" weight="0.3"/>
</VehicleCategoryDistribution><ControllerDistribution>
<ControllerDistributionEntry weight="1"><Controller name="drv"><Properties/></Controller>
</ControllerDistributionEntry></ControllerDistribution></TrafficDefinition>"""

POSITION = '<Position><WorldPosition x="10" y="-2"/></Position>'


def _global(write_scenario: ScenarioWriter, body: str, *, minor: int = 2) -> model.AnyAction:
    path = write_scenario(minor=minor, init=f"<GlobalAction>{body}</GlobalAction>")
    scenario = load_scenario(path)
    (action,) = scenario.storyboard.init.global_actions
    return action


def _line_of(text: str, tag: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if f"<{tag}" in line)


def test_swarm_1_0_velocity_and_definition(write_scenario: ScenarioWriter) -> None:
    attributes = 'semiMajorAxis="300" semiMinorAxis="50" offset="5" numberOfVehicles="12"'
    body = f"""<TrafficAction>
<TrafficSwarmAction innerRadius="20" {attributes} velocity="25">
<CentralObject entityRef="Ego"/>{DEFINITION}
</TrafficSwarmAction></TrafficAction>"""
    path = write_scenario(minor=0, init=f"<GlobalAction>{body}</GlobalAction>")
    scenario = load_scenario(path)
    (swarm,) = scenario.storyboard.init.global_actions
    assert isinstance(swarm, model.TrafficSwarmAction)
    assert (swarm.central_entity, swarm.inner_radius, swarm.semi_major_axis) == ("Ego", 20, 300)
    assert (swarm.semi_minor_axis, swarm.offset, swarm.number_of_vehicles) == (50, 5, 12)
    assert swarm.velocity == 25 and swarm.speed_range is None and swarm.direction is None
    assert swarm.traffic_name is None
    assert swarm.line == _line_of(path.read_text(), "TrafficSwarmAction")
    assert swarm.definition is not None
    assert [(c.category, c.weight) for c in swarm.definition.categories] == [
        ("car", 0.7),
        ("truck", 0.3),
    ]
    assert [c.controller for c in swarm.definition.controllers] == ["drv"]
    assert "ControllerDistribution" in scenario.ignored_kinds


def test_swarm_speed_ranges_and_directions(write_scenario: ScenarioWriter) -> None:
    v12 = _global(
        write_scenario,
        f"""<TrafficAction trafficName="bg"><TrafficSwarmAction innerRadius="0"
semiMajorAxis="100" semiMinorAxis="100" offset="0" numberOfVehicles="3">
<CentralObject entityRef="Ego"/>{DEFINITION}<SpeedRange lowerLimit="5" upperLimit="9"/>
</TrafficSwarmAction></TrafficAction>""",
    )
    assert isinstance(v12, model.TrafficSwarmAction)
    assert v12.traffic_name == "bg"
    assert v12.speed_range is not None and (v12.speed_range.lower, v12.speed_range.upper) == (5, 9)
    v13 = _global(
        write_scenario,
        """<TrafficAction><TrafficSwarmAction innerRadius="0" semiMajorAxis="100"
semiMinorAxis="100" offset="0" numberOfVehicles="3"><CentralObject entityRef="Ego"/>
<InitialSpeedRange lowerLimit="1" upperLimit="2"/>
<DirectionOfTravelDistribution same="3" opposite="1"/></TrafficSwarmAction></TrafficAction>""",
        minor=3,
    )
    assert isinstance(v13, model.TrafficSwarmAction)
    assert v13.definition is None  # optional since 1.3: cars
    assert v13.speed_range is not None and v13.speed_range.upper == 2
    assert v13.direction is not None and (v13.direction.same, v13.direction.opposite) == (3, 1)


def test_source_speed_spellings(write_scenario: ScenarioWriter) -> None:
    old = _global(
        write_scenario,
        f"""<TrafficAction><TrafficSourceAction radius="2" rate="0.5" velocity="12">
{POSITION}{DEFINITION}</TrafficSourceAction></TrafficAction>""",
    )
    assert isinstance(old, model.TrafficSourceAction)
    assert (old.radius, old.rate, old.speed) == (2, 0.5, 12)
    assert isinstance(old.position, model.WorldPosition)
    new = _global(
        write_scenario,
        f"""<TrafficAction><TrafficSourceAction radius="2" rate="1" speed="7">{POSITION}
</TrafficSourceAction></TrafficAction>""",
        minor=3,
    )
    assert isinstance(new, model.TrafficSourceAction) and new.speed == 7


def test_sink_rate_is_infinite_without_attribute(write_scenario: ScenarioWriter) -> None:
    sink = _global(
        write_scenario,
        f"""<TrafficAction><TrafficSinkAction radius="15">{POSITION}{DEFINITION}
</TrafficSinkAction></TrafficAction>""",
    )
    assert isinstance(sink, model.TrafficSinkAction)
    assert sink.rate is None and sink.radius == 15 and sink.definition is not None
    limited = _global(
        write_scenario,
        f"""<TrafficAction><TrafficSinkAction radius="15" rate="2">{POSITION}
</TrafficSinkAction></TrafficAction>""",
    )
    assert isinstance(limited, model.TrafficSinkAction) and limited.rate == 2


def test_stop_action_names_the_traffic(write_scenario: ScenarioWriter) -> None:
    stop = _global(
        write_scenario, '<TrafficAction trafficName="bg"><TrafficStopAction/></TrafficAction>'
    )
    assert isinstance(stop, model.TrafficStopAction) and stop.traffic_name == "bg"


def test_areas_and_entity_distributions_are_unsupported(write_scenario: ScenarioWriter) -> None:
    area = _global(
        write_scenario,
        """<TrafficAction><TrafficAreaAction numberOfEntities="3" continuous="true">
<TrafficDistribution/><TrafficArea/></TrafficAreaAction></TrafficAction>""",
        minor=3,
    )
    assert isinstance(area, model.Unsupported) and area.element == "TrafficAreaAction"
    templated = _global(
        write_scenario,
        f"""<TrafficAction><TrafficSourceAction radius="2" rate="1">{POSITION}
<TrafficDistribution><TrafficDistributionEntry weight="1"><EntityDistribution/>
</TrafficDistributionEntry></TrafficDistribution></TrafficSourceAction></TrafficAction>""",
        minor=3,
    )
    assert isinstance(templated, model.Unsupported)
    assert "TrafficDistribution" in templated.reason


@pytest.mark.parametrize(
    ("attributes", "message"),
    [
        ('innerRadius="-1" semiMajorAxis="1" semiMinorAxis="1"', "innerRadius"),
        ('innerRadius="1" semiMajorAxis="-1" semiMinorAxis="1"', "semiMajorAxis"),
    ],
)
def test_negative_sizes_are_rejected(
    write_scenario: ScenarioWriter, attributes: str, message: str
) -> None:
    body = f"""<TrafficAction><TrafficSwarmAction {attributes} offset="0" numberOfVehicles="1">
<CentralObject entityRef="Ego"/>{DEFINITION}</TrafficSwarmAction></TrafficAction>"""
    with pytest.raises(ScenarioError, match=message):
        _global(write_scenario, body)
