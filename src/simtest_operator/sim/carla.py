"""CARLA ScenarioRunner's controller conventions, mapped to the stand-in's built-in drivers.

ScenarioRunner names a controller by its Python ``module`` property. The stand-in runs none of
them; it maps each to what it already has:

- ``external_control``: the ego is handed to the system under test. The configured SUT drives
  (the driver model by default, or an external SUT); an ego standing still is given
  :data:`CRUISE_SPEED` as set speed, because such scenarios wait for the ego to move.
- ``npc_vehicle_control``, ``vehicle_longitudinal_control``: lane following at the speed the
  SpeedActions ask for -- what the engine does for every scripted vehicle.
- ``carla_autopilot`` and, under ScenarioRunner's rules, ``ActivateControllerAction`` on a non-ego
  vehicle: CARLA's traffic-manager autopilot, here the driver model (IDM car following, lane
  keeping, AEB) with the SUT defaults at the vehicle's speed, or :data:`CRUISE_SPEED` from rest.

Anything else is an unknown controller, handled as before (listed as not imitated).
"""

from __future__ import annotations

import enum

from simtest_operator.drivermodel import DriverModel, SutConfig
from simtest_operator.openscenario import model, rulesets
from simtest_operator.sim.actors import Actor

CRUISE_SPEED = 30.0 / 3.6
"""m/s: the urban speed limit of the CARLA towns, which their autopilot and agents drive at."""


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


def module_of(controller: model.Controller) -> Module:
    """The mapping of ``controller``'s ``module`` property (OTHER when absent or unknown)."""
    stem = rulesets.module_name(controller)
    return _MODULES.get(stem, Module.OTHER) if stem is not None else Module.OTHER


def autopilot(actor: Actor, *, on: bool) -> None:
    """Switch the built-in autopilot of a non-ego vehicle on or off."""
    if not on:
        actor.driver = None
    elif actor.driver is None:
        driver = DriverModel(SutConfig(), set_speed=actor.speed)
        start_moving(driver)
        actor.driver = driver


def start_moving(driver: DriverModel) -> None:
    """Give a driver that would stand still the towns' cruise speed."""
    if driver.set_speed <= 0.0:
        driver.set_speed = CRUISE_SPEED
