"""Distance keeping (LongitudinalDistanceAction): without acceleration limits the actor is held
rigidly at the gap; with limits it closes the gap like a critically damped spring, its
acceleration inside the limits and built up no faster than the allowed rate (released at once,
as the reference player does); ``any`` displacement keeps the side the actor starts on; the gap
is measured between both entities at the same instant, also when the reference moves first."""

from __future__ import annotations

import itertools

import pytest

from simtest_operator.openscenario import model
from tests.sim.worlds import DT, Bench, lane, speed, teleport


def keep(
    gap: float,
    *,
    limits: model.DynamicConstraints | None = None,
    displacement: str = "trailingReferencedEntity",
) -> model.LongitudinalDistanceAction:
    return model.LongitudinalDistanceAction(
        entity_ref="Lead",
        freespace=False,
        continuous=True,
        distance=gap,
        displacement=model.LongitudinalDisplacement(displacement),
        constraints=limits,
    )


def bench(follower_s: float, follower_speed: float) -> Bench:
    b = Bench("Car", "Lead")
    b.start("Lead", teleport(lane(-1, 200.0)))
    b.start("Lead", speed(10.0))
    b.start("Car", teleport(lane(-1, follower_s)))
    b.start("Car", speed(follower_speed))
    return b


def test_without_limits_the_gap_is_held_rigidly() -> None:
    b = bench(100.0, 25.0)
    b.start("Car", keep(30.0))
    b.step(20)
    assert b.actor("Lead").x - b.actor("Car").x == pytest.approx(30.0, abs=1e-6)
    assert b.actor("Car").speed == pytest.approx(10.0)


def test_with_limits_the_gap_closes_within_acceleration_and_jerk_limits() -> None:
    limits = model.DynamicConstraints(
        max_acceleration=3.0, max_deceleration=3.0, max_speed=30.0,
        max_acceleration_rate=1.0, max_deceleration_rate=1.0,
    )  # fmt: skip
    b = bench(100.0, 20.0)
    b.start("Car", keep(30.0, limits=limits))
    car = b.actor("Car")
    accelerations = []
    for _ in range(int(40.0 / DT)):
        before = car.speed
        b.step()
        accelerations.append((car.speed - before) / DT)
    assert max(accelerations) <= 3.0 + 1e-9 and min(accelerations) >= -3.0 - 1e-9
    build_up = [
        a1 - a0
        for a0, a1 in itertools.pairwise(accelerations)
        if a1 < min(a0, 0.0) or a1 > max(a0, 0.0)
    ]
    assert max(abs(d) for d in build_up) <= 1.0 * DT + 1e-9
    assert b.actor("Lead").x - car.x == pytest.approx(30.0, abs=0.2)
    assert car.speed == pytest.approx(10.0, abs=0.1)


def test_any_displacement_keeps_the_side_the_actor_starts_on() -> None:
    b = bench(250.0, 10.0)  # starts 50 m ahead of the reference
    b.start("Car", keep(20.0, displacement="any"))
    b.step(2)
    assert b.actor("Car").x - b.actor("Lead").x == pytest.approx(20.0, abs=1e-6)


def test_gap_is_measured_at_one_instant_when_the_reference_moves_first() -> None:
    limits = model.DynamicConstraints(max_acceleration=2.0, max_deceleration=5.0, max_speed=40.0)
    b = Bench("Lead", "Car")  # the reference moves before the follower in each step
    b.start("Lead", teleport(lane(-1, 100.0)))
    b.start("Lead", speed(25.0))
    b.start("Car", teleport(lane(-1, 40.0)))
    b.start("Car", speed(25.0))
    b.start("Car", keep(30.0, limits=limits))
    b.step(int(25.0 / DT))  # the reference stays short of the road's end (1000 m)
    # measured against the reference's next pose the gap would settle one step short (1.25 m)
    assert b.actor("Lead").x - b.actor("Car").x == pytest.approx(30.0, abs=0.01)
    assert b.actor("Car").speed == pytest.approx(25.0, abs=0.01)
