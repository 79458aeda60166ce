"""RoadNetwork ``TrafficSignals``: controllers with their phases and states read in order, a
delayed reference kept, and bad declarations (duplicate name, unknown or circular reference,
negative duration) refused naming the element and line."""

from __future__ import annotations

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario, model
from tests.openscenario.conftest import ScenarioWriter

PHASES = """
      <Phase name="stop" duration="10">
        <TrafficSignalState trafficSignalId="1" state="on;off;off"/>
        <TrafficSignalState trafficSignalId="2" state="off;on"/>
      </Phase>
      <Phase name="go" duration="{go}"><TrafficSignalState trafficSignalId="1" state="green"/></Phase>
"""  # noqa: E501


def signals(*controllers: str) -> str:
    return f"<TrafficSignals>{''.join(controllers)}</TrafficSignals>"


def controller(name: str, attributes: str = "", go: str = "5") -> str:
    return (
        f'<TrafficSignalController name="{name}" {attributes}>'
        f"{PHASES.format(go=go)}</TrafficSignalController>"
    )


def test_controllers_are_read(write_scenario: ScenarioWriter) -> None:
    road = signals(controller("a"), controller("b", 'delay="3" reference="a"'))
    scenario = load_scenario(write_scenario(road=road))
    first, second = scenario.road_network.controllers
    assert first == model.TrafficSignalController(
        name="a",
        phases=(
            model.Phase(name="stop", duration=10.0, states=(("1", "on;off;off"), ("2", "off;on"))),
            model.Phase(name="go", duration=5.0, states=(("1", "green"),)),
        ),
        line=first.line,
    )
    assert (second.delay, second.reference) == (3.0, "a")


@pytest.mark.parametrize(
    ("road", "message"),
    [
        (signals(controller("a"), controller("a")), "controller 'a' is declared twice"),
        (signals(controller("a", 'reference="z"')), "references unknown controller 'z'"),
        (
            signals(controller("a", 'reference="b"'), controller("b", 'reference="a"')),
            "controller 'a' references itself",
        ),
        (signals(controller("a", go="-1")), "duration"),
    ],
)
def test_bad_controllers_are_refused(
    write_scenario: ScenarioWriter, road: str, message: str
) -> None:
    with pytest.raises(ScenarioError, match=message) as caught:
        load_scenario(write_scenario(road=road))
    assert caught.value.line is not None
