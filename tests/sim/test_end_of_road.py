"""The end of a lane: an actor that reaches it stands there (its speed drops one step later,
so a teleport triggered right at the end keeps the speed, as in the reference player), and the
time at the end of the road counts from the moment the end was reached."""

from __future__ import annotations

import pytest

from simtest_operator.errors import ScenarioError
from tests.sim.worlds import DT, Bench, lane, speed, teleport


def test_reaching_the_end_stops_the_actor_after_one_step() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 990.0)))
    bench.start("Car", speed(20.0))  # 1 m per step: at the end (s = 1000) in step 11
    bench.step(11)
    car = bench.actor("Car")
    assert car.stuck and car.s == pytest.approx(1000.0)
    assert car.speed == 20.0 and car.end_of_road_time == 0.0
    bench.step()
    assert car.speed == 0.0
    assert car.end_of_road_time == pytest.approx(DT)


def test_teleport_right_at_the_end_keeps_the_speed() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 990.0)))
    bench.start("Car", speed(20.0))
    bench.step(11)
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.step()
    car = bench.actor("Car")
    assert not car.stuck
    assert car.s == pytest.approx(11.0)
    assert car.speed == 20.0


@pytest.mark.parametrize("s", [1001.5, -2.0, 5000.0])
def test_a_lane_position_off_its_road_is_invalid(s: float) -> None:
    # Clamped to the road's end, such positions put entities on one point: a collision at t=0
    # blamed on the system under test (issue 29).
    bench = Bench("Car")
    with pytest.raises(ScenarioError, match=f"s={s:g} is off road '1', which is 1000 m long"):
        bench.start("Car", teleport(lane(-1, s)))


def test_a_lane_position_within_rounding_of_the_end_is_placed_at_the_end() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 1000.5)))
    assert bench.actor("Car").s == pytest.approx(1000.0)
