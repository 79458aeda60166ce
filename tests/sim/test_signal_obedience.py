"""The built-in driver model obeys the map's traffic lights and stop signs.

On ``carla/crossing.xodr`` (light 10's stop line at s=100, stop sign 20's at s=200, the road
along +x so x is s) the hero is handed to the driver model (``external_control``, or CARLA's
autopilot through ActivateControllerAction) at 10 m/s: it stops before a red light and goes on
green, goes through a light it sees green or whose state is unknown, stops at the stop sign and
goes on; with ``traffic_signals`` off it runs them (the old behaviour). The dilemma rule on
yellow, the committed red and the stop-sign latch are checked on the model itself.
"""

from __future__ import annotations

import dataclasses
import itertools
import shutil
from pathlib import Path

import pytest

from simtest_operator.drivermodel import (
    STOP_MARGIN,
    Aspect,
    DriverModel,
    SignalAhead,
    SutConfig,
)
from simtest_operator.runner import scenario_execution
from simtest_operator.verdicts import Verdict

from . import carla_scenarios as cs

LINE_S = 100.0
STOP_S = 200.0
FRONT = 3.75
"""Reference point to front bumper of the tests' vehicle (``carla_scenarios.vehicle``)."""

RED_THEN_GREEN = """
  <TrafficSignals>
    <TrafficSignalController name="crossing">
      <Phase name="stop" duration="14"><TrafficSignalState trafficSignalId="10" state="Red"/></Phase>
      <Phase name="go" duration="60"><TrafficSignalState trafficSignalId="10" state="Green"/></Phase>
    </TrafficSignalController>
  </TrafficSignals>"""  # noqa: E501


def scenario(
    *,
    control: str = cs.HERO_CONTROL,
    signals: str = "",
    start: float = 20.0,
    end: float = 25.0,
    speed: float = 10.0,
    adversary: str = "",
) -> str:
    criteria = cs.criteria("RunningRedLightTest", "RunningStopTest", distance=None)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2020-03-20T12:00:00" description="CARLA:Obey" author=""/>
  <ParameterDeclarations>
    <ParameterDeclaration name="done" parameterType="boolean" value="false"/>
  </ParameterDeclarations>
  <CatalogLocations/>
  <RoadNetwork><LogicFile filepath="crossing.xodr"/><SceneGraphFile filepath=""/>{signals}</RoadNetwork>
  <Entities>{cs.vehicle("hero", "ego_vehicle")}{cs.vehicle("adversary", "simulation") if adversary else ""}
  </Entities>
  <Storyboard>
    <Init><Actions>
      <Private entityRef="hero">
        <PrivateAction><TeleportAction><Position>
          <LanePosition roadId="1" laneId="-1" s="{start:g}" offset="0"/>
        </Position></TeleportAction></PrivateAction>
        <PrivateAction><LongitudinalAction><SpeedAction>
          <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
          <SpeedActionTarget><AbsoluteTargetSpeed value="{speed:g}"/></SpeedActionTarget>
        </SpeedAction></LongitudinalAction></PrivateAction>{control}
      </Private>{adversary}
    </Actions></Init>
    <Story name="Crossing">
      <Act name="Drive">
        <ManeuverGroup name="Hero" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="hero"/></Actors>
          <Maneuver name="Wait">
            <Event name="Finish" priority="parallel">
              <Action name="Finish"><GlobalAction><ParameterAction parameterRef="done">
                <SetAction value="true"/>
              </ParameterAction></GlobalAction></Action>
              <StartTrigger><ConditionGroup>
                <Condition name="End" delay="0" conditionEdge="rising"><ByValueCondition>
                  <SimulationTimeCondition value="{end:g}" rule="greaterThan"/>
                </ByValueCondition></Condition>
              </ConditionGroup></StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup>
          <Condition name="Go" delay="0" conditionEdge="rising"><ByValueCondition>
            <SimulationTimeCondition value="0" rule="greaterThan"/>
          </ByValueCondition></Condition>
        </ConditionGroup></StartTrigger>
      </Act>
    </Story>
    <StopTrigger><ConditionGroup>{criteria}
    </ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""  # noqa: E501


def run(tmp_path: Path, text: str, sut: SutConfig | None = None) -> scenario_execution.RunReport:
    shutil.copy(cs.HERE / "crossing.xodr", tmp_path / "crossing.xodr")
    path = tmp_path / "obey.xosc"
    path.write_text(text, encoding="utf-8")
    return cs.run(path, sut=sut)


def front_at(
    report: scenario_execution.RunReport, seconds: float, entity: str = "hero"
) -> tuple[float, float]:
    """The front bumper (x = s on the avenue) and speed of ``entity`` at the 1 Hz sample
    ``seconds``."""
    for time, x, _, _, speed in report.samples[entity]:
        if time == pytest.approx(seconds):
            return x + FRONT, speed
    raise AssertionError(f"no sample at t={seconds}")


@pytest.mark.parametrize("control", [cs.HERO_CONTROL, cs.HERO_ACTIVATE])
def test_the_hero_stops_at_red_and_goes_on_green(tmp_path: Path, control: str) -> None:
    # Red for the first 14 s: at 10 m/s the hero would reach the line after 8 s.
    report = run(tmp_path, scenario(control=control, signals=RED_THEN_GREEN))
    outcome = report.outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    front, speed = front_at(report, 13.0)
    assert LINE_S - STOP_MARGIN - 0.5 <= front < LINE_S
    assert speed == 0.0
    assert front_at(report, 20.0)[0] > LINE_S + 10.0
    assert "RunningRedLightTest passed (passed traffic lights 1 time, never on red)" in (
        outcome.reason
    )


AUTOPILOT_ADVERSARY = """
      <Private entityRef="adversary">
        <PrivateAction><TeleportAction><Position>
          <LanePosition roadId="1" laneId="-2" s="20" offset="0"/>
        </Position></TeleportAction></PrivateAction>
        <PrivateAction><ActivateControllerAction longitudinal="true" lateral="true"/>
        </PrivateAction>
      </Private>"""


def test_a_vehicle_on_carla_autopilot_stops_at_red_and_goes_on_green(tmp_path: Path) -> None:
    # ScenarioRunner's ActivateControllerAction puts the adversary on CARLA's autopilot (8.33 m/s
    # on a road without a speed limit); the hero stands still, scripted.
    text = scenario(control="", speed=0.0, signals=RED_THEN_GREEN, adversary=AUTOPILOT_ADVERSARY)
    report = run(tmp_path, text)
    front, speed = front_at(report, 13.0, "adversary")  # (coming to rest: it started at 0)
    assert LINE_S - STOP_MARGIN - 0.5 <= front < LINE_S
    assert speed < 0.1
    assert front_at(report, 20.0, "adversary")[0] > LINE_S + 10.0


def test_braking_for_red_is_comfortable_and_late(tmp_path: Path) -> None:
    # It keeps its speed until comfortable braking (3 m/s^2) is needed: from 10 m/s that is
    # about 17 m before the stop point, so at t=5 s (front at 72.5 m) it still cruises.
    report = run(tmp_path, scenario(signals=RED_THEN_GREEN))
    speeds = [speed for _, _, _, _, speed in report.samples["hero"]]
    assert front_at(report, 5.0)[1] == pytest.approx(10.0)
    assert all(b - a >= -3.3 for a, b in itertools.pairwise(speeds))


def test_with_signals_off_it_runs_the_red_light(tmp_path: Path) -> None:
    report = run(tmp_path, scenario(signals=RED_THEN_GREEN), SutConfig(traffic_signals=False))
    assert report.outcome.verdict is Verdict.FAILED
    assert "hero crossed red light 10 at t=" in report.outcome.reason


@pytest.mark.parametrize("state", ["Green", "Off"])
def test_green_or_unknown_lights_do_not_stop_it(tmp_path: Path, state: str) -> None:
    signals = RED_THEN_GREEN.replace('state="Red"', f'state="{state}"')
    report = run(tmp_path, scenario(signals=signals, end=10.0))
    assert min(speed for _, _, _, _, speed in report.samples["hero"]) > 9.9


def test_the_hero_stands_still_at_a_stop_sign_then_goes(tmp_path: Path) -> None:
    report = run(tmp_path, scenario(start=150.0, end=15.0))
    outcome = report.outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert "RunningStopTest passed (stood still before every stop line crossed (1))" in (
        outcome.reason
    )
    # It brakes from 10 m/s at t=2.5 s, stands at the line at about t=6.5 s and drives off (on
    # 10 m/s all along it would be 20 m past the line at t=7 s).
    front, speed = front_at(report, 7.0)
    assert STOP_S - STOP_MARGIN - 1.0 <= front < STOP_S + 0.5
    assert speed < 2.0
    assert front_at(report, 15.0)[0] > STOP_S + 10.0


def driver() -> DriverModel:
    return DriverModel(SutConfig(), set_speed=14.0)


def test_yellow_stops_when_comfortable_braking_can() -> None:
    far = SignalAhead(key="10", distance=60.0, aspect=Aspect.YELLOW)
    model = driver()
    # 14 m/s needs 1.6 m/s^2 over 60 m: it will stop (no braking needed yet, then braking)
    assert model.command(speed=14.0, leader=None, signals=[far], dt=0.05).acceleration == 0.0
    near = dataclasses.replace(far, distance=32.0)
    assert model.command(speed=14.0, leader=None, signals=[near], dt=0.05).acceleration < -2.5


def test_yellow_goes_when_it_could_not_stop_comfortably() -> None:
    # 14 m/s over 20 m needs 4.9 m/s^2 (> 3): go, and keep going while it stays yellow.
    model = driver()
    near = SignalAhead(key="10", distance=20.0, aspect=Aspect.YELLOW)
    assert model.command(speed=14.0, leader=None, signals=[near], dt=0.05).acceleration >= 0.0
    nearer = dataclasses.replace(near, distance=12.0)
    assert model.command(speed=14.0, leader=None, signals=[nearer], dt=0.05).acceleration >= 0.0


def test_red_it_cannot_stop_for_any_more_is_passed() -> None:
    # 14 m/s over 10 m needs 9.8 m/s^2, beyond the 8 m/s^2 the car has: committed.
    committed = SignalAhead(key="10", distance=10.0, aspect=Aspect.RED)
    assert driver().command(speed=14.0, leader=None, signals=[committed]).acceleration >= 0.0
    stoppable = dataclasses.replace(committed, distance=16.0)
    assert driver().command(speed=14.0, leader=None, signals=[stoppable]).acceleration < -6.0


def test_a_stop_sign_is_served_once_per_approach() -> None:
    model = driver()
    sign = SignalAhead(key="20", distance=STOP_MARGIN + 0.3, stop_sign=True)
    # standing at the line: served, so it drives off
    assert model.command(speed=0.0, leader=None, signals=[sign], dt=0.05).acceleration > 0.0
    assert model.command(speed=0.5, leader=None, signals=[sign], dt=0.05).acceleration > 0.0
    # once out of sight, the next approach to the same sign stops again
    model.command(speed=5.0, leader=None, signals=[], dt=0.05)
    again = dataclasses.replace(sign, distance=4.0)
    assert model.command(speed=5.0, leader=None, signals=[again], dt=0.05).acceleration < 0.0
