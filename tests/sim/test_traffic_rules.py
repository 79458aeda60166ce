"""Traffic rules without SUMO, on a recording fake host: a sink removes at its rate (all at once
without one), only its definition's categories and never engine entities; a swarm asks for
vehicles only in its ring and in the requested direction of travel; stopping unknown traffic and
unknown categories are scenario errors."""

from __future__ import annotations

import math
from collections.abc import Sequence

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim.backends import ActorState, LaneSlot, TrafficVehicle
from simtest_operator.sim.traffic import Traffic
from tests.sim.worlds import Bench, lane, speed, teleport


class FakeHost:
    """Lane points every 5 m on two opposite lanes along x; records spawns and removals."""

    def __init__(self) -> None:
        self.spawned: list[TrafficVehicle] = []
        self.removed: list[str] = []
        self._slots = [
            LaneSlot(lane=f"{name}_0", pos=x, x=x, y=y, heading=h, max_speed=20.0)
            for name, y, h in (("E", -1.5, 0.0), ("W", 1.5, math.pi))
            for x in range(5, 1000, 5)
        ]

    def slots(self) -> Sequence[LaneSlot]:
        return self._slots

    def allows(self, lane: str, category: str) -> bool:
        return True

    def spawn(self, vehicle: TrafficVehicle) -> None:
        self.spawned.append(vehicle)

    def remove(self, name: str) -> None:
        self.removed.append(name)


def _vehicle(name: str, x: float, category: str = "car") -> ActorState:
    return ActorState(name=name, x=x, y=-1.5, heading=0.0, speed=10.0, length=4.5, width=1.8,
                      front_offset=2.25, external=True, category=category)  # fmt: skip


def _bench() -> Bench:
    bench = Bench("Ego")
    bench.start("Ego", teleport(lane(-1, 300.0)))
    bench.start("Ego", speed(0.0))
    return bench


def _sink(rate: float | None, categories: tuple[str, ...] = ()) -> model.TrafficSinkAction:
    definition = None
    if categories:
        weights = tuple(model.CategoryWeight(category=c, weight=1.0) for c in categories)
        definition = model.TrafficDefinition(name="d", categories=weights)
    return model.TrafficSinkAction(
        position=model.WorldPosition(x=100.0, y=-1.5), radius=20.0, rate=rate, definition=definition
    )


def test_sink_removes_at_its_rate_and_all_at_once_without_one() -> None:
    bench, host = _bench(), FakeHost()
    traffic = Traffic(seed=1)
    traffic.start(bench.world, host, _sink(rate=2.0))
    others = {f"v{i}": _vehicle(f"v{i}", 90.0 + i) for i in range(10)}
    others["far"] = _vehicle("far", 200.0)
    ego = bench.world.state("Ego")
    for _ in range(20):  # one second
        traffic.update(bench.world, host, [ego], {k: v for k, v in others.items()
                                                  if k not in host.removed})  # fmt: skip
    assert len(host.removed) == 2
    everything = Traffic(seed=1)
    host = FakeHost()
    everything.start(bench.world, host, _sink(rate=None))
    everything.update(bench.world, host, [ego], others)
    assert sorted(host.removed) == sorted(f"v{i}" for i in range(10))  # not "far", not Ego


def test_sink_with_a_definition_removes_only_its_categories() -> None:
    bench, host = _bench(), FakeHost()
    traffic = Traffic(seed=1)
    traffic.start(bench.world, host, _sink(rate=None, categories=("truck",)))
    others = {"car": _vehicle("car", 100.0), "truck": _vehicle("truck", 105.0, "truck")}
    traffic.update(bench.world, host, [bench.world.state("Ego")], others)
    assert host.removed == ["truck"]


@pytest.mark.parametrize(("same", "opposite", "heading"), [(1.0, 0.0, 0.0), (0.0, 1.0, math.pi)])
def test_swarm_inserts_in_its_ring_and_direction(
    same: float, opposite: float, heading: float
) -> None:
    bench, host = _bench(), FakeHost()
    traffic = Traffic(seed=5)
    swarm = model.TrafficSwarmAction(
        central_entity="Ego", inner_radius=50.0, semi_major_axis=200.0, semi_minor_axis=20.0,
        offset=0.0, number_of_vehicles=8, velocity=12.0,
        direction=model.DirectionOfTravel(same=same, opposite=opposite),
    )  # fmt: skip
    traffic.start(bench.world, host, swarm)
    ego = bench.world.state("Ego")
    traffic.update(bench.world, host, [ego], {})
    assert len(host.spawned) == 8
    for vehicle in host.spawned:
        distance = math.dist((vehicle.slot.x, vehicle.slot.y), (ego.x, ego.y))
        assert 50.0 < distance <= 200.0
        assert math.cos(vehicle.slot.heading - heading) > 0.99
        assert vehicle.speed == 12.0 and vehicle.category == "car"
    assert len({v.name for v in host.spawned}) == 8


def test_scenario_errors() -> None:
    bench, host = _bench(), FakeHost()
    traffic = Traffic(seed=1)
    with pytest.raises(ScenarioError, match="no running traffic called 'nope'"):
        traffic.start(bench.world, host, model.TrafficStopAction(traffic_name="nope"))
    with pytest.raises(ScenarioError, match="unknown vehicle category 'hovercraft'"):
        traffic.start(bench.world, host, _sink(rate=None, categories=("hovercraft",)))
