"""The libsumo backend: with :mod:`.sumoloading` (which loads it), the only code that uses libsumo.

libsumo runs SUMO inside this process and is a per-process singleton: one simulation per process
at a time. :meth:`SumoBackend.start` refuses to start a second one; the local executor and
``simtest scenario check`` therefore run each scenario in its own worker process.

Conventions translated here and nowhere else:
- SUMO positions a vehicle by its front-bumper centre; the engine speaks about the OpenSCENARIO
  reference point, ``front_offset`` metres behind the bumper along the heading.
- SUMO angle = 90 - degrees(OpenDRIVE heading) (compass degrees, clockwise from north).
- Network coordinates = OpenDRIVE coordinates + the net's ``netOffset`` (zero for nets the cache
  builds with ``--offset.disable-normalization``, non-zero for some hand-made SUMO inputs).

Engine-driven actors get ``speedMode 0`` / ``laneChangeMode 0`` and are placed with
``moveToXY(keepRoute=2)`` (exact, even off the lanes) before each step when mirroring is on
(:attr:`BackendConfig.mirror`). SUMO runs with ``--collision.action none``; the engine detects
collisions from bounding boxes itself.
"""

from __future__ import annotations

import contextlib
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from simtest_operator.errors import SimulationError
from simtest_operator.sim import sumoloading
from simtest_operator.sim.backends import (
    ActorSpec,
    ActorState,
    BackendConfig,
    LaneSlot,
    TrafficHost,
    TrafficVehicle,
)
from simtest_operator.sim.sumotraffic import SumoTraffic, category_of_vclass
from simtest_operator.snapshots import EntityKind

_ROUTE_ID = "simtest_route"
_POSITION, _ANGLE, _SPEED = 0x42, 0x43, 0x40
"""libsumo.constants VAR_POSITION, VAR_ANGLE, VAR_SPEED (stable TraCI protocol numbers)."""
_SUBSCRIBED = (_POSITION, _ANGLE, _SPEED)
_MATCH_THRESHOLD = 3.0
"""Lane search radius (m) of moveToXY: enough to land on the lane an actor drives in, and far
cheaper than SUMO's default 100 m on maps with long, finely shaped lanes."""
_OFFSET_RE = re.compile(rb'netOffset="(-?[0-9.]+),(-?[0-9.]+)"')
_NET_FILE_RE = re.compile(rb'<net-file\s+value="([^"]+)"')


def _load_libsumo() -> ModuleType:
    # Nothing to silence: libsumo prints only when pyarrow's Arrow ABI differs from its own, and
    # pyproject.toml pins the one it was built with (tests/sim/test_arrow_abi.py).
    return sumoloading.bindings()


def preload() -> None:
    """Load libsumo now, so processes forked from this one start with it in memory."""
    _load_libsumo()


def running() -> bool:
    """Whether this process has a SUMO simulation loaded (never loads libsumo to find out)."""
    lib: Any = sumoloading.loaded()
    return lib is not None and bool(lib.simulation.isLoaded())


def sumo_angle(heading: float) -> float:
    """SUMO compass angle (degrees) for an OpenDRIVE heading (radians)."""
    return (90.0 - math.degrees(heading)) % 360.0


def odr_heading(angle: float) -> float:
    """OpenDRIVE heading (radians, in [-pi, pi)) for a SUMO compass angle (degrees)."""
    return (math.radians(90.0 - angle) + math.pi) % (2.0 * math.pi) - math.pi


def read_net_offset(net_file: Path) -> tuple[float, float]:
    """The ``netOffset`` of a SUMO network (it sits in the first few kB of the file)."""
    with net_file.open("rb") as handle:
        head = handle.read(16384)
    match = _OFFSET_RE.search(head)
    return (float(match.group(1)), float(match.group(2))) if match else (0.0, 0.0)


def _config_net(sumo_config: Path) -> Path | None:
    match = _NET_FILE_RE.search(sumo_config.read_bytes())
    return (sumo_config.parent / match.group(1).decode()) if match else None


class SumoBackend:
    """Backend protocol on libsumo."""

    __slots__ = (
        "_added",
        "_external",
        "_lib",
        "_mirror",
        "_mirror_setting",
        "_offset",
        "_placed",
        "_specs",
        "_speeds",
        "_started",
        "_traffic",
    )

    def __init__(self) -> None:
        self._lib: Any = None
        self._specs: dict[str, ActorSpec] = {}
        self._placed: dict[str, ActorState] = {}
        self._speeds: dict[str, float] = {}
        self._external: dict[str, tuple[float, float, str]] = {}
        """External vehicles: name -> (length, width, category)."""
        self._traffic: SumoTraffic | None = None
        self._mirror_setting: bool | None = None
        self._offset = (0.0, 0.0)
        self._started = False
        self._mirror = False
        self._added: set[str] = set()

    def start(self, config: BackendConfig) -> None:
        lib = _load_libsumo()
        if lib.simulation.isLoaded():
            raise SimulationError(
                "libsumo already runs a simulation in this process; run one scenario per process"
            )
        args = ["sumo"]
        net = config.net_file
        if config.sumo_config is not None:
            args += ["-c", str(config.sumo_config)]
            net = _config_net(config.sumo_config) or net
        elif net is not None:
            args += ["-n", str(net)]
        else:
            raise SimulationError("the SUMO backend needs a road network; use open space instead")
        args += [
            "--step-length",
            f"{config.step_length:g}",
            "--seed",
            str(config.seed),
            "--lateral-resolution",
            f"{config.lateral_resolution:g}",
            "--collision.action",
            "none",
            "--time-to-teleport",
            "-1",
            "--begin",
            "0",
            "--no-step-log",
            "true",
            "--no-warnings",
            "true",
            "--duration-log.disable",
            "true",
        ]
        try:
            lib.simulation.start(args)
            edges = [e for e in lib.edge.getIDList() if not e.startswith(":")]
            if not edges:
                raise SimulationError(f"SUMO network {net} has no edges")
            lib.route.add(_ROUTE_ID, [edges[0]])
        except lib.TraCIException as exc:
            self._close_quietly(lib)
            raise SimulationError(f"SUMO failed to start: {exc}") from exc
        self._lib = lib
        self._offset = read_net_offset(net) if net is not None else (0.0, 0.0)
        self._mirror_setting = config.mirror
        self._mirror = (
            config.mirror if config.mirror is not None else config.sumo_config is not None
        )
        self._traffic = SumoTraffic(lib, offset=self._offset, seed=config.seed)
        self._started = True

    def add(self, spec: ActorSpec) -> None:
        self._require()
        self._specs[spec.name] = spec

    def _insert(self, spec: ActorSpec) -> None:
        lib = self._lib
        type_id = f"simtest_{spec.name}"
        try:
            lib.vehicletype.copy("DEFAULT_VEHTYPE", type_id)
            lib.vehicletype.setLength(type_id, max(spec.length, 0.1))
            lib.vehicletype.setWidth(type_id, max(spec.width, 0.1))
            lib.vehicletype.setMinGap(type_id, 0.0)
            vclass = "passenger" if spec.kind is EntityKind.VEHICLE else "ignoring"
            lib.vehicletype.setVehicleClass(type_id, vclass)
            lib.vehicle.add(spec.name, _ROUTE_ID, typeID=type_id, departSpeed="0")
            lib.vehicle.setSpeedMode(spec.name, 0)
            lib.vehicle.setLaneChangeMode(spec.name, 0)
        except lib.TraCIException as exc:
            raise SimulationError(f"SUMO refused actor {spec.name!r}: {exc}") from exc
        self._added.add(spec.name)

    def place(self, name: str, *, x: float, y: float, heading: float, speed: float) -> None:
        self._require()
        spec = self._specs[name]
        self._placed[name] = spec.placed(x=x, y=y, heading=heading, speed=speed)

    def _push(self) -> None:
        """Mirror the engine-driven actors' poses into SUMO for the coming step."""
        lib = self._lib
        offset_x, offset_y = self._offset
        for name, state in self._placed.items():
            if name not in self._added:
                self._insert(self._specs[name])
            cos_h, sin_h = math.cos(state.heading), math.sin(state.heading)
            front_x = state.x + state.front_offset * cos_h + offset_x
            front_y = state.y + state.front_offset * sin_h + offset_y
            try:
                lib.vehicle.moveToXY(
                    name,
                    "",
                    -1,
                    front_x,
                    front_y,
                    sumo_angle(state.heading),
                    keepRoute=2,
                    matchThreshold=_MATCH_THRESHOLD,
                )
                if self._speeds.get(name) != state.speed:
                    lib.vehicle.setSpeed(name, max(state.speed, 0.0))
                    self._speeds[name] = state.speed
            except lib.TraCIException as exc:
                raise SimulationError(f"SUMO could not place {name!r}: {exc}") from exc

    def step(self) -> None:
        lib = self._require()
        if self._mirror:
            self._push()
        try:
            if self._traffic is not None:
                self._traffic.flush()
            lib.simulation.step()
            departed = lib.simulation.getDepartedIDList()
            spawned = self._traffic.settle(departed) if self._traffic is not None else {}
            for vid in departed:
                if vid not in self._added:
                    lib.vehicle.subscribe(vid, _SUBSCRIBED)
                    category = spawned.get(vid) or category_of_vclass(
                        lib.vehicle.getVehicleClass(vid)
                    )
                    self._external[vid] = (
                        lib.vehicle.getLength(vid),
                        lib.vehicle.getWidth(vid),
                        category,
                    )
            for vid in lib.simulation.getArrivedIDList():
                self._external.pop(vid, None)
        except lib.TraCIException as exc:
            raise SimulationError(f"SUMO step failed: {exc}") from exc

    def states(self) -> Mapping[str, ActorState]:
        """Engine-driven actors as placed (SUMO moves them exactly there) plus SUMO traffic."""
        result = dict(self._placed)
        if not self._external:
            return result
        lib = self._require()
        for vid, values in lib.vehicle.getAllSubscriptionResults().items():
            dims = self._external.get(vid)
            if dims is None:
                continue
            length, width, category = dims
            heading = odr_heading(values[_ANGLE])
            front_x, front_y = values[_POSITION]
            half = length / 2.0
            result[vid] = ActorState(
                name=vid,
                x=front_x - self._offset[0] - half * math.cos(heading),
                y=front_y - self._offset[1] - half * math.sin(heading),
                heading=heading,
                speed=values[_SPEED],
                length=length,
                width=width,
                front_offset=half,
                external=True,
                category=category,
            )
        return result

    def close(self) -> None:
        if self._started and self._lib is not None:
            self._close_quietly(self._lib)
        self._started = False
        self._traffic = None
        self._specs.clear()
        self._added.clear()
        self._placed.clear()
        self._external.clear()
        self._speeds.clear()

    # --- traffic (TrafficHost) -----------------------------------------------------------------

    def traffic(self) -> TrafficHost | None:
        """This backend: SUMO drives traffic on the network (usable once started)."""
        return self

    def slots(self) -> Sequence[LaneSlot]:
        return self._require_traffic().slots()

    def allows(self, lane: str, category: str) -> bool:
        return self._require_traffic().allows(lane, category)

    def spawn(self, vehicle: TrafficVehicle) -> None:
        self._require_traffic().spawn(vehicle)
        # SUMO traffic must see the scenario entities to react to them.
        if self._mirror_setting is None:
            self._mirror = True

    def remove(self, name: str) -> None:
        self._require_traffic().remove(name)
        self._external.pop(name, None)

    def _require_traffic(self) -> SumoTraffic:
        self._require()
        assert self._traffic is not None
        return self._traffic

    def _require(self) -> Any:
        if not self._started:
            raise SimulationError("SUMO backend used before start or after close")
        return self._lib

    @staticmethod
    def _close_quietly(lib: Any) -> None:
        with contextlib.suppress(Exception):
            lib.simulation.close()
