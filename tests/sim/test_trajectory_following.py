"""Following trajectories in the engine: a path that ends mid-step carries the rest of the step
on along the lane (no second move, no heading kick), a trajectory started while reversing is
backed along facing against it, and a road position faces along the reference line whichever
lane it lies in."""

from __future__ import annotations

import math

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Mode
from tests.sim.worlds import Bench, lane, speed, teleport


def line_trajectory(length: float, h: float = 0.0) -> model.FollowTrajectoryAction:
    start = model.RelativeObjectPosition(
        entity_ref="Car", dx=0.0, dy=0.0,
        orientation=model.Orientation(type=model.ReferenceContext.RELATIVE, h=h),
    )  # fmt: skip
    shape = model.Clothoid(curvature=0.0, curvature_prime=0.0, length=length, position=start)
    return model.FollowTrajectoryAction(
        trajectory=model.Trajectory(name="t", closed=False, shape=shape),
        following_mode=model.FollowingMode.POSITION,
    )


def test_path_end_mid_step_carries_the_rest_on_along_the_lane() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 50.0)))
    bench.start("Car", speed(10.0))
    bench.start("Car", line_trajectory(5.2))  # ends 0.2 m into the 11th step of 0.5 m
    bench.step(11)
    car = bench.actor("Car")
    assert car.mode is Mode.ROAD
    assert car.x == pytest.approx(55.5, abs=1e-6)  # 11 steps x 0.5 m, nothing lost or doubled
    assert car.heading == pytest.approx(0.0, abs=1e-9)
    assert car.odometer == pytest.approx(5.5, abs=1e-6)


def test_trajectory_started_while_reversing_is_backed_along() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 50.0)))
    bench.start("Car", speed(-2.0))
    bench.start("Car", line_trajectory(10.0, h=math.pi))  # drawn the way the car backs
    bench.step(10)
    car = bench.actor("Car")
    assert car.x == pytest.approx(49.0, abs=1e-6)
    assert abs(math.remainder(car.heading, 2.0 * math.pi)) < 1e-9  # still facing +x


def test_road_position_faces_along_the_reference_line_in_a_left_lane() -> None:
    bench = Bench("Car")
    orientation = model.Orientation(type=model.ReferenceContext.RELATIVE, h=-1.57)
    bench.start("Car", teleport(model.RoadPosition(road_id="1", s=10.0, t=5.0,
                                                   orientation=orientation)))  # fmt: skip
    car = bench.actor("Car")
    assert car.lane_id == 2
    assert car.heading == pytest.approx(-1.57)
