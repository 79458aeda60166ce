"""OpenDRIVE signals: read with bounds (malformed and oversized input refused with the element and
line), placed as stop lines (CARLA's references replace the pole's position, validity or
orientation picks the lanes, only driving lanes) on a hand-written road and on the shipped CARLA
towns, and crossed only in the travel direction within the line's span."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simtest_operator import maps
from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import (
    Control,
    RoadNetwork,
    limits,
    parse,
    traffic_controls,
)

CROSSING = Path(__file__).resolve().parents[1] / "sim" / "carla" / "crossing.xodr"


def road_with(signals: str) -> bytes:
    return (
        '<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>'
        '<road id="r" length="100" junction="-1"><planView>'
        '<geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry></planView>'
        '<lanes><laneSection s="0"><left><lane id="1" type="driving"><width sOffset="0" a="3.5"/>'
        '</lane></left><center><lane id="0" type="none"/></center><right>'
        '<lane id="-1" type="driving"><width sOffset="0" a="3.5"/></lane>'
        '<lane id="-2" type="sidewalk"><width sOffset="0" a="2.0"/></lane></right></laneSection>'
        f"</lanes><signals>{signals}</signals></road></OpenDRIVE>"
    ).encode()


LIGHT = (
    '<signal id="7" name="L" s="50" t="-6" orientation="{orientation}" dynamic="yes" '
    'country="OpenDRIVE" type="1000001" subtype="-1">{validity}</signal>'
)


def light(orientation: str = "+", validity: str = "") -> str:
    return LIGHT.format(orientation=orientation, validity=validity)


def test_signal_fields_are_read() -> None:
    document = parse(road_with(light(validity='<validity fromLane="-1" toLane="1"/>')))
    (signal,) = document.roads[0].signals
    place = signal.placement
    assert (signal.id, signal.name, place.road_id, place.s, place.t, place.orientation) == (
        "7", "L", "r", 50.0, -6.0, "+"
    )  # fmt: skip
    assert (signal.dynamic, signal.country, signal.type, signal.subtype) == (
        True, "OpenDRIVE", "1000001", "-1"
    )  # fmt: skip
    assert [v.lane_ids for v in place.validities] == [(-1, 1)]


@pytest.mark.parametrize(
    ("signals", "message"),
    [
        (light().replace('id="7" ', ""), "attribute 'id' is missing"),
        (light().replace('s="50"', 's="nan"'), "is not finite"),
        (light().replace('s="50"', 's="1e9"'), "outside"),
        (light().replace('t="-6"', 't="north"'), "t='north' is invalid"),
        (light(orientation="up"), "orientation='up' is not"),
        (light().replace('dynamic="yes"', 'dynamic="maybe"'), "dynamic='maybe'"),
        (light(validity='<validity fromLane="-1" toLane="9999"/>'), "validity lanes"),
        (light(validity='<validity fromLane="-1"/>'), "'toLane' is missing"),
        ('<signalReference s="10" t="0" orientation="+"/>', "attribute 'id' is missing"),
    ],
)
def test_malformed_signals_are_refused_with_element_and_line(signals: str, message: str) -> None:
    with pytest.raises(ScenarioError, match=message) as caught:
        parse(road_with(signals), source="s.xodr")
    assert caught.value.file == "s.xodr"
    assert caught.value.element in ("signal", "signalReference", "validity")
    assert caught.value.line == 1


def test_too_many_signals_are_refused() -> None:
    many = light() * 3
    parse(road_with(many), bounds=limits.Limits(max_signals=3))
    with pytest.raises(ScenarioError, match="more than 2 signals"):
        parse(road_with(many), bounds=limits.Limits(max_signals=2))


def test_signal_s_past_the_road_end_is_clamped() -> None:
    # Town06 has a reference 0.9 m beyond its road: it still governs that end.
    document = parse(road_with(light().replace('s="50"', 's="100.9"')))
    assert document.roads[0].signals[0].placement.s == 100.0


def test_lanes_from_validity_orientation_and_type() -> None:
    def lanes(signals: str) -> list[int]:
        (control,) = traffic_controls(RoadNetwork(parse(road_with(signals))))
        return [line.lane_id for line in control.lines]

    assert lanes(light("+")) == [-1]  # -2 is a sidewalk
    assert lanes(light("-")) == [1]
    assert lanes(light("none")) == [1, -1]
    assert lanes(light("+", '<validity fromLane="0" toLane="0"/>')) == [-1]
    assert lanes(light("+", '<validity fromLane="1" toLane="1"/>')) == [1]


def test_other_signals_are_no_stop_lines() -> None:
    sign = light().replace("1000001", "274")  # a speed limit
    assert traffic_controls(RoadNetwork(parse(road_with(sign)))) == ()


def test_reference_replaces_the_pole_position() -> None:
    network = RoadNetwork.from_file(CROSSING)
    light_, stop = traffic_controls(network)
    assert (light_.signal_id, light_.control, stop.control) == (
        "10", Control.TRAFFIC_LIGHT, Control.STOP_SIGN
    )  # fmt: skip
    assert (light_.position.x, light_.position.y) == pytest.approx((96.0, -8.5))
    assert [(line.lane_id, line.s) for line in light_.lines] == [(-1, 100.0), (-2, 100.0)]
    assert [(line.lane_id, line.s) for line in stop.lines] == [(-1, 200.0), (-2, 200.0)]
    first = light_.lines[0]
    # 90 % of the 3.5 m lane, centred on it; traffic in lane -1 runs along +x.
    assert first.start == pytest.approx((100.0, -1.75 - 1.575))
    assert first.end == pytest.approx((100.0, -1.75 + 1.575))
    assert first.heading == pytest.approx(0.0)


def test_crossing_only_forwards_and_within_the_span() -> None:
    (line, _) = traffic_controls(RoadNetwork.from_file(CROSSING))[0].lines
    assert line.crossed_by((99.0, -1.75), (100.0, -1.75))  # reaching the line counts
    assert not line.crossed_by((100.0, -1.75), (101.0, -1.75))  # ... only once
    assert not line.crossed_by((101.0, -1.75), (99.0, -1.75))  # backwards
    assert not line.crossed_by((99.0, -5.0), (101.0, -5.0))  # next lane's line, not this
    assert not line.crossed_by((90.0, -1.75), (95.0, -1.75))


@pytest.mark.parametrize(
    ("town", "lights", "stops"), [("Town01", 36, 0), ("Town07", 17, 19), ("Town10HD", 17, 3)]
)
def test_carla_towns(town: str, lights: int, stops: int) -> None:
    path = maps.MapLibraries.with_user().find(town)
    assert path is not None
    controls = traffic_controls(RoadNetwork.from_file(path))
    kinds = [c.control for c in controls]
    assert (kinds.count(Control.TRAFFIC_LIGHT), kinds.count(Control.STOP_SIGN)) == (lights, stops)
    # Every light governs lanes through its junction references, at most across the junction
    # from its pole (Town10HD's lights stand on the far side, up to 36 m away).
    for control in controls:
        if control.control is Control.TRAFFIC_LIGHT:
            assert control.lines
            nearest = min(
                math.hypot(line.start[0] - control.position.x, line.start[1] - control.position.y)
                for line in control.lines
            )
            assert nearest < 40.0
