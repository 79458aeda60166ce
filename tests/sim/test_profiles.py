"""Speed-profile planning against the reference player's documented behaviour (the expected
speeds of esmini's own speed-profile unit tests): position mode rides the straight speed lines
(entry times are durations; a zero duration jumps), follow mode turns between them with limited
jerk, a single follow-mode target is reached on time or, under tight limits, later; entries
without time use the acceleration limits; a non-zero initial acceleration is honoured."""

from __future__ import annotations

import pytest

from simtest_operator.sim import profiles

SOFT = profiles.Limits(
    acceleration=4.0, deceleration=5.0, acceleration_rate=1.0, deceleration_rate=2.0
)


def speeds(
    entries: list[tuple[float | None, float]],
    times: list[float],
    *,
    speed: float,
    follow: bool,
    limits: profiles.Limits = SOFT,
    start: float = 0.0,
    acceleration: float = 0.0,
) -> list[float]:
    plan = profiles.plan(
        entries, start=start, speed=speed, acceleration=acceleration, follow=follow, limits=limits
    )
    return [profiles.speed_at(plan, t) for t in times]


def test_position_mode_rides_the_lines_with_durations_between_entries() -> None:
    got = speeds([(10.0, 0.0), (5.0, 30.0)], [5.0, 8.0, 14.0, 17.0, 20.0, 25.0],
                 speed=10.0, follow=False, start=5.0)  # fmt: skip
    assert got == pytest.approx([10.0, 7.0, 1.0, 12.0, 30.0, 30.0])


def test_a_zero_duration_last_entry_jumps() -> None:
    got = speeds([(10.0, 0.0), (5.0, 30.0), (0.0, 40.0)], [14.0, 15.0, 16.0],
                 speed=10.0, follow=False)  # fmt: skip
    assert got == pytest.approx([24.0, 40.0, 40.0])


def test_position_mode_starts_at_a_first_entry_at_time_zero() -> None:
    got = speeds([(0.0, 0.0), (10.0, 10.0), (10.0, 5.0)], [0.0, 1.0, 11.0],
                 speed=10.0, follow=False)  # fmt: skip
    assert got == pytest.approx([0.0, 1.0, 9.5])


def test_follow_mode_starts_from_the_current_speed_and_turns_with_limited_jerk() -> None:
    got = speeds([(0.0, 0.0), (10.0, 10.0), (10.0, 5.0)], [0.0, 9.0, 11.0],
                 speed=10.0, follow=True)  # fmt: skip
    assert got == pytest.approx([10.0, 10.0, 9.5])


def test_single_follow_target_is_reached_on_time() -> None:
    got = speeds([(10.0, 20.0)], [0.0, 9.0, 12.0], speed=1.0, follow=True)
    assert got == pytest.approx([1.0, 19.0, 20.0])
    braking = speeds([(10.0, 0.0)], [0.0, 4.0, 8.0, 10.0], speed=19.0, follow=True)
    assert braking == pytest.approx([19.0, 11.13664, 2.0, 0.0], abs=1e-5)


def test_single_follow_target_under_a_tight_acceleration_limit_arrives_later() -> None:
    tight = profiles.Limits(
        acceleration=1.0, deceleration=5.0, acceleration_rate=1.0, deceleration_rate=2.0
    )
    got = speeds([(10.0, 20.0)], [0.0, 9.0, 17.0, 20.0], speed=1.0, follow=True, limits=tight)
    assert got == pytest.approx([1.0, 9.5, 17.5, 20.0])


def test_entries_without_time_use_the_acceleration_limits() -> None:
    limits = profiles.Limits(
        acceleration=5.0, deceleration=10.0, acceleration_rate=5.0, deceleration_rate=5.0
    )
    assert speeds([(None, 10.0)], [2.0], speed=0.0, follow=False, limits=limits) == [10.0]
    follow = speeds([(0.0, 0.0), (None, 10.0)], [2.0, 4.0], speed=0.0, follow=True,
                    limits=limits)  # fmt: skip
    assert follow == pytest.approx([7.5, 10.0])


def test_follow_mode_from_a_later_start_time() -> None:
    limits = profiles.Limits(
        acceleration=4.0, deceleration=10.0, acceleration_rate=5.0, deceleration_rate=4.0
    )
    times = [3.2, 4.0, 5.0, 6.0, 8.0]
    entries: list[tuple[float | None, float]] = [(0.0, 0.0), (4.0, 6.0)]
    position = speeds(entries, times, speed=0.0, follow=False, limits=limits, start=3.0)
    assert position == pytest.approx([0.3, 1.5, 3.0, 4.5, 6.0])
    follow = speeds(entries, times, speed=0.0, follow=True, limits=limits, start=3.0)
    assert follow == pytest.approx([0.1, 1.38033, 3.03419, 4.68805, 6.0], abs=1e-5)


def test_follow_mode_honours_the_initial_acceleration() -> None:
    limits = profiles.Limits(
        acceleration=4.0, deceleration=10.0, acceleration_rate=5.0, deceleration_rate=4.0
    )
    got = speeds([(5.0, 4.0)], [0.4, 5.0, 5.2], speed=10.0, follow=True, limits=limits,
                 start=0.1, acceleration=1.0)  # fmt: skip
    assert got == pytest.approx([10.12, 4.025, 4.0], abs=1e-3)


def test_follow_mode_entries_asking_for_more_than_the_limits_are_reached_later() -> None:
    # esmini's speed-profile_test Car2: from a stop, 10 m/s "in 2 s" under maxAcceleration 1:
    # the car accelerates at 1 m/s² (after a 2 m/s³ ramp) and reaches 10 m/s after ~10.75 s
    # (esmini: 0.75, 1.75, 9.72 and 10.0 m/s at 1, 2, 10 and 11 s).
    limits = profiles.Limits(
        acceleration=1.0, deceleration=10.0, acceleration_rate=2.0, deceleration_rate=1.0
    )
    got = speeds([(2.0, 10.0), (10.0, 10.0)], [1.0, 2.0, 10.0, 11.0], speed=0.0, follow=True,
                 limits=limits)  # fmt: skip
    assert got == pytest.approx([0.75, 1.75, 9.71875, 10.0])
