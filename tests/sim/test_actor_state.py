"""Actor.state: built once per change, never stale.

Covers: the state equals a from-scratch ``EntityState`` of the actor's attributes (heading
normalised to [-pi, pi), lane fields only in ROAD mode); asked again with nothing reassigned it
is the very same value; reassigning any attribute it is made of -- also to an equal value of
another sign (``-0.0``) -- gives a new state with that value; leaving ROAD mode drops the lane
fields; a mode change without a lane change (FREE <-> PATH) keeps the state.
"""

from __future__ import annotations

import math

import pytest

from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.snapshots import BoundingBox, EntityState
from tests.sim.worlds import car


def _from_scratch(actor: Actor) -> EntityState:
    road = actor.mode is Mode.ROAD
    return EntityState(
        id=actor.id,
        name=actor.name,
        kind=actor.kind,
        category=actor.category,
        x=actor.x,
        y=actor.y,
        z=actor.z,
        heading=(actor.heading + math.pi) % (2.0 * math.pi) - math.pi,
        pitch=actor.pitch,
        roll=actor.roll,
        speed=actor.speed,
        acceleration=actor.acceleration,
        travel=_travel(actor),
        yaw_rate=actor.yaw_rate,
        box=actor.box,
        road_id=actor.road_id if road else None,
        lane_id=actor.lane_id if road else None,
        s=actor.s if road else None,
    )


def _travel(actor: Actor) -> tuple[float, float] | None:
    if actor.travel is None or actor.speed == actor.travel_speed:
        return actor.travel
    if actor.travel_speed == 0.0:
        return None
    scale = actor.speed / actor.travel_speed
    return actor.travel[0] * scale, actor.travel[1] * scale


def _on_road() -> Actor:
    actor = Actor(car("A"), 3)
    actor.mode = Mode.ROAD
    actor.road_id, actor.lane_id, actor.s = "1", -1, 20.0
    actor.x, actor.y, actor.heading, actor.speed = 10.0, -1.75, 7.0, 12.0
    return actor


def _same_repr(a: EntityState, b: EntityState) -> bool:
    return repr(a) == repr(b)  # repr tells -0.0 from 0.0, == does not


def test_state_is_the_actor_frozen() -> None:
    actor = _on_road()
    state = actor.state()
    assert _same_repr(state, _from_scratch(actor))
    assert -math.pi <= state.heading < math.pi
    assert (state.road_id, state.lane_id, state.s) == ("1", -1, 20.0)


def test_unchanged_actor_gives_the_same_state() -> None:
    actor = _on_road()
    first = actor.state()
    assert actor.state() is first
    actor.driver = None  # not part of the state
    actor.odometer = 5.0
    assert actor.state() is first


@pytest.mark.parametrize(
    ("attribute", "value"),
    [
        ("x", 11.0),
        ("y", -0.0),
        ("z", 0.5),
        ("heading", 0.25),
        ("pitch", 0.01),
        ("roll", -0.0),
        ("speed", 12.5),
        ("acceleration", -3.0),
        ("travel", (3.0, 4.0)),
        ("travel_speed", 2.5),
        ("yaw_rate", 0.2),
        ("road_id", "2"),
        ("lane_id", 1),
        ("s", 21.0),
        ("box", BoundingBox(length=5.0)),
    ],
)
def test_any_reassigned_attribute_gives_a_fresh_state(attribute: str, value: object) -> None:
    actor = _on_road()
    if attribute in {"y", "roll"}:
        setattr(actor, attribute, 0.0)  # then -0.0: equal by ==, a different value all the same
    first = actor.state()
    setattr(actor, attribute, value)
    second = actor.state()
    assert second is not first
    assert _same_repr(second, _from_scratch(actor))
    assert actor.state() is second


def test_equal_value_reassigned_is_still_exact() -> None:
    actor = _on_road()
    actor.speed = 0.0
    first = actor.state()
    actor.speed = float("-0.0")
    assert math.copysign(1.0, actor.state().speed) == -1.0
    assert actor.state() is not first


def test_mode_changes() -> None:
    actor = _on_road()
    on_road = actor.state()
    actor.mode = Mode.FREE
    free = actor.state()
    assert (free.road_id, free.lane_id, free.s) == (None, None, None)
    assert free != on_road
    actor.mode = Mode.PATH
    assert actor.state() is free  # no lane fields either way: the same value
    actor.mode = Mode.ROAD
    assert _same_repr(actor.state(), on_road)


def test_a_speed_set_after_the_motion_scales_its_travel() -> None:
    """An action started at the step's end sets a new speed: the state's velocity keeps the
    direction the motion gave and takes the new speed."""
    actor = _on_road()
    actor.set_travel((6.0, 8.0))  # at speed 12
    assert actor.state().velocity() == (6.0, 8.0)
    actor.speed = 6.0
    assert actor.state().velocity() == (3.0, 4.0)
    actor.speed = 0.0
    assert actor.state().velocity() == (0.0, 0.0)
