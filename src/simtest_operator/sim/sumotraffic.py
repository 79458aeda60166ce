"""SUMO-driven traffic for TrafficActions: insertion points, vehicle types, routes.

Used by :class:`~simtest_operator.sim.sumo.SumoBackend` (which owns the libsumo handle; this
module never imports libsumo). The engine decides *where and when* traffic appears
(:mod:`simtest_operator.sim.traffic`); this module turns that into SUMO vehicles:

- insertion points every :data:`SLOT_SPACING` metres along every non-internal lane, from the
  lane shapes (network coordinates minus the net offset = OpenDRIVE coordinates);
- one vType per OpenSCENARIO category (:mod:`.vehicle_types`), copied from SUMO's default type so
  the Krauss car-following and LC2013 lane-change models drive it;
- insertion with SUMO's ``departSpeed="max"`` (as fast as is safe behind the vehicle ahead) and
  a speed factor making the requested speed the vehicle's desired speed;
- a route per vehicle: a random walk over the lane graph from its start edge (turnarounds
  excluded), drawn from an RNG seeded with the run's seed, so the same seed gives the same routes.
  A vehicle that reaches the end of its route leaves the world (SUMO "arrives" it).

A vehicle whose insertion SUMO refused (a blocked spot) is removed after the step instead of
waiting in SUMO's insertion queue, so it never pops up later somewhere unexpected.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Sequence
from typing import Any

from simtest_operator.errors import SimulationError
from simtest_operator.sim.backends import LaneSlot, TrafficVehicle
from simtest_operator.sim.vehicle_types import VehicleType, vehicle_type

SLOT_SPACING = 5.0
"""Distance between insertion points along a lane (m)."""
_MAX_ROUTE_EDGES = 64
_VCLASS_CATEGORY = {
    "passenger": "car", "private": "car", "taxi": "car", "evehicle": "car", "hov": "car",
    "delivery": "van", "truck": "truck", "trailer": "semitrailer", "bus": "bus", "coach": "bus",
    "motorcycle": "motorbike", "moped": "motorbike", "bicycle": "bicycle", "tram": "tram",
    "rail": "train", "rail_urban": "train",
}  # fmt: skip


def category_of_vclass(vclass: str) -> str:
    """OpenSCENARIO category for a SUMO vehicle class (``car`` when there is no better one)."""
    return _VCLASS_CATEGORY.get(vclass, "car")


class SumoTraffic:
    """Traffic insertion and removal on a running libsumo simulation."""

    __slots__ = (
        "_allowed",
        "_lib",
        "_offset",
        "_queue",
        "_requested",
        "_rng",
        "_slots",
        "_successors",
        "_types",
    )

    def __init__(self, lib: Any, *, offset: tuple[float, float], seed: int) -> None:
        self._lib = lib
        self._offset = offset
        self._rng = random.Random(f"simtest-sumo-routes:{seed}")
        self._slots: tuple[LaneSlot, ...] | None = None
        self._allowed: dict[str, frozenset[str] | None] = {}
        self._successors: dict[str, tuple[str, ...]] = {}
        self._types: set[str] = set()
        self._queue: list[tuple[TrafficVehicle, list[str]]] = []
        self._requested: dict[str, str] = {}
        """Vehicles inserted for the coming step: name -> category."""

    # --- insertion points ---------------------------------------------------------------------

    def slots(self) -> Sequence[LaneSlot]:
        if self._slots is None:
            self._slots = tuple(self._sample_lanes())
        return self._slots

    def _sample_lanes(self) -> list[LaneSlot]:
        lib = self._lib
        off_x, off_y = self._offset
        result: list[LaneSlot] = []
        for edge in sorted(lib.edge.getIDList()):
            if edge.startswith(":"):
                continue
            for index in range(lib.edge.getLaneNumber(edge)):
                lane = f"{edge}_{index}"
                shape = [(x - off_x, y - off_y) for x, y, *_ in lib.lane.getShape(lane)]
                length = lib.lane.getLength(lane)
                max_speed = lib.lane.getMaxSpeed(lane)
                result.extend(_along(lane, shape, length, max_speed))
        return result

    def allows(self, lane: str, category: str) -> bool:
        if lane not in self._allowed:
            allowed = tuple(self._lib.lane.getAllowed(lane))
            self._allowed[lane] = frozenset(allowed) if allowed else None
        permitted = self._allowed[lane]
        return permitted is None or vehicle_type(category).vclass in permitted

    # --- vehicles -----------------------------------------------------------------------------

    def spawn(self, vehicle: TrafficVehicle) -> None:
        """Queue ``vehicle``; :meth:`flush` hands the queue to SUMO before the step."""
        edge = vehicle.slot.lane.rpartition("_")[0]
        self._queue.append((vehicle, self._route(edge)))

    def flush(self) -> None:
        """Add the queued vehicles, front-most first along each edge: SUMO inserts in the order
        of addition per edge, and a vehicle placed ahead of one inserted earlier in the same step
        could be refused for being in its way."""
        queue = sorted(self._queue, key=lambda item: (item[1][0], -item[0].slot.pos))
        self._queue.clear()
        for vehicle, route in queue:
            self._add(vehicle, route)

    def _add(self, vehicle: TrafficVehicle, route: list[str]) -> None:
        lib = self._lib
        kind = vehicle_type(vehicle.category)
        type_id = self._vtype(kind)
        index = vehicle.slot.lane.rpartition("_")[2]
        route_id = f"simtest_route_{vehicle.name}"
        try:
            lib.route.add(route_id, route)
            lib.vehicle.add(
                vehicle.name,
                route_id,
                typeID=type_id,
                depart="now",
                departLane=index,
                departPos=f"{max(vehicle.slot.pos, kind.length):.3f}",
                departSpeed="max",
            )
            if vehicle.speed is not None and vehicle.slot.max_speed > 0.0:
                # Desired speed = the requested one; SUMO inserts as fast as is safe up to it.
                lib.vehicle.setSpeedFactor(
                    vehicle.name, max(vehicle.speed, 0.1) / vehicle.slot.max_speed
                )
        except lib.TraCIException as exc:
            raise SimulationError(f"SUMO refused traffic vehicle {vehicle.name!r}: {exc}") from exc
        self._requested[vehicle.name] = vehicle.category

    def remove(self, name: str) -> None:
        self._requested.pop(name, None)
        self._queue = [item for item in self._queue if item[0].name != name]
        try:
            # libsumo fails the next step on a subscription to a removed vehicle.
            self._lib.vehicle.unsubscribe(name)
            self._lib.vehicle.remove(name)
        except self._lib.TraCIException as exc:
            raise SimulationError(f"SUMO could not remove {name!r}: {exc}") from exc

    def settle(self, departed: Sequence[str]) -> dict[str, str]:
        """After a step: categories of the requested vehicles that departed; the others (SUMO
        could not insert them) are removed from SUMO's insertion queue."""
        done = {name: self._requested.pop(name) for name in departed if name in self._requested}
        if self._requested:
            pending = set(self._lib.simulation.getPendingVehicles())
            for name in sorted(self._requested.keys() & pending):
                self._lib.vehicle.remove(name)
            self._requested.clear()
        return done

    def _vtype(self, kind: VehicleType) -> str:
        type_id = f"simtest_traffic_{kind.category}"
        if type_id in self._types:
            return type_id
        lib = self._lib
        lib.vehicletype.copy("DEFAULT_VEHTYPE", type_id)
        lib.vehicletype.setVehicleClass(type_id, kind.vclass)
        lib.vehicletype.setLength(type_id, kind.length)
        lib.vehicletype.setWidth(type_id, kind.width)
        lib.vehicletype.setHeight(type_id, kind.height)
        lib.vehicletype.setMaxSpeed(type_id, kind.max_speed)
        lib.vehicletype.setAccel(type_id, kind.accel)
        lib.vehicletype.setDecel(type_id, kind.decel)
        self._types.add(type_id)
        return type_id

    def _route(self, start: str) -> list[str]:
        edges = [start]
        while len(edges) < _MAX_ROUTE_EDGES:
            options = self._next_edges(edges[-1])
            if not options:
                break
            edges.append(self._rng.choice(options))
        return edges

    def _next_edges(self, edge: str) -> tuple[str, ...]:
        found = self._successors.get(edge)
        if found is None:
            lib = self._lib
            targets: set[str] = set()
            for index in range(lib.edge.getLaneNumber(edge)):
                for link in lib.lane.getLinks(f"{edge}_{index}"):
                    if link[6] != "t":  # no turnarounds
                        targets.add(lib.lane.getEdgeID(link[0]))
            found = tuple(sorted(targets))
            self._successors[edge] = found
        return found


def _along(
    lane: str, shape: list[tuple[float, float]], length: float, max_speed: float
) -> list[LaneSlot]:
    """Insertion points every SLOT_SPACING m along a lane shape (lane positions scaled to the
    shape, whose geometric length may differ slightly from the lane length)."""
    segments = list(itertools.pairwise(shape))
    lengths = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in segments]
    total = sum(lengths)
    if total <= 0.0 or length < 2.0 * SLOT_SPACING:
        return []
    slots: list[LaneSlot] = []
    pos = SLOT_SPACING
    index, start = 0, 0.0
    while pos <= length - SLOT_SPACING:
        along = pos * total / length
        while index < len(segments) - 1 and start + lengths[index] < along:
            start += lengths[index]
            index += 1
        (x0, y0), (x1, y1) = segments[index]
        frac = (along - start) / lengths[index] if lengths[index] > 0 else 0.0
        slots.append(
            LaneSlot(
                lane=lane,
                pos=pos,
                x=x0 + frac * (x1 - x0),
                y=y0 + frac * (y1 - y0),
                heading=math.atan2(y1 - y0, x1 - x0),
                max_speed=max_speed,
            )
        )
        pos += SLOT_SPACING
    return slots
