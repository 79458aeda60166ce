"""Opening a simulation: load the scenario and its road network, pick and configure a backend.

Scenarios with a road network run on SUMO (:class:`~simtest_operator.sim.sumo.SumoBackend`, the
network converted once and cached by :mod:`~simtest_operator.sim.netcache`); scenarios without one
run in open space on :class:`~simtest_operator.sim.memory.MemoryBackend`. An entity whose
controller is esmini's SUMO controller brings a ``.sumocfg``; SUMO then also loads that file's
routes and its vehicles join the run as background traffic. A map netconvert cannot convert
runs on the in-memory backend unless the scenario brings traffic (SUMO does nothing else).

libsumo is one simulation per process: run one session at a time per process.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from pathlib import Path

from simtest_operator.drivermodel import SutConfig
from simtest_operator.errors import SimulationError
from simtest_operator.opendrive import RoadNetwork
from simtest_operator.openscenario import LoadOptions, load_scenario, model
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import netcache
from simtest_operator.sim.backends import Backend, BackendConfig
from simtest_operator.sim.engine import Simulation
from simtest_operator.sim.memory import MemoryBackend
from simtest_operator.sim.sumo import SumoBackend


class BackendChoice(enum.StrEnum):
    """Which backend runs scenarios that have a road network."""

    SUMO = "sumo"
    MEMORY = "memory"
    """Pure Python (tests, and runs that need no SUMO traffic)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Opened:
    """A ready-to-start simulation and what it took to get there."""

    simulation: Simulation
    scenario: model.Scenario
    net_file: Path | None
    net_from_cache: bool
    net_seconds: float


def sumo_config_of(scenario: model.Scenario) -> Path | None:
    """The ``.sumocfg`` of an esmini SumoController in the scenario, if any."""
    for obj in scenario.entities:
        controller = obj.controller
        if not isinstance(controller, model.Controller):
            continue
        if controller.property("esminiController") != "SumoController" or not controller.files:
            continue
        config = (scenario.path.parent / controller.files[0]).resolve()
        if config.is_file():
            return config
    return None


def brings_traffic(scenario: model.Scenario) -> bool:
    """Whether the scenario has SUMO drive traffic: an esmini SumoController's ``.sumocfg``,
    or a TrafficAction (swarm, source, sink) anywhere in its storyboard."""
    if sumo_config_of(scenario) is not None:
        return True
    storyboard = scenario.storyboard
    bodies: list[model.AnyAction] = [*storyboard.init.global_actions]
    for story in storyboard.stories:
        for act in story.acts:
            for group in act.maneuver_groups:
                for maneuver in group.maneuvers:
                    for event in maneuver.events:
                        bodies.extend(action.body for action in event.actions)
    traffic = (model.TrafficSwarmAction, model.TrafficSourceAction, model.TrafficSinkAction)
    return any(isinstance(body, traffic) for body in bodies)


def open_simulation(
    path: Path,
    *,
    sut: SutConfig,
    settings: SimulationSettings,
    nets_dir: Path,
    overrides: Mapping[str, str] | None = None,
    backend: BackendChoice = BackendChoice.SUMO,
    loading: LoadOptions | None = None,
) -> Opened:
    """Load ``path`` (with ``loading`` options) and prepare its simulation (ScenarioError on bad
    input)."""
    scenario = load_scenario(path, overrides=overrides, options=loading or LoadOptions())
    logic_file = scenario.road_network.logic_file
    roads = RoadNetwork.from_file(logic_file) if logic_file is not None else None
    net_file: Path | None = None
    from_cache, seconds = False, 0.0
    chosen: Backend
    config = BackendConfig(step_length=settings.step_length, seed=settings.seed)
    converted = None
    if logic_file is not None and backend is BackendChoice.SUMO:
        try:
            converted = netcache.ensure_net(logic_file, cache_dir=nets_dir)
        except SimulationError:
            # SUMO only drives background traffic (the engine owns every scenario entity): a
            # map netconvert cannot convert fails only the runs that bring traffic.
            if brings_traffic(scenario):
                raise
    if converted is not None:
        net_file, from_cache, seconds = converted.path, converted.from_cache, converted.seconds
        config = dataclasses.replace(
            config, net_file=net_file, sumo_config=sumo_config_of(scenario)
        )
        chosen = SumoBackend()
    else:
        chosen = MemoryBackend()
    simulation = Simulation(scenario, roads=roads, backend=chosen, backend_config=config, sut=sut)
    return Opened(
        simulation=simulation,
        scenario=scenario,
        net_file=net_file,
        net_from_cache=from_cache,
        net_seconds=seconds,
    )
