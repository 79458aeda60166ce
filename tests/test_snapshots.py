"""The fast EntityState constructor used on the simulator's hot path.

Covers: ``fast_entity_state`` takes exactly the dataclass fields in their order; what it builds
equals, hashes and prints like the dataclass constructor's value for the same arguments (every
field distinct, so a swapped pair would show), keeps signed zeros and ``None`` values as given,
and stays frozen.
"""

from __future__ import annotations

import dataclasses
import inspect

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
        "lateral_speed": 0.375,
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
