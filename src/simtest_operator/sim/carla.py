"""CARLA ScenarioRunner's controller conventions, mapped to the stand-in's built-in drivers.

ScenarioRunner names a controller by its Python ``module`` property. The stand-in runs none of
them; it maps each to what it already has:

- ``external_control``: the ego is handed to the system under test. The configured SUT drives
  (the driver model by default, or an external SUT); an ego standing still is given
  :data:`CRUISE_SPEED` as set speed, because such scenarios wait for the ego to move.
- ``npc_vehicle_control``, ``vehicle_longitudinal_control``: lane following at the speed the
  SpeedActions ask for -- what the engine does for every scripted vehicle.
- ``carla_autopilot`` and, under ScenarioRunner's rules, ``ActivateControllerAction``
  (ScenarioRunner's ``ChangeAutoPilot``, on the hero too): CARLA's traffic-manager autopilot,
  here the driver model (IDM car following, lane keeping, AEB; the SUT's configuration on the
  hero, the defaults on other vehicles) at the road's OpenDRIVE speed limit,
  :data:`CRUISE_SPEED` where the map sets none. Like CARLA's autopilot it takes no SpeedActions
  (listed as ignored).

Walkers are CARLA's: 0.5 m across whatever the file's BoundingBox says, and a walker given a
speed walks where it faces (off the lane, across the road), as ScenarioRunner's
``PedestrianControl`` steers it, instead of following its lane.

Anything else is an unknown controller, handled as before (listed as not imitated).
"""

from __future__ import annotations

import enum
from collections.abc import Iterable

from simtest_operator.drivermodel import DriverModel, SutConfig
from simtest_operator.openscenario import model, rulesets
from simtest_operator.openscenario.readers.entities import CARLA_SIZES
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World
from simtest_operator.snapshots import BoundingBox, EntityKind

CRUISE_SPEED = 30.0 / 3.6
"""m/s: the urban speed limit of the CARLA towns, which their autopilot and agents drive at."""


_LENGTH, _WIDTH, _HEIGHT = CARLA_SIZES[EntityKind.PEDESTRIAN]
WALKER_BOX = BoundingBox(center_z=_HEIGHT / 2, length=_LENGTH, width=_WIDTH, height=_HEIGHT)
"""CARLA's walker blueprints: a capsule about 0.5 m across and 1.8 m tall round the actor's
location. ScenarioRunner spawns the blueprint; a Pedestrian's BoundingBox in the file is not
its size in CARLA."""


class Module(enum.Enum):
    """What a ScenarioRunner controller module maps to."""

    EXTERNAL = "external_control"
    NPC = "npc"
    AUTOPILOT = "autopilot"
    OTHER = "other"


_MODULES = {
    "external_control": Module.EXTERNAL,
    "npc_vehicle_control": Module.NPC,
    "vehicle_longitudinal_control": Module.NPC,
    "carla_autopilot": Module.AUTOPILOT,
}


def spawn_walkers(actors: Iterable[Actor]) -> None:
    """Give the pedestrians of a ScenarioRunner file the size CARLA's walkers have."""
    for actor in actors:
        if actor.kind is EntityKind.PEDESTRIAN:
            actor.box = WALKER_BOX


def is_walker(actor: Actor) -> bool:
    """Whether ``actor`` is one of CARLA's walkers: given a speed it walks where it faces
    (ScenarioRunner's ``PedestrianControl``), not along a lane."""
    return actor.kind is EntityKind.PEDESTRIAN


def module_of(controller: model.Controller) -> Module:
    """The mapping of ``controller``'s ``module`` property (OTHER when absent or unknown)."""
    stem = rulesets.module_name(controller)
    return _MODULES.get(stem, Module.OTHER) if stem is not None else Module.OTHER


def autopilot(world: World, actor: Actor, *, on: bool) -> None:
    """Switch the built-in autopilot of a non-ego vehicle on or off."""
    if not on:
        actor.driver = None
    elif actor.driver is None:
        driver = DriverModel(SutConfig(), set_speed=actor.speed)
        engage_autopilot(world, actor, driver)
        actor.driver = driver


def engage_autopilot(world: World, actor: Actor, driver: DriverModel) -> None:
    """Make ``driver`` CARLA's autopilot: it drives at the road's speed limit (the towns' cruise
    speed where the map sets none) and takes no speed requests from the scenario."""
    driver.follows_limits = True
    driver.set_speed = speed_limit(world, actor) or CRUISE_SPEED


def keep_to_limit(world: World, actor: Actor, driver: DriverModel) -> None:
    """An autopilot's set speed where ``actor`` is now (kept on a road without a limit, such as
    the connecting roads of CARLA's junctions)."""
    limit = speed_limit(world, actor)
    if limit is not None:
        driver.set_speed = limit


def speed_limit(world: World, actor: Actor) -> float | None:
    """The OpenDRIVE speed limit (m/s) of the road ``actor`` follows, if the map sets one."""
    if world.roads is None or actor.mode is not Mode.ROAD or actor.road_id is None:
        return None
    return world.roads.road(actor.road_id).speed_limit(actor.s)


def start_moving(driver: DriverModel) -> None:
    """Give a driver that would stand still the towns' cruise speed."""
    if driver.set_speed <= 0.0:
        driver.set_speed = CRUISE_SPEED
