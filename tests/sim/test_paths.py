"""Trajectory shapes sampled into paths: a clothoid arc and a spiral against closed forms
(circle, Fresnel series), a clothoid spline segment that starts at its own pose with a heading
offset, per-segment timing of a spline, a timed stop (repeated point), NURBS timing by the peaks of
the control points' basis functions, and ``follow``-mode speeds that reach every vertex on time."""

from __future__ import annotations

import math

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim import nurbs, shapes
from simtest_operator.sim.placements import Placement
from simtest_operator.sim.sampled_paths import build

ORIGIN = Placement(x=0.0, y=0.0, z=0.0, heading=0.0)


def world(x: float, y: float, h: float = 0.0) -> model.WorldPosition:
    return model.WorldPosition(x=x, y=y, h=h)


def resolve(position: model.Position) -> Placement:
    assert isinstance(position, model.WorldPosition)
    return Placement(x=position.x, y=position.y, z=0.0, heading=position.h or 0.0)


def fresnel_spiral(rate: float, s: float) -> tuple[float, float]:
    """(x, y) of a spiral with curvature ``rate * s`` from the origin heading +x (power series)."""
    x = y = 0.0
    term_x, term_y = s, 0.0
    # x = sum (-1)^n a^(2n) s^(4n+1) / ((2n)! (4n+1)), y = sum (-1)^n a^(2n+1) s^(4n+3) / ...
    a = rate / 2.0
    for n in range(12):
        term_x = (-1) ** n * a ** (2 * n) * s ** (4 * n + 1) / (math.factorial(2 * n) * (4 * n + 1))
        term_y = (
            (-1) ** n
            * a ** (2 * n + 1)
            * s ** (4 * n + 3)
            / (math.factorial(2 * n + 1) * (4 * n + 3))
        )
        x += term_x
        y += term_y
    return x, y


def test_clothoid_with_constant_curvature_is_a_circular_arc() -> None:
    radius, length = 50.0, 40.0
    shape = model.Clothoid(curvature=1.0 / radius, curvature_prime=0.0, length=length)
    path = shapes.sample(shape, resolve, ORIGIN)
    assert path.length == pytest.approx(length, abs=1e-3)  # chords of 0.5 m
    for d in (0.0, 13.3, 25.0, 40.0):
        x, y, h = path.at_distance(d)
        angle = d / radius
        assert x == pytest.approx(radius * math.sin(angle), abs=1e-3)
        assert y == pytest.approx(radius * (1.0 - math.cos(angle)), abs=1e-3)
        assert h == pytest.approx(angle, abs=1e-3)


def test_spiral_matches_the_fresnel_closed_form() -> None:
    rate, length = 0.002, 60.0  # curvature 0 -> 0.12 over 60 m
    shape = model.Clothoid(curvature=0.0, curvature_prime=rate, length=length)
    path = shapes.sample(shape, resolve, ORIGIN)
    x, y, h = path.at_distance(length)
    ex, ey = fresnel_spiral(rate, length)
    assert math.hypot(x - ex, y - ey) < 5e-3
    assert h == pytest.approx(rate * length**2 / 2.0, abs=1e-9)


def test_spline_segment_with_its_own_start_jumps_there_and_turns_by_the_offset() -> None:
    spline = model.ClothoidSpline(
        segments=(
            model.ClothoidSplineSegment(curvature_start=0.0, curvature_end=0.0, length=10.0),
            model.ClothoidSplineSegment(
                curvature_start=0.0,
                curvature_end=0.0,
                length=5.0,
                h_offset=0.4,
                position_start=world(10.0, -1.0, 0.2),
            ),
        )
    )
    path = shapes.sample(spline, resolve, ORIGIN)
    x, y, h = path.at_distance(path.length)
    assert x == pytest.approx(10.0 + 5.0 * math.cos(0.6), abs=1e-6)
    assert y == pytest.approx(-1.0 + 5.0 * math.sin(0.6), abs=1e-6)
    assert h == pytest.approx(0.6)


def test_timed_spline_runs_each_segment_at_its_own_speed() -> None:
    spline = model.ClothoidSpline(
        segments=(
            model.ClothoidSplineSegment(
                curvature_start=0.0, curvature_end=0.0, length=10.0, time_start=0.0
            ),
            model.ClothoidSplineSegment(
                curvature_start=0.0, curvature_end=0.0, length=14.0, time_start=2.0
            ),
        ),
        time_end=4.0,
    )
    path = shapes.sample(spline, resolve, ORIGIN)
    assert path.speed_at_time(1.0) == pytest.approx(5.0)
    assert path.speed_at_time(3.0) == pytest.approx(7.0)
    assert path.distance_at_time(3.0) == pytest.approx(17.0)


def test_a_repeated_vertex_with_a_later_time_is_a_stop() -> None:
    path = build([(0.0, 0.0), (10.0, 0.0), (10.0, 0.0)], [0.0, 1.0, 3.0])
    assert path.times == (0.0, 1.0, 3.0)
    assert path.distance_at_time(2.0) == pytest.approx(10.0)
    assert path.speed_at_time(2.5) == 0.0


def test_follow_mode_speeds_change_linearly_and_reach_every_vertex_on_time() -> None:
    # The reference player's bicycle: 10 m/s, then half the distance per second, then a stop.
    path = build(
        [(100.0, 0.0), (120.0, 0.0), (125.0, 0.0), (130.0, 0.0), (130.0, 0.0)],
        [0.0, 2.0, 2.5, 3.5, 4.0],
    ).following(10.0)
    assert path.speeds == (10.0, 10.0, 10.0, 0.0, 0.0)
    for t, d in ((2.5, 25.0), (3.5, 30.0), (4.0, 30.0)):
        assert path.distance_at_time(t) == pytest.approx(d)
    assert path.distance_at_time(3.0) == pytest.approx(28.75)  # esmini: x = 128.75 at t = 3
    assert path.speed_at_time(3.0) == pytest.approx(5.0)


def test_follow_mode_starts_at_the_entity_speed_so_a_braking_profile_stays_a_braking_one() -> None:
    # esmini's brake_by_trajectory_100-0: 100 km/h braked at 10 m/s² to 50 km/h, then at
    # 6 m/s² to a stop; the vertex times and distances describe exactly that deceleration.
    v1, v2 = 100 / 3.6, 50 / 3.6
    t1, t2 = (v1 - v2) / 10.0, v2 / 6.0
    d1, d2 = v1 * t1 - 5.0 * t1**2, v2 * t2 - 3.0 * t2**2
    path = build(
        [(0.0, 0.0), (d1, 0.0), (d1 + d2, 0.0), (d1 + d2, 0.0)],
        [0.0, t1, t1 + t2, t1 + t2 + 1.0],
    ).following(-v1)  # the magnitude counts (a reversing entity)
    assert path.speeds == pytest.approx((v1, v2, 0.0, 0.0), abs=1e-9)
    assert path.speed_at_time(1.0) == pytest.approx(v1 - 10.0)
    assert path.distance_at_time(1.0) == pytest.approx(v1 - 5.0)
    assert path.distance_at_time(t1 + 1.0) == pytest.approx(d1 + v2 - 3.0)


def test_nurbs_time_follows_the_peaks_of_the_basis_functions() -> None:
    # Symmetric quadratic NURBS: the middle control point's basis peaks at u = 0.5, so the
    # curve's midpoint is reached at that control point's time even when times are uneven.
    shape = model.Nurbs(
        order=3,
        control_points=tuple(
            model.ControlPoint(position=world(x, y), time=t, weight=1.0)
            for (x, y), t in (((0.0, 0.0), 0.0), ((50.0, 20.0), 1.0), ((100.0, 0.0), 5.0))
        ),
        knots=(0.0, 0.0, 0.0, 1.0, 1.0, 1.0),
    )
    placed = [resolve(cp.position) for cp in shape.control_points]
    path = nurbs.sample(shape, placed)
    assert path.times is not None
    assert path.times[0] == 0.0 and path.times[-1] == pytest.approx(5.0)
    middle = len(path.times) // 2
    assert path.xs[middle] == pytest.approx(50.0, abs=1e-6)
    assert path.times[middle] == pytest.approx(1.0, abs=1e-6)
    assert path.ys[middle] == pytest.approx(10.0, abs=1e-6)  # quadratic Bezier midpoint
