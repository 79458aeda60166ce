"""TrafficActions: swarms around an entity, sources and sinks, run on the backend's traffic.

OpenSCENARIO's traffic actions create or remove anonymous vehicles whose behaviour belongs to a
traffic simulation. The engine decides where and when (this module, with its own RNG seeded from
the run's seed); the backend (:class:`~simtest_operator.sim.backends.TrafficHost`, SUMO) inserts
them on lanes and drives them with its own car-following and lane-change models. They come back
each step as external entities: anonymous to conditions (which name entities), visible to the
evaluation (collisions, TTC) and the recording.

Semantics (OpenSCENARIO 1.x, see docs/simulator.md "Traffic"):

- Swarm: up to ``numberOfVehicles`` vehicles inside an ellipse centred ``offset`` m ahead of the
  central entity (semi-major axis along its heading) and outside a circle of ``innerRadius``
  around it. Missing vehicles are inserted at free lane points in that ring, a vehicle that leaves
  the ellipse is removed, so the count is kept as the central entity moves.
- Source: ``rate`` vehicles per second at lane points within ``radius`` of the position.
- Sink: removes traffic (never scenario entities) within ``radius`` at ``rate`` per second, all at
  once without a rate; with a TrafficDefinition only vehicles of its categories.
- The storyboard action completes when started; the traffic keeps going until a
  TrafficStopAction names its ``trafficName`` (vehicles already inserted stay, driven by SUMO).
"""

from __future__ import annotations

import math
import random
from collections.abc import Mapping, Sequence

import numpy as np

from simtest_operator.errors import ScenarioError, UnsupportedFeatureError
from simtest_operator.openscenario import model
from simtest_operator.sim import positions
from simtest_operator.sim.backends import ActorState, LaneSlot, TrafficHost, TrafficVehicle
from simtest_operator.sim.vehicle_types import vehicle_type
from simtest_operator.sim.world import World
from simtest_operator.snapshots import EntityState

SPAWN_GAP = 8.0
"""Free space (m) kept along the lane between an inserted vehicle and anyone in its way."""
LANE_CLEARANCE = 2.5
"""Lateral distance (m) below which someone is in the way of an inserted vehicle (lanes are
about 3-3.75 m apart, so a vehicle in the next lane does not block)."""
_TRIES = 12
"""Free lane points tried per vehicle (a lane may forbid its category) before giving up."""
_EPSILON = 1e-9
"""Tolerance of the fractional insert/remove budgets (0.1 added ten times is not quite 1)."""
_DEFAULT = (model.CategoryWeight(category="car", weight=1.0),)


class _Occupancy:
    """Where everyone is this step (reference points and half lengths), for insertion gaps."""

    __slots__ = ("half", "x", "y")

    def __init__(self, points: list[tuple[float, float, float]]) -> None:
        self.x = np.array([p[0] for p in points], dtype=float)
        self.y = np.array([p[1] for p in points], dtype=float)
        self.half = np.array([p[2] for p in points], dtype=float)

    def free(
        self, x: np.ndarray, y: np.ndarray, heading: np.ndarray, half_length: float
    ) -> np.ndarray:
        """Which lane points (x, y, driving direction) leave room for a vehicle of this half
        length: nobody within the gap along the lane who overlaps it sideways (a vehicle one
        lane over does not block)."""
        if not len(self.x) or not len(x):
            return np.ones(len(x), dtype=bool)
        dx = self.x[None, :] - x[:, None]
        dy = self.y[None, :] - y[:, None]
        cos_h, sin_h = np.cos(heading)[:, None], np.sin(heading)[:, None]
        along = np.abs(dx * cos_h + dy * sin_h)
        across = np.abs(dy * cos_h - dx * sin_h)
        need = half_length + self.half[None, :] + SPAWN_GAP
        blocked = (along < need) & (across < LANE_CLEARANCE)
        result: np.ndarray = ~np.any(blocked, axis=1)
        return result

    def add(self, x: float, y: float, half_length: float) -> None:
        self.x = np.append(self.x, x)
        self.y = np.append(self.y, y)
        self.half = np.append(self.half, half_length)


class _Slots:
    """The backend's insertion points as arrays for vectorised area tests."""

    __slots__ = ("heading", "items", "x", "y")

    def __init__(self, items: Sequence[LaneSlot]) -> None:
        self.items = items
        self.x = np.fromiter((s.x for s in items), dtype=float, count=len(items))
        self.y = np.fromiter((s.y for s in items), dtype=float, count=len(items))
        self.heading = np.fromiter((s.heading for s in items), dtype=float, count=len(items))


class _Generator:
    """One running traffic action."""

    __slots__ = ("action", "label")

    def __init__(self, action: model.TrafficAction, label: str) -> None:
        self.action = action
        self.label = label


class Traffic:
    """The traffic actions of one run and the vehicles they own."""

    __slots__ = ("_budget", "_counter", "_generators", "_owned", "_points", "_rng", "_slots")

    def __init__(self, *, seed: int) -> None:
        self._rng = random.Random(f"simtest-traffic:{seed}")
        self._generators: list[_Generator] = []
        self._owned: dict[int, set[str]] = {}
        """Vehicles of each swarm (by generator id) still in the world."""
        self._budget: dict[int, float] = {}
        """Vehicles a source may still insert / a sink may still remove (fractional)."""
        self._points: dict[int, tuple[float, float, np.ndarray]] = {}
        """Source/sink position and (source) indices of the lane points within its radius."""
        self._slots: _Slots | None = None
        self._counter = 0

    @property
    def active(self) -> bool:
        return bool(self._generators)

    def start(self, world: World, host: TrafficHost | None, action: model.TrafficAction) -> None:
        """Start (or, for TrafficStopAction, stop) a traffic action; Invalid without a host."""
        kind = type(action).__name__
        if isinstance(action, model.TrafficStopAction):
            self._stop(action)
            return
        if host is None:
            why = (
                "the scenario has no road network (open space)"
                if world.roads is None
                else "the in-memory backend drives no traffic (run it on SUMO)"
            )
            raise UnsupportedFeatureError(
                f"{kind} needs SUMO traffic on a road network: {why}",
                element=kind,
                line=action.line,
            )
        if isinstance(action, model.TrafficSwarmAction):
            world.actor(action.central_entity)  # ScenarioError when it does not exist
            if action.semi_major_axis <= 0.0 or action.semi_minor_axis <= 0.0:
                raise ScenarioError(
                    "a swarm needs positive semi axes", element=kind, line=action.line
                )
        if action.definition is not None:
            for entry in action.definition.categories:
                vehicle_type(entry.category)
        label = action.traffic_name or kind.removeprefix("Traffic").removesuffix("Action").lower()
        generator = _Generator(action, label)
        key = id(generator)
        if isinstance(action, model.TrafficSwarmAction):
            self._owned[key] = set()
        else:
            placement = positions.resolve(world, action.position)
            self._points[key] = (placement.x, placement.y, np.empty(0, dtype=int))
            self._budget[key] = 0.0
        self._generators.append(generator)

    def _stop(self, action: model.TrafficStopAction) -> None:
        if action.traffic_name is None:
            raise ScenarioError(
                "TrafficStopAction needs the trafficName of the traffic to stop",
                element="TrafficStopAction",
                line=action.line,
            )
        kept = [g for g in self._generators if g.action.traffic_name != action.traffic_name]
        if len(kept) == len(self._generators):
            raise ScenarioError(
                f"no running traffic called {action.traffic_name!r} to stop",
                element="TrafficStopAction",
                line=action.line,
            )
        self._generators = kept

    # --- per step -----------------------------------------------------------------------------

    def update(
        self,
        world: World,
        host: TrafficHost,
        entities: Sequence[EntityState],
        others: Mapping[str, ActorState],
    ) -> None:
        """Insert and remove traffic for the coming step (poses as of now)."""
        if self._slots is None:
            self._slots = _Slots(host.slots())
        external = {name: s for name, s in sorted(others.items()) if s.external}
        occupancy = _Occupancy(
            [(e.x, e.y, e.box.length / 2.0) for e in entities]
            + [(s.x, s.y, s.length / 2.0) for s in external.values()]
        )
        for generator in list(self._generators):
            action = generator.action
            if isinstance(action, model.TrafficSwarmAction):
                self._swarm(generator, action, world, host, external, occupancy)
            elif isinstance(action, model.TrafficSourceAction):
                self._source(generator, action, world.dt, host, occupancy)
            elif isinstance(action, model.TrafficSinkAction):
                self._sink(generator, action, world.dt, host, external)

    def _swarm(
        self,
        generator: _Generator,
        action: model.TrafficSwarmAction,
        world: World,
        host: TrafficHost,
        external: dict[str, ActorState],
        occupancy: _Occupancy,
    ) -> None:
        owned = self._owned[id(generator)]
        owned.intersection_update(external)
        central = world.actor(action.central_entity)
        if not central.placed:
            return
        state = world.state(central.name)
        cos_h, sin_h = math.cos(state.heading), math.sin(state.heading)
        cx, cy = state.x + action.offset * cos_h, state.y + action.offset * sin_h
        a, b = action.semi_major_axis, action.semi_minor_axis

        def inside(x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | bool:
            u = (x - cx) * cos_h + (y - cy) * sin_h
            v = -(x - cx) * sin_h + (y - cy) * cos_h
            return (u / a) ** 2 + (v / b) ** 2 <= 1.0

        for gone in sorted(owned):
            vehicle = external[gone]
            if not inside(vehicle.x, vehicle.y):
                host.remove(gone)
                owned.discard(gone)
        missing = action.number_of_vehicles - len(owned)
        if missing <= 0:
            return
        slots = self._slots
        assert slots is not None
        ring = inside(slots.x, slots.y) & (
            np.hypot(slots.x - state.x, slots.y - state.y) > action.inner_radius
        )
        everywhere = np.flatnonzero(ring)
        same = np.cos(slots.heading - state.heading) >= 0.0
        groups = (np.flatnonzero(ring & same), np.flatnonzero(ring & ~same))
        for _ in range(missing):
            candidates = everywhere
            if action.direction is not None:
                weights = (action.direction.same, action.direction.opposite)
                first = 0 if self._rng.random() * sum(weights) < weights[0] else 1
                candidates = groups[first] if len(groups[first]) else groups[1 - first]
            speed = action_speed(action, self._rng)
            added = self._insert(generator, action, host, candidates, occupancy, speed)
            if added is None:
                break
            owned.add(added)

    def _source(
        self,
        generator: _Generator,
        action: model.TrafficSourceAction,
        dt: float,
        host: TrafficHost,
        occupancy: _Occupancy,
    ) -> None:
        key = id(generator)
        x, y, candidates = self._points[key]
        slots = self._slots
        assert slots is not None
        if not len(candidates):
            distance = np.hypot(slots.x - x, slots.y - y)
            candidates = np.flatnonzero(distance <= action.radius)
            if not len(candidates) and len(distance):
                nearest = int(np.argmin(distance))
                if distance[nearest] <= action.radius + 5.0:
                    candidates = np.array([nearest])
            if not len(candidates):
                raise ScenarioError(
                    f"no lane within {action.radius:g} m of the traffic source at "
                    f"({x:.1f}, {y:.1f})",
                    element="TrafficSourceAction",
                    line=action.line,
                )
            self._points[key] = (x, y, candidates)
        budget = min(self._budget[key] + action.rate * dt, max(1.0, action.rate))
        while budget >= 1.0 - _EPSILON:
            speed = action.speed
            if self._insert(generator, action, host, candidates, occupancy, speed) is None:
                break
            budget -= 1.0
        self._budget[key] = budget

    def _sink(
        self,
        generator: _Generator,
        action: model.TrafficSinkAction,
        dt: float,
        host: TrafficHost,
        external: dict[str, ActorState],
    ) -> None:
        key = id(generator)
        x, y, _ = self._points[key]
        if action.rate is None:
            budget = math.inf
        else:
            budget = min(self._budget[key] + action.rate * dt, max(1.0, action.rate))
        wanted = None
        if action.definition is not None:
            wanted = {c.category for c in action.definition.categories if c.weight > 0.0}
        near = sorted(
            (math.hypot(s.x - x, s.y - y), name)
            for name, s in external.items()
            if math.hypot(s.x - x, s.y - y) <= action.radius + s.length / 2.0
            and (wanted is None or s.category in wanted)
        )
        for _, name in near:
            if budget < 1.0 - _EPSILON:
                break
            host.remove(name)
            del external[name]
            budget -= 1.0
        self._budget[key] = 0.0 if math.isinf(budget) else budget

    def _insert(
        self,
        generator: _Generator,
        action: model.TrafficSwarmAction | model.TrafficSourceAction,
        host: TrafficHost,
        candidates: np.ndarray,
        occupancy: _Occupancy,
        speed: float | None,
    ) -> str | None:
        """Insert one vehicle at a free random lane point among ``candidates``; its name, or
        None when no free point was found."""
        if not len(candidates):
            return None
        slots = self._slots
        assert slots is not None
        definition = action.definition
        categories = definition.categories if definition is not None else _DEFAULT
        category = self._rng.choices(
            [c.category for c in categories], weights=[c.weight for c in categories]
        )[0]
        kind = vehicle_type(category)
        half = kind.length / 2.0
        free = candidates[
            occupancy.free(
                slots.x[candidates], slots.y[candidates], slots.heading[candidates], half
            )
        ]
        for _ in range(_TRIES):
            if not len(free):
                return None
            pick = self._rng.randrange(len(free))
            slot = slots.items[int(free[pick])]
            if not host.allows(slot.lane, category):
                free = np.delete(free, pick)
                continue
            self._counter += 1
            name = f"traffic_{generator.label}_{self._counter}"
            if speed is not None:
                speed = min(max(speed, 0.0), kind.max_speed)
            host.spawn(TrafficVehicle(name=name, category=category, slot=slot, speed=speed))
            occupancy.add(slot.x, slot.y, half)
            return name
        return None


def action_speed(action: model.TrafficSwarmAction, rng: random.Random) -> float | None:
    """Initial speed of a new swarm vehicle: the range (uniform), else ``velocity``, else None
    (the lane's speed limit)."""
    if action.speed_range is not None:
        return rng.uniform(action.speed_range.lower, action.speed_range.upper)
    return action.velocity
