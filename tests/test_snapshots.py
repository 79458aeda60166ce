"""The fast EntityState constructor used on the simulator's hot path.

Covers: ``fast_entity_state`` takes exactly the dataclass fields in their order; what it builds
equals, hashes and prints like the dataclass constructor's value for the same arguments (every
field distinct, so a swapped pair would show), keeps signed zeros and ``None`` values as given,
and stays frozen. The velocity: ``travel`` where the motion gave one, else the speed along the
heading; the box centre's adds its turn round the reference point.
"""

from __future__ import annotations

import dataclasses
import inspect
import math

import pytest

from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, fast_entity_state


def _values(**changes: object) -> dict[str, object]:
    values: dict[str, object] = {
        "id": 7,
        "name": "Car7",
        "kind": EntityKind.PEDESTRIAN,
        "category": "pedestrian",
        "x": 1.5,
        "y": -2.25,
        "z": 0.125,
        "heading": 0.75,
        "pitch": 0.0625,
        "roll": -0.03125,
        "speed": 13.5,
        "acceleration": -1.75,
        "travel": (12.5, -0.375),
        "yaw_rate": 0.0625,
        "box": BoundingBox(center_x=1.4, length=4.5, width=1.8),
        "road_id": "12",
        "lane_id": -2,
        "s": 101.5,
        "t": 0.4375,
    }
    values.update(changes)
    return values


def test_parameters_are_the_fields_in_order() -> None:
    parameters = list(inspect.signature(fast_entity_state).parameters)
    assert parameters == [field.name for field in dataclasses.fields(EntityState)]


@pytest.mark.parametrize(
    "changes",
    [
        {},
        {"road_id": None, "lane_id": None, "s": None, "t": None},
        {"x": -0.0, "heading": -0.0, "speed": 0.0},
        {"kind": EntityKind.MISC_OBJECT, "box": BoundingBox()},
    ],
)
def test_same_value_as_the_dataclass_constructor(changes: dict[str, object]) -> None:
    values = _values(**changes)
    fast = fast_entity_state(*values.values())  # type: ignore[arg-type]
    slow = EntityState(**values)  # type: ignore[arg-type]
    assert type(fast) is EntityState
    assert fast == slow
    assert hash(fast) == hash(slow)
    assert repr(fast) == repr(slow)
    for field in dataclasses.fields(EntityState):
        assert getattr(fast, field.name) is values[field.name], field.name


def test_stays_frozen() -> None:
    fast = fast_entity_state(*_values().values())  # type: ignore[arg-type]
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.x = 3.0  # type: ignore[misc]
    assert dataclasses.replace(fast, x=3.0).x == 3.0


def test_velocity_is_the_travel_where_given() -> None:
    state = EntityState(**_values(heading=0.0, speed=10.0, travel=None))  # type: ignore[arg-type]
    assert state.velocity() == (10.0, 0.0)
    crabbing = dataclasses.replace(state, heading=math.pi / 2, travel=(10.0, 0.0))
    assert crabbing.velocity() == (10.0, 0.0)


def test_box_velocity_is_the_derivative_of_the_box_centre() -> None:
    """A box whose centre lies ahead of and beside the reference point, turning while it moves:
    the box velocity is the box centre's rate of change (central difference)."""
    box = BoundingBox(center_x=1.4, center_y=-0.3)
    rate, dt = 2.0, 1e-6

    def at(time: float) -> EntityState:
        return EntityState(
            id=1, name="c", kind=EntityKind.VEHICLE, category="car", x=5.0 * time, y=0.0,
            heading=0.7 + rate * time, speed=5.0, travel=(5.0, 0.0), yaw_rate=rate, box=box,
        )  # fmt: skip

    before, after = at(-dt).box_center(), at(dt).box_center()
    derivative = ((after[0] - before[0]) / (2 * dt), (after[1] - before[1]) / (2 * dt))
    assert at(0.0).box_velocity() == pytest.approx(derivative, rel=1e-6)
