"""Following trajectories in the engine: a path that ends mid-step carries the rest of the step
on along the lane (no second move, no heading kick), a trajectory started while reversing is
backed along facing against it unless the path gives a heading along it, a road position faces
along the reference line whichever lane it lies in, and a Timing runs the trajectory clock
``scale`` times as fast with the position read ``offset`` later (a relative clock starting at
the initialDistanceOffset point), as in the reference player."""

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


def _line(*, h: float | None = None, times: bool = True) -> model.Trajectory:
    """100 m along lane -2's centre (y = -5.25) from x = 100, in 10 s when timed."""
    vertices = tuple(
        model.Vertex(position=model.WorldPosition(x=x, y=-5.25, h=h), time=t if times else None)
        for x, t in ((100.0, 0.0), (200.0, 10.0))
    )
    return model.Trajectory(name="line", closed=False, shape=model.Polyline(vertices=vertices))


def _follow(trajectory: model.Trajectory, timing: model.Timing | None = None,
            offset: float | None = None) -> model.FollowTrajectoryAction:  # fmt: skip
    return model.FollowTrajectoryAction(
        trajectory=trajectory,
        following_mode=model.FollowingMode.POSITION,
        timing=timing,
        initial_distance_offset=offset,
    )


def test_timing_scale_runs_the_trajectory_clock_faster_and_offset_shifts_it() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-2, 100.0)))
    timing = model.Timing(domain=model.ReferenceContext.RELATIVE, scale=2.0, offset=1.0)
    bench.start("Car", _follow(_line(), timing))
    bench.step(20)  # 1 s: the clock reads 2 s, the position is taken at 3 s
    car = bench.actor("Car")
    assert car.x == pytest.approx(130.0, abs=1e-6)
    assert car.speed == pytest.approx(20.0, abs=1e-6)
    bench.step(79)  # the clock (without the offset) reaches 10 s after 5 s
    assert car.mode is Mode.PATH
    bench.step()
    assert car.mode is not Mode.PATH


def test_initial_distance_offset_starts_a_relative_clock_at_that_point() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-2, 100.0)))
    timing = model.Timing(domain=model.ReferenceContext.RELATIVE, scale=1.0, offset=0.0)
    bench.start("Car", _follow(_line(), timing, offset=50.0))
    bench.step(20)
    car = bench.actor("Car")
    assert car.x == pytest.approx(160.0, abs=1e-6)
    bench.step(80)  # 5 s: the rest of the path's time
    assert car.mode is not Mode.PATH


@pytest.mark.parametrize(("h", "x"), [(0.0, 140.0), (math.pi, 160.0), (None, 160.0)])
def test_reversing_along_a_path_depends_on_the_heading_it_gives(h: float | None, x: float) -> None:
    # facing along the path (heading given as 0) a negative speed backs the car towards the
    # start; facing against it (pi), or with no heading given, it moves on towards the end
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-2, 100.0)))
    bench.start("Car", speed(-5.0))
    bench.start("Car", _follow(_line(h=h, times=False), offset=50.0))
    bench.step(40)
    car = bench.actor("Car")
    assert car.x == pytest.approx(x, abs=1e-6)
    facing = 0.0 if h == 0.0 else math.pi
    assert math.cos(car.heading - facing) == pytest.approx(1.0)
