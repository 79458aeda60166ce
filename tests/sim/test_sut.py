"""The system under test: the IDM/ACC/AEB driver model in isolation (free road towards the set
speed, following, AEB latching below the TTC threshold and releasing, lane keeping within what
the vehicle can steer at its speed), and end to end: two SUT
configurations give different verdicts on the same hard-braking-lead scenario; with takeover
``never`` the ego stays scripted."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simtest_operator.drivermodel import LANE_KEEPING_TIME, DriverModel, Leader, Steering
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from simtest_operator.verdicts import Verdict

DATA = Path(__file__).parent / "data"


def test_free_road_accelerates_towards_set_speed_and_holds_it() -> None:
    model = DriverModel(SutConfig(), set_speed=30.0)
    assert model.command(speed=10.0, leader=None).acceleration == pytest.approx(
        2.0 * (1 - (1 / 3) ** 4)
    )
    assert model.command(speed=30.0, leader=None).acceleration == pytest.approx(0.0)


def test_a_set_speed_of_zero_stops_and_stays_stopped() -> None:
    model = DriverModel(SutConfig(), set_speed=0.0)
    assert model.command(speed=0.0, leader=None).acceleration == 0.0
    assert model.command(speed=5.0, leader=None).acceleration == pytest.approx(-3.0)


def test_following_brakes_for_a_close_slow_leader_only_with_acc() -> None:
    close = Leader(gap=10.0, speed=10.0)
    assert (
        DriverModel(SutConfig(), set_speed=25.0).command(speed=25.0, leader=close).acceleration
        < -3.0
    )
    cruise = DriverModel(SutConfig(acc=False, aeb=False), set_speed=25.0)
    assert cruise.command(speed=25.0, leader=close).acceleration == pytest.approx(0.0)


def test_aeb_latches_below_threshold_and_releases() -> None:
    model = DriverModel(
        SutConfig(acc=False, aeb_ttc_threshold=1.5, aeb_deceleration=9.0), set_speed=20.0
    )
    assert not model.command(speed=20.0, leader=Leader(gap=40.0, speed=10.0)).aeb_active
    braking = model.command(speed=20.0, leader=Leader(gap=12.0, speed=10.0))
    assert braking.aeb_active and braking.acceleration == pytest.approx(-9.0)
    # still closing, TTC above threshold again: stays latched until no longer closing
    assert model.command(speed=15.0, leader=Leader(gap=12.0, speed=10.0)).aeb_active
    assert not model.command(speed=9.0, leader=Leader(gap=12.0, speed=10.0)).aeb_active


def _steer_from_rest(
    model: DriverModel, *, offset: float, speed: float, steps: int
) -> tuple[float, list[float]]:
    """Lane keeping for ``steps`` steps of 0.05 s at ``speed``: the last offset and the headings."""
    heading, headings = 0.0, []
    for _ in range(steps):
        heading = model.steer(
            offset=offset, heading=heading, speed=speed, dt=0.05, steering=Steering()
        )
        offset += speed * math.sin(heading) * 0.05
        headings.append(heading)
    return offset, headings


def test_lane_keeping_turns_no_faster_than_the_vehicle_can() -> None:
    model = DriverModel(SutConfig(), set_speed=10.0)
    # Walking pace, 0.65 m off centre: the wheels at full lock turn the car by v tan(0.5) / L.
    slow = Steering().max_yaw_rate(0.5)
    assert slow == pytest.approx(0.5 * math.tan(0.5) / 2.8)
    offset, headings = _steer_from_rest(model, offset=0.65, speed=0.5, steps=1)
    assert headings == [pytest.approx(-slow * 0.05)]
    assert offset == pytest.approx(0.65 - 0.5 * math.sin(slow * 0.05) * 0.05)
    # At speed, lateral acceleration caps the yaw rate (3 m/s^2 / v).
    assert Steering().max_yaw_rate(20.0) == pytest.approx(3.0 / 20.0)
    assert Steering().max_yaw_rate(0.0) == 0.0
    # Back to the centre without crossing it, the heading unwound on the way.
    offset, headings = _steer_from_rest(model, offset=0.65, speed=2.0, steps=200)
    assert 0.0 <= offset < 0.01 and abs(headings[-1]) < 1e-3
    assert max(abs(b - a) for a, b in zip([0.0, *headings], headings, strict=False)) <= (
        Steering().max_yaw_rate(2.0) * 0.05 + 1e-12
    )


def test_lane_keeping_within_the_limits_decays_the_offset() -> None:
    # Small offset at speed: the wished heading is reachable, the offset decays exponentially.
    model = DriverModel(SutConfig(), set_speed=20.0)
    heading = model.steer(offset=0.01, heading=-0.0005, speed=20.0, dt=0.05, steering=Steering())
    moved = 0.01 + 20.0 * math.sin(heading) * 0.05
    assert moved == pytest.approx(0.01 * math.exp(-0.05 / LANE_KEEPING_TIME))
    off = DriverModel(SutConfig(lane_keeping=False), set_speed=20.0)
    assert off.steer(offset=0.5, heading=0.1, speed=20.0, dt=0.05, steering=Steering()) == 0.0


def run(sut: SutConfig, tmp_path: Path) -> scenario_execution.RunReport:
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=DATA / "hard_braking_lead.xosc",
            nets_dir=tmp_path,
            sut=sut,
            record=False,
            backend=BackendChoice.MEMORY,
        )
    )


def test_two_sut_configurations_give_different_verdicts(tmp_path: Path) -> None:
    without_aeb = run(SutConfig(acc=False, aeb=False), tmp_path)
    with_aeb = run(
        SutConfig(acc=False, aeb=True, aeb_ttc_threshold=2.5, aeb_deceleration=9.0), tmp_path
    )
    assert without_aeb.outcome.verdict is Verdict.FAILED
    assert without_aeb.outcome.reason.startswith("Ego collided with Lead")
    assert with_aeb.outcome.verdict is Verdict.PASSED
    assert with_aeb.outcome.metrics["maxDecel"] == pytest.approx(9.0)
    assert "Ego driven by the SUT model" in with_aeb.intended


def test_takeover_never_keeps_the_ego_scripted(tmp_path: Path) -> None:
    scripted = run(SutConfig(takeover=Takeover.NEVER, aeb=True), tmp_path)
    assert scripted.outcome.verdict is Verdict.FAILED
    assert scripted.outcome.metrics["maxDecel"] == pytest.approx(0.0)
    assert "Ego driven by the SUT model" not in scripted.intended
