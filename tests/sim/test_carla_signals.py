"""ScenarioRunner's RunningRedLightTest and RunningStopTest on scenarios written as CARLA's are.

On ``carla/crossing.xodr`` (a light whose stop line is a CARLA-style signalReference at s=100, a
stop sign at s=200) the hero drives lane -1 at 10 m/s, its behaviour scripted by the story:
it runs a light the story set red (by id, and by ScenarioRunner's ``pos=x,y``), passes it on
green (esmini's lamp list), crosses it with no state set (not evaluated), runs the stop sign,
stops before it and goes on (passes), and stops too far before it (fails). On the shipped Town01
it runs a red light at a junction, the light named by its position in CARLA's frame; on Town07 it
runs a stop sign whose lines are CARLA references in two junction roads, or stops and goes on.
A RoadNetwork TrafficSignalController sets the light red when the hero crosses (fails); a
TrafficSignalControllerAction in the story makes the file Invalid (ScenarioRunner cannot build it).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from simtest_operator.verdicts import Verdict

from . import carla_scenarios as cs

CRITERIA = cs.criteria("RunningRedLightTest", "RunningStopTest", distance=None)


def at_time(name: str, seconds: float) -> str:
    return f"""
              <StartTrigger><ConditionGroup>
                <Condition name="{name}" delay="0" conditionEdge="rising"><ByValueCondition>
                  <SimulationTimeCondition value="{seconds:g}" rule="greaterThan"/>
                </ByValueCondition></Condition>
              </ConditionGroup></StartTrigger>"""


def light(name: str, state: str) -> str:
    return f"""
            <Event name="Light{state}" priority="parallel">
              <Action name="SetLight{state}"><GlobalAction><InfrastructureAction>
                <TrafficSignalAction>
                  <TrafficSignalStateAction name="{name}" state="{state}"/>
                </TrafficSignalAction>
              </InfrastructureAction></GlobalAction></Action>{at_time("Now" + state, 0)}
            </Event>"""


def speed(event: str, target: float, trigger: str) -> str:
    return f"""
            <Event name="{event}" priority="parallel">
              <Action name="{event}Speed"><PrivateAction><LongitudinalAction><SpeedAction>
                <SpeedActionDynamics dynamicsShape="linear" value="5" dynamicsDimension="rate"/>
                <SpeedActionTarget><AbsoluteTargetSpeed value="{target:g}"/></SpeedActionTarget>
              </SpeedAction></LongitudinalAction></PrivateAction></Action>
              <StartTrigger><ConditionGroup>
                <Condition name="{event}When" delay="0" conditionEdge="rising">
                  <ByEntityCondition>
                    <TriggeringEntities triggeringEntitiesRule="any">
                      <EntityRef entityRef="hero"/>
                    </TriggeringEntities>
                    <EntityCondition>{trigger}</EntityCondition>
                  </ByEntityCondition>
                </Condition>
              </ConditionGroup></StartTrigger>
            </Event>"""


def finish(seconds: float) -> str:
    """The last event: the story (so the run) ends once it ran, at ``seconds``."""
    return f"""
            <Event name="Finish" priority="parallel">
              <Action name="Finish"><GlobalAction><ParameterAction parameterRef="done">
                <SetAction value="true"/>
              </ParameterAction></GlobalAction></Action>{at_time("End", seconds)}
            </Event>"""


def stop_and_go(brake_after: float) -> str:
    """Brake to a standstill after ``brake_after`` metres (5 m/s^2: 10 m), wait 1 s, go on."""
    return speed("Brake", 0.0, f'<TraveledDistanceCondition value="{brake_after:g}"/>') + speed(
        "Go", 10.0, '<StandStillCondition duration="1"/>'
    )


def scenario(
    events: str,
    *,
    road: str = "1",
    start: float = 20.0,
    end: float = 20.0,
    stop: str = CRITERIA,
    logic_file: str = "crossing.xodr",
    traffic_signals: str = "",
) -> str:
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2020-03-20T12:00:00" description="CARLA:SignalCrossing" author=""/>
  <ParameterDeclarations>
    <ParameterDeclaration name="done" parameterType="boolean" value="false"/>
  </ParameterDeclarations>
  <CatalogLocations/>
  <RoadNetwork><LogicFile filepath="{logic_file}"/><SceneGraphFile filepath=""/>{traffic_signals}</RoadNetwork>
  <Entities>{cs.vehicle("hero", "ego_vehicle")}
  </Entities>
  <Storyboard>
    <Init><Actions>
      <Private entityRef="hero">
        <PrivateAction><TeleportAction><Position>
          <LanePosition roadId="{road}" laneId="-1" s="{start:g}" offset="0"/>
        </Position></TeleportAction></PrivateAction>
        <PrivateAction><LongitudinalAction><SpeedAction>
          <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
          <SpeedActionTarget><AbsoluteTargetSpeed value="10"/></SpeedActionTarget>
        </SpeedAction></LongitudinalAction></PrivateAction>
      </Private>
    </Actions></Init>
    <Story name="Crossing">
      <Act name="Drive">
        <ManeuverGroup name="Hero" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="hero"/></Actors>
          <Maneuver name="Approach">{events}{finish(end)}
          </Maneuver>
        </ManeuverGroup>{at_time("Go", 0)}
      </Act>
    </Story>
    <StopTrigger><ConditionGroup>{stop}
    </ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""  # noqa: E501


def write(tmp_path: Path, text: str) -> Path:
    shutil.copy(cs.HERE / "crossing.xodr", tmp_path / "crossing.xodr")
    path = tmp_path / "signals.xosc"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("name", ["10", "id=10", "pos=96,8.5"])
def test_running_a_red_light_fails(tmp_path: Path, name: str) -> None:
    outcome = cs.run(write(tmp_path, scenario(light(name, "Red")))).outcome
    assert outcome.verdict is Verdict.FAILED
    # The point 1 m behind the centre (reference + 0.5 m) reaches s=100 at 79.5 m: t=7.95 s.
    assert outcome.reason.startswith(
        "criteria_RunningRedLightTest failed: hero crossed red light 10 at t=7.9"
    )
    # The hero never stopped, so it ran the stop sign at s=200 too (centre at 198.5 + 1.5).
    assert "RunningStopTest failed (hero ran stop sign 20 at t=17.8" in outcome.reason
    assert outcome.metrics["criteria.RunningRedLightTest"] == 0.0


@pytest.mark.parametrize(
    ("name", "state", "status", "detail"),
    [
        ("10", "GREEN", "passed", "passed traffic lights 1 time, never on red"),
        (
            "pos=500,500",
            "red",
            "not evaluated",
            "no light states known: hero crossed the stop line of traffic light 10 at t=7.95 s, "
            "whose state the scenario never set; TrafficSignalStateAction names matching no "
            "traffic light: pos=500,500",
        ),
    ],
)
def test_green_passes_and_an_unknown_state_is_not_judged(
    tmp_path: Path, name: str, state: str, status: str, detail: str
) -> None:
    text = scenario(light(name, state), stop=cs.criteria("RunningRedLightTest", distance=None))
    outcome = cs.run(write(tmp_path, text)).outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert f"RunningRedLightTest {status} ({detail})" in outcome.reason
    # Only a judged test is a metric.
    assert outcome.metrics.get("criteria.RunningRedLightTest") == (
        1.0 if status == "passed" else None
    )


def test_stopping_before_the_stop_sign_passes(tmp_path: Path) -> None:
    # From s=150 the hero brakes at s=180 and stands at about s=190: centre 8.5 m before the line.
    text = scenario(stop_and_go(30.0), start=150.0, end=15.0)
    outcome = cs.run(write(tmp_path, text)).outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert (
        "RunningStopTest passed (stood still before every stop line crossed (1))" in outcome.reason
    )
    assert "RunningRedLightTest passed (crossed no traffic light's stop line)" in outcome.reason


def test_stopping_too_early_fails(tmp_path: Path) -> None:
    # Standing at about s=170, 28.5 m before the line: beyond the 20 m + 3.15 m stop box.
    text = scenario(stop_and_go(10.0), start=150.0, end=15.0)
    outcome = cs.run(write(tmp_path, text)).outcome
    assert outcome.verdict is Verdict.FAILED
    assert outcome.reason.startswith("criteria_RunningStopTest failed: hero ran stop sign 20 at t=")
    assert "(no standstill within 23.1 m before its line)" in outcome.reason


def test_town01_red_light_by_position(tmp_path: Path) -> None:
    # Light 362 stands at (348.75, 4.48) beside road 0 (CARLA frame: y negated); its stop lines
    # lie 0.6 m into junction 26, which the hero on lane -1 of road 0 enters after about 35 m.
    text = scenario(
        light("pos=348.75,-4.48", "Red"), road="0", start=2.0, end=6.0, logic_file="Town01"
    )
    path = tmp_path / "town01.xosc"
    path.write_text(text, encoding="utf-8")
    outcome = cs.run(path).outcome
    assert outcome.verdict is Verdict.FAILED
    assert outcome.reason.startswith(
        "criteria_RunningRedLightTest failed: hero crossed red light 362 at t=3."
    )
    assert "RunningStopTest passed (the map has no stop signs)" in outcome.reason


@pytest.mark.parametrize(
    ("brake_after", "verdict", "expected"),
    [
        (
            None,
            Verdict.FAILED,
            "criteria_RunningStopTest failed: hero ran stop sign 983 at t=3.10 s "
            "(no standstill within 22.8 m before its line)",
        ),
        # Two lines of the one sign, 2.6 m apart on the hero's path: one stop.
        (
            16.0,
            Verdict.PASSED,
            "RunningStopTest passed (stood still before every stop line crossed (1))",
        ),
    ],
)
def test_town07_stop_sign(
    tmp_path: Path, brake_after: float | None, verdict: Verdict, expected: str
) -> None:
    # Stop sign 983 governs lane -1 of junction roads 151 and 153, which road 1 leads into.
    events = stop_and_go(brake_after) if brake_after is not None else ""
    text = scenario(events, road="1", start=2.0, end=12.0, logic_file="Town07")
    path = tmp_path / "town07.xosc"
    path.write_text(text, encoding="utf-8")
    outcome = cs.run(path).outcome
    assert outcome.verdict is verdict, outcome.reason
    assert expected in outcome.reason


CONTROLLER = """
  <TrafficSignals>
    <TrafficSignalController name="crossing">
      <Phase name="go" duration="5"><TrafficSignalState trafficSignalId="10" state="off;off;on"/></Phase>
      <Phase name="stop" duration="10"><TrafficSignalState trafficSignalId="10" state="on;off;off"/></Phase>
    </TrafficSignalController>
  </TrafficSignals>"""  # noqa: E501

SWITCH_TO_GO = f"""
            <Event name="Extend" priority="parallel">
              <Action name="BackToGo"><GlobalAction><InfrastructureAction><TrafficSignalAction>
                <TrafficSignalControllerAction trafficSignalControllerRef="crossing" phase="go"/>
              </TrafficSignalAction></InfrastructureAction></GlobalAction></Action>
              {at_time("Red", 5).strip()}
            </Event>"""


@pytest.mark.parametrize(
    ("events", "verdict", "expected"),
    [
        ("", Verdict.FAILED, "RunningRedLightTest failed (hero crossed red light 10 at t=7.95 s)"),
        # ScenarioRunner builds no TrafficSignalControllerAction: it cannot load the file.
        (
            SWITCH_TO_GO,
            Verdict.INVALID,
            "ScenarioRunner cannot load the file: action 'BackToGo' (line 47): TrafficLights can "
            "only be influenced via TrafficSignalStateAction",
        ),
    ],
)
def test_light_controlled_by_a_signal_controller(
    tmp_path: Path, events: str, verdict: Verdict, expected: str
) -> None:
    # Green for 5 s, then red; the hero's tail reaches the line at t=7.95 s.
    stop = cs.criteria("RunningRedLightTest", distance=None)
    text = scenario(events, stop=stop, traffic_signals=CONTROLLER)
    outcome = cs.run(write(tmp_path, text)).outcome
    assert outcome.verdict is verdict, outcome.reason
    assert expected in outcome.reason
