"""The signal watch on its own: which states are red, how action names find a light (id, ``id=``,
``pos=`` in CARLA's frame, nothing for junk), a light crossed on two approaches counted twice but
two lines of one light on one approach once, and no crossing across a gap where the ego left the
world."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simtest_operator.evaluation.signal_criteria import SignalWatch, is_red
from simtest_operator.opendrive import RoadNetwork, traffic_controls
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState

CROSSING = Path(__file__).resolve().parents[1] / "sim" / "carla" / "crossing.xodr"
BOX = BoundingBox(center_x=1.5, length=4.5, width=2.0)


def hero(x: float, speed: float = 10.0) -> EntityState:
    return EntityState(
        id=0, name="hero", kind=EntityKind.VEHICLE, category="car", x=x, y=-1.75, speed=speed,
        box=BOX,
    )  # fmt: skip


@pytest.fixture(scope="module")
def watch_parts() -> RoadNetwork:
    return RoadNetwork.from_file(CROSSING)


@pytest.mark.parametrize(
    ("state", "red"),
    [("red", True), ("RED", True), ("on;off;off", True), ("on;on;off", True),
     ("green", False), ("off;off;on", False), ("yellow", False), ("", False), ("on", False)],
)  # fmt: skip
def test_red_states(state: str, red: bool) -> None:
    assert is_red(state) is red


@pytest.mark.parametrize(
    ("name", "judged"),
    [("10", True), ("id=10", True), (" pos=96.5, 9.0 ", True), ("pos=96,-8.5", False),
     ("pos=a,b", False), ("id=20", False), ("Signal_3Light_Post01", False)],
)  # fmt: skip
def test_names_of_the_light(watch_parts: RoadNetwork, name: str, judged: bool) -> None:
    watch = SignalWatch(traffic_controls(watch_parts))
    for step, x in enumerate((90.0, 99.0, 100.0)):
        watch.observe(step * 1.0, hero(x), ((name, "red"),))
    assert watch.red_light().passed is (False if judged else None)


def test_every_red_crossing_counts(watch_parts: RoadNetwork) -> None:
    watch = SignalWatch(traffic_controls(watch_parts))
    states = (("10", "red"),)
    for step, x in enumerate((97.0, 100.0, 80.0, 100.0)):  # over the line, back (teleported), over
        watch.observe(step * 1.0, hero(x), states)
    found = watch.red_light()
    assert (found.passed, found.time) == (False, 1.0)
    assert found.detail == "hero crossed red light 10 at t=1.00 s; 2 red lights crossed"


def test_no_crossing_while_the_ego_is_absent(watch_parts: RoadNetwork) -> None:
    watch = SignalWatch(traffic_controls(watch_parts))
    watch.observe(0.0, hero(95.0), (("10", "red"),))
    watch.observe(1.0, None, (("10", "red"),))
    watch.observe(2.0, hero(105.0), (("10", "red"),))
    assert watch.red_light().detail == "crossed no traffic light's stop line"


def test_lines_of_one_light_on_one_approach_count_once(watch_parts: RoadNetwork) -> None:
    (light, stop) = traffic_controls(watch_parts)
    # A second reference 3 m further on (as CARLA puts one in each junction road of a lane).
    later = tuple(
        dataclasses.replace(line, start=(103.0, line.start[1]), end=(103.0, line.end[1]))
        for line in light.lines
    )
    watch = SignalWatch((dataclasses.replace(light, lines=light.lines + later), stop))
    for step, x in enumerate((97.0, 100.0, 103.0, 106.0)):
        watch.observe(step * 1.0, hero(x), (("10", "green"),))
    assert watch.red_light().detail == "passed traffic lights 1 time, never on red"
