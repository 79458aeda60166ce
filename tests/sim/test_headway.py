"""Time headway of the deprecated ``alongRoute="false"``: the straight distance between the
reference points (the chord across a curve, not the way along the road), defined only while the
reference is ahead."""

from __future__ import annotations

import math

import pytest

from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import Conditions
from tests.sim.worlds import Bench, lane, speed, teleport

RADIUS = 50.0


def headway(bench: Bench) -> float:
    conditions = Conditions(bench.world, lambda *args: False)
    condition = model.TimeHeadwayCondition(
        entity_ref="Lead", value=1.0, rule=model.Rule.LESS_THAN, freespace=False, along_route=False
    )
    bench.world.refresh()
    return conditions._headway(bench.actor("Car"), condition)


def test_along_route_false_is_the_chord_across_the_curve() -> None:
    bench = Bench("Car", "Lead", road="arc.xodr")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-1, 70.0)))
    chord = 2.0 * (RADIUS + 1.75) * math.sin(60.0 / RADIUS / 2.0)
    assert headway(bench) == pytest.approx(chord / 10.0, rel=1e-3)


def test_no_headway_to_a_reference_alongside() -> None:
    bench = Bench("Car", "Lead")
    bench.start("Car", teleport(lane(-1, 50.0)))
    bench.start("Car", speed(10.0))
    bench.start("Lead", teleport(lane(-2, 49.0)))
    assert math.isnan(headway(bench))
