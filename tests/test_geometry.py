"""Shared geometry: box corners, SAT overlap (rotated boxes), free-space distance, signed gaps
along/across a heading, in-path TTC and THW (ahead/behind, closing/opening, adjacent lane)."""

from __future__ import annotations

import math

import pytest

from simtest_operator import geometry
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState

BOX = BoundingBox(center_x=1.5, length=4.0, width=2.0)


def car(name: str, x: float, y: float, heading: float = 0.0, speed: float = 0.0) -> EntityState:
    return EntityState(
        id=0, name=name, kind=EntityKind.VEHICLE, category="car", x=x, y=y,
        heading=heading, speed=speed, box=BOX,
    )  # fmt: skip


def test_corners_follow_centre_offset_and_heading() -> None:
    corners = geometry.box_corners(car("a", 0.0, 0.0, heading=math.pi / 2))
    xs = sorted(round(c[0], 6) for c in corners)
    ys = sorted(round(c[1], 6) for c in corners)
    assert xs == [-1.0, -1.0, 1.0, 1.0]
    assert ys == [-0.5, -0.5, 3.5, 3.5]


def test_overlap_and_separation() -> None:
    assert geometry.boxes_overlap(car("a", 0, 0), car("b", 3.9, 0))
    assert not geometry.boxes_overlap(car("a", 0, 0), car("b", 4.1, 0))
    assert not geometry.boxes_overlap(car("a", 0, 0), car("b", 0, 2.1))


def test_rotated_boxes_separated_only_on_a_diagonal_axis() -> None:
    # b rotated 45 deg, its corner points at a's front-left corner but does not reach it
    a = car("a", 0, 0)
    b = car("b", 3.5 + 1.0 + 1.5, 1.0 + 1.5, heading=math.pi / 4)
    assert not geometry.boxes_overlap(a, b)
    assert geometry.box_distance(a, b) > 0.0


def test_box_distance_free_space() -> None:
    assert geometry.box_distance(car("a", 0, 0), car("b", 10, 0)) == pytest.approx(6.0)
    assert geometry.box_distance(car("a", 0, 0), car("b", 0, 5)) == pytest.approx(3.0)
    assert geometry.box_distance(car("a", 0, 0), car("b", 1, 0)) == 0.0


def test_signed_gaps() -> None:
    a, ahead, behind = car("a", 0, 0), car("b", 10, 3), car("c", -10, -3)
    assert geometry.longitudinal_gap(a, ahead, freespace=False) == pytest.approx(10.0)
    assert geometry.longitudinal_gap(a, ahead, freespace=True) == pytest.approx(6.0)
    assert geometry.longitudinal_gap(a, behind, freespace=True) == pytest.approx(-6.0)
    assert geometry.lateral_gap(a, ahead, freespace=False) == pytest.approx(3.0)
    assert geometry.lateral_gap(a, behind, freespace=True) == pytest.approx(-1.0)


def test_ttc_and_thw_in_path() -> None:
    ego, lead = car("e", 0, 0, speed=20.0), car("l", 24, 0, speed=10.0)
    assert geometry.time_to_collision(ego, lead) == pytest.approx(2.0)
    assert geometry.time_headway(ego, lead) == pytest.approx(1.0)


def test_ttc_infinite_when_opening_behind_or_adjacent_lane() -> None:
    ego = car("e", 0, 0, speed=20.0)
    assert geometry.time_to_collision(ego, car("l", 24, 0, speed=25.0)) == math.inf
    assert geometry.time_to_collision(ego, car("b", -24, 0, speed=0.0)) == math.inf
    assert geometry.time_to_collision(ego, car("n", 24, 3.5, speed=0.0)) == math.inf
    assert geometry.time_headway(car("s", 0, 0), car("l", 24, 0)) == math.inf


def test_wrap_angle() -> None:
    assert geometry.wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert geometry.to_local(1, 1, math.pi / 2, 1, 3) == pytest.approx((2.0, 0.0))
