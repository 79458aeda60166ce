"""The simulator backend protocol: the small surface the engine needs from SUMO.

The engine (storyboard, actions, driver model) computes the authoritative motion of every scenario
entity and pushes it to the backend each step; the backend hosts the road network, moves its own
traffic (SUMO car-following for vehicles from a SUMO route file) and reports everyone's state back.
Keeping this to a handful of methods lets unit tests run the whole engine on
:class:`~simtest_operator.sim.memory.MemoryBackend` while production uses
:class:`~simtest_operator.sim.sumo.SumoBackend` (the only module that imports libsumo).

Coordinates are OpenDRIVE world coordinates of the entity's *reference point*; heading in radians
counter-clockwise from +x. Conversions to SUMO's front-bumper/compass conventions stay inside the
SUMO adapter.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Protocol

from simtest_operator.snapshots import EntityKind


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BackendConfig:
    """How to start a backend for one run."""

    net_file: Path | None = None
    """SUMO network; None runs in open space (no road network)."""
    sumo_config: Path | None = None
    """A ``.sumocfg`` whose net and route files provide SUMO-driven background traffic."""
    step_length: float = 0.05
    seed: int = 42
    lateral_resolution: float = 0.1
    """Sublane resolution (m); lets entities keep lateral offsets inside a lane."""
    mirror: bool | None = None
    """Push engine-driven actors into the backend every step: True always, False never, None
    (default) only when the backend drives traffic of its own that must see them. Placing costs
    SUMO a map-matching search per actor and step (0.03-0.5 ms each, more on maps with long
    curved lanes), which buys nothing when no SUMO vehicle reacts to the actors."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ActorSpec:
    """An entity the engine adds to the backend."""

    name: str
    kind: EntityKind
    length: float
    width: float
    front_offset: float
    """Distance from the reference point forward to the front bumper (m)."""

    def placed(self, *, x: float, y: float, heading: float, speed: float) -> ActorState:
        """This actor's state at a pose the engine chose."""
        return ActorState(
            name=self.name,
            x=x,
            y=y,
            heading=heading,
            speed=speed,
            length=self.length,
            width=self.width,
            front_offset=self.front_offset,
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ActorState:
    """An actor's state as the backend reports it (reference point, OpenDRIVE conventions)."""

    name: str
    x: float
    y: float
    heading: float
    speed: float
    length: float
    width: float
    front_offset: float
    external: bool = False
    """True for traffic the backend itself drives (not added by the engine)."""
    category: str = "car"
    """OpenSCENARIO vehicle category (meaningful for external traffic)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneSlot:
    """A point on a lane where traffic can be inserted (sampled from the backend's network)."""

    lane: str
    """Backend lane id (SUMO ``<edge>_<index>``)."""
    pos: float
    """Distance along the lane (m)."""
    x: float
    y: float
    heading: float
    """Driving direction of the lane here (radians, OpenDRIVE convention)."""
    max_speed: float


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficVehicle:
    """A vehicle the engine asks the backend to insert and then drive on its own."""

    name: str
    category: str
    slot: LaneSlot
    speed: float | None
    """Initial and desired speed (m/s); None: the lane's speed limit (with the backend's usual
    spread). The backend inserts at most as fast as is safe behind the vehicle ahead."""


class TrafficHost(Protocol):
    """The part of a backend that drives traffic of its own (SUMO's driver models)."""

    def slots(self) -> Sequence[LaneSlot]:
        """Insertion points along every lane, a few metres apart (computed once per run)."""

    def allows(self, lane: str, category: str) -> bool:
        """Whether vehicles of ``category`` may drive on ``lane``."""

    def spawn(self, vehicle: TrafficVehicle) -> None:
        """Insert ``vehicle`` for the coming step; it appears in :meth:`Backend.states` (as
        external) after the step if the insertion succeeded, and is dropped otherwise."""

    def remove(self, name: str) -> None:
        """Take external vehicle ``name`` out of the world for the coming step."""


class Backend(Protocol):
    """A simulator hosting the road network and background traffic; one run at a time."""

    def start(self, config: BackendConfig) -> None:
        """Load the network (if any) and background traffic; time starts at 0."""

    def add(self, spec: ActorSpec) -> None:
        """Register an engine-driven entity; it appears on its first :meth:`place`."""

    def place(self, name: str, *, x: float, y: float, heading: float, speed: float) -> None:
        """Put an engine-driven entity exactly at this pose with this speed for the next step."""

    def step(self) -> None:
        """Advance the backend by one step length."""

    def states(self) -> Mapping[str, ActorState]:
        """Every actor currently in the world, engine-driven and external."""

    def close(self) -> None:
        """Release the simulator; safe to call twice."""

    def traffic(self) -> TrafficHost | None:
        """The backend's traffic control, or None when it cannot drive traffic itself."""
