"""Driving along lanes: on a curve an actor covers its speed along its own lateral position
(outside the reference line of a left arc less s per metre, inside more), also while it changes
lanes, where the scale follows the changing lateral position step by step; a lane change steers
the speed sideways (the path, not the lane, is driven at the speed)."""

from __future__ import annotations

import math

import pytest

from simtest_operator.openscenario import model
from tests.sim.worlds import DT, Bench, lane, speed, teleport

RADIUS = 50.0  # data/arc.xodr: curvature 0.02, lanes 3.5 m wide


def test_outer_lane_covers_its_speed_along_the_lane() -> None:
    bench = Bench("Car", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    bench.step(round(2.0 / DT))
    car = bench.actor("Car")
    lane_radius = RADIUS + 1.75
    assert car.s - 10.0 == pytest.approx(20.0 * RADIUS / lane_radius, rel=1e-3)


def test_lane_change_steers_the_speed_sideways() -> None:
    # The speed is along the path: a lane change drives sqrt(v^2 - lateral^2) along the lane.
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    change = model.LaneChangeAction(
        dynamics=model.TransitionDynamics(
            shape=model.DynamicsShape.LINEAR, dimension=model.DynamicsDimension.TIME, value=2.0
        ),
        target=model.AbsoluteTargetLane(lane_id=-2),
    )
    bench.start("Car", change)
    car = bench.actor("Car")
    travelled, x0, y0 = 0.0, car.x, car.y
    for _ in range(round(2.0 / DT)):
        bench.step()
        travelled += math.hypot(car.x - x0, car.y - y0)
        x0, y0 = car.x, car.y
    assert car.lane_id == -2
    assert travelled == pytest.approx(20.0, abs=0.05)
    assert car.s - 10.0 == pytest.approx(math.sqrt(20.0**2 - 3.5**2), abs=0.05)


def test_lane_change_on_a_curve_scales_with_the_changing_lateral_position() -> None:
    bench = Bench("Car", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    change = model.LaneChangeAction(
        dynamics=model.TransitionDynamics(
            shape=model.DynamicsShape.LINEAR, dimension=model.DynamicsDimension.TIME, value=2.0
        ),
        target=model.AbsoluteTargetLane(lane_id=1),
    )
    bench.start("Car", change)
    bench.step(round(2.0 / DT))
    car = bench.actor("Car")
    assert car.lane_id == 1
    # ds/dτ = u / (1 - κ t): u the speed along the lane, t linear from -1.75 to 1.75 m
    half, kappa = 1.75, 1.0 / RADIUS
    mean = math.log((1 + kappa * half) / (1 - kappa * half)) / (2 * kappa * half)
    along = math.sqrt(10.0**2 - (2 * half / 2.0) ** 2) * 2.0
    assert car.s - 10.0 == pytest.approx(along * mean, abs=0.05)
