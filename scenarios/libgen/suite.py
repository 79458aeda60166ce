"""The parameter grids that make the 200-scenario suite and the smoke set.

Each grid is a full factorial over a few values per parameter, chosen so that a sensible
system under test (car-following with automatic emergency braking) passes most combinations
and the corners are genuinely hard: small gaps, large speed differences, late pedestrians,
a target turning left just ahead of the ego. Change a grid here and regenerate.
"""

from __future__ import annotations

from itertools import product

from libgen import crossing, lateral, longitudinal, roads
from libgen.blueprints import CATEGORIES, SEARCH_CATEGORIES, Blueprint

SUITE_SIZE = 200


def _following() -> list[Blueprint]:
    highway = [
        longitudinal.following(road=roads.HIGHWAY, speed=v, thw=thw, drop=drop, decel=decel)
        for v, thw, (drop, decel) in product(
            (25.0, 30.0, 35.0), (1.2, 1.8), ((10.0, 2.0), (15.0, 3.5))
        )
    ]
    rural = [
        longitudinal.following(road=roads.RURAL, speed=v, thw=thw, drop=drop, decel=decel)
        for v, thw, (drop, decel) in product(
            (15.0, 20.0, 25.0), (1.2, 1.8), ((5.0, 2.0), (10.0, 3.5))
        )
    ]
    return highway + rural


def _hard_braking() -> list[Blueprint]:
    highway = [
        longitudinal.hard_braking(road=roads.HIGHWAY, speed=v, thw=thw, decel=decel)
        for v, thw, decel in product((25.0, 30.0, 35.0), (1.0, 1.5, 2.0), (5.0, 9.0))
    ]
    rural = [
        longitudinal.hard_braking(road=roads.RURAL, speed=v, thw=thw, decel=decel)
        for v, thw, decel in product((15.0, 20.0, 25.0), (1.0, 1.5, 2.0), (5.0, 9.0))
    ]
    return highway + rural


def _cut_out() -> list[Blueprint]:
    return [
        longitudinal.cut_out(speed=v, ttc=ttc, obstacle_speed=obstacle)
        for v, ttc, obstacle in product((20.0, 25.0, 30.0, 35.0), (1.5, 2.5, 4.0), (0.0, 8.0))
    ]


def _cut_in() -> list[Blueprint]:
    return [
        lateral.cut_in(speed=v, gap=gap, dv=dv)
        for v, gap, dv in product((20.0, 25.0, 30.0, 35.0), (10.0, 15.0, 25.0, 40.0), (5.0, 10.0))
    ]


def _lane_change() -> list[Blueprint]:
    return [
        lateral.lane_change(speed=v, dv=dv, gap=gap)
        for v, dv, gap in product((25.0, 30.0), (4.0, 8.0), (8.0, 12.0, 20.0, 30.0, 45.0))
    ]


def _merge() -> list[Blueprint]:
    return [
        lateral.merge(speed=v, merger_speed=vm, gap=gap)
        for v, vm, gap in product((25.0, 30.0), (15.0, 20.0, 25.0), (8.0, 20.0, 35.0, 50.0))
    ]


def _ltap() -> list[Blueprint]:
    return [
        crossing.ltap(speed=v, target_speed=vt, offset=dt)
        for v, vt, dt in product((10.0, 14.0), (6.0, 8.0), (-1.5, -0.5, 0.5, 1.5))
    ]


def _pedestrian() -> list[Blueprint]:
    junction = [
        crossing.pedestrian_junction(speed=v, tta=tta, walk_speed=walk)
        for v, tta, walk in product((8.0, 11.0, 14.0), (2.5, 4.0), (1.4, 2.5))
    ]
    rural = [
        crossing.pedestrian_rural(speed=v, tta=tta, side=side)
        for v, tta, side in product((14.0, 17.0, 20.0), (3.0, 4.5), ("near", "far"))
    ]
    return junction + rural


def suite() -> list[Blueprint]:
    """All scenarios of the library, in category order."""
    blueprints = (
        _following()
        + _cut_in()
        + _cut_out()
        + _hard_braking()
        + _lane_change()
        + _merge()
        + _ltap()
        + _pedestrian()
    )
    _check(blueprints, SUITE_SIZE)
    return blueprints


def search_cases() -> list[Blueprint]:
    """Logical scenarios the search benchmark needs beyond the suite (outside its 200): a
    pedestrian who turns back, whose failures form two separate regions over (EgoSpeed,
    TriggerDistance, WalkSpeed)."""
    blueprints = [crossing.pedestrian_turn_back(speed=8.0, tta=7.0, walk_speed=2.5)]
    _check(blueprints, len(blueprints), SEARCH_CATEGORIES)
    return blueprints


def smoke() -> list[Blueprint]:
    """Six short scenarios (10 s each) for the quick start: five a sensible SUT passes and
    one close cut-in it cannot avoid, so both verdicts show up."""
    blueprints = [
        longitudinal.following(
            road=roads.HIGHWAY,
            speed=25.0,
            thw=2.0,
            drop=5.0,
            decel=2.0,
            duration=10.0,
            slow_at=2.0,
        ),
        longitudinal.hard_braking(
            road=roads.RURAL, speed=15.0, thw=2.0, decel=4.0, duration=10.0, brake_at=2.0
        ),
        lateral.cut_in(speed=25.0, gap=30.0, dv=5.0, duration=10.0, lead_time=2.0),
        lateral.merge(speed=25.0, merger_speed=20.0, gap=35.0, duration=10.0),
        crossing.pedestrian_junction(speed=8.0, tta=4.0, walk_speed=1.4, duration=10.0),
        lateral.cut_in(speed=30.0, gap=8.0, dv=12.0, duration=10.0, lead_time=1.0),
    ]
    _check(blueprints, len(blueprints))
    return blueprints


def _check(
    blueprints: list[Blueprint], size: int, categories: tuple[str, ...] = CATEGORIES
) -> None:
    stems = [(b.category, b.stem) for b in blueprints]
    if len(set(stems)) != len(stems):
        raise ValueError("two scenarios share a file name")
    if len(blueprints) != size:
        raise ValueError(f"expected {size} scenarios, built {len(blueprints)}")
    unknown = {b.category for b in blueprints} - set(categories)
    if unknown:
        raise ValueError(f"unknown categories: {sorted(unknown)}")
    for b in blueprints:
        if not 10.0 <= b.duration <= 35.0:
            raise ValueError(f"{b.stem}: duration {b.duration} s outside 10-35 s")
