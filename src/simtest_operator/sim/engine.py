"""The engine: one scenario run, step by step, on a backend.

Split of work (see docs/simulator.md): the engine owns the authoritative kinematics of every
scenario entity (storyboard actions, lane following on the OpenDRIVE geometry, the SUT driver
model for the ego) because that is what makes reference-player behaviour reachable; the backend
(SUMO via libsumo) hosts the network, receives every entity's pose each step with
``moveToXY(keepRoute=2)`` and drives its own background traffic, which comes back as extra
entities in the snapshots.

Each :meth:`Simulation.step`: storyboard triggers are evaluated on the world at time t, actions
and the driver model update speeds and lateral offsets reading every other entity as it was at
t (whichever moved first), motion advances poses to t + dt,
completions propagate through the storyboard, the backend is synchronised, and a
:class:`~simtest_operator.snapshots.WorldSnapshot` at t + dt comes out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from simtest_operator.drivermodel import DriverModel, SutConfig, Takeover, signal_horizon
from simtest_operator.errors import ScenarioError
from simtest_operator.geometry import unexplained_displacement
from simtest_operator.opendrive import RoadNetwork
from simtest_operator.openscenario import model, rulesets
from simtest_operator.sim import (
    carla,
    carla_init,
    esmini_acc,
    esmini_alks,
    esmini_controllers,
    esmini_ghost,
    motion,
    perception,
    trailers,
)
from simtest_operator.sim.actors import Actor, Domain, Mode
from simtest_operator.sim.backends import ActorSpec, Backend, BackendConfig
from simtest_operator.sim.condition_checks import Conditions
from simtest_operator.sim.dispatch import Dispatcher
from simtest_operator.sim.runs import Run
from simtest_operator.sim.storyboard import Storyboard
from simtest_operator.sim.sut import Pilot, PilotView
from simtest_operator.sim.traffic import Traffic
from simtest_operator.sim.trajectories import PathRun
from simtest_operator.sim.world import World
from simtest_operator.snapshots import (
    BoundingBox,
    Discontinuity,
    EntityKind,
    EntityState,
    JumpCause,
    WorldSnapshot,
)

EGO_NAMES = ("Ego", "ego", "hero", "Hero", "EGO")


def pick_ego(
    scenario: model.Scenario, configured: str | None, *, scenario_runner: bool = False
) -> str | None:
    """The ego entity: configured name, else (under ScenarioRunner's rules) the first vehicle
    with the property ``type`` = ``ego_vehicle``, which is what makes a vehicle an ego vehicle
    for ScenarioRunner (``OpenScenarioConfiguration._extract_vehicle_information``: its
    criteria judge that vehicle whatever its name), else a conventional name, else the first
    vehicle."""
    names = [obj.name for obj in scenario.entities]
    if configured is not None:
        if configured not in names:
            raise ScenarioError(f"ego entity {configured!r} is not in the scenario")
        return configured
    if scenario_runner:
        for obj in scenario.entities:
            if obj.kind is EntityKind.VEHICLE and obj.property("type") == "ego_vehicle":
                return obj.name
    for name in EGO_NAMES:
        if name in names:
            return name
    vehicles = [obj.name for obj in scenario.entities if obj.kind is EntityKind.VEHICLE]
    return vehicles[0] if vehicles else None


class Simulation:
    """One run of one scenario; create, :meth:`start`, :meth:`step` until done, :meth:`close`."""

    __slots__ = (
        "_backend",
        "_backend_config",
        "_conditions",
        "_dispatcher",
        "_external_ids",
        "_ghosts",
        "_init_runs",
        "_pilot",
        "_scenario",
        "_snapshot",
        "_steps",
        "_storyboard",
        "_sut",
        "_sut_engaged",
        "_traffic",
        "ego",
        "rules",
        "world",
    )

    def __init__(
        self,
        scenario: model.Scenario,
        *,
        roads: RoadNetwork | None,
        backend: Backend,
        backend_config: BackendConfig,
        sut: SutConfig,
    ) -> None:
        self._pilot: Pilot | None = None
        self._backend = backend
        self._backend_config = backend_config
        self._sut = sut
        self.rules = rulesets.rules_of(scenario)
        """The reference player whose rules this run follows (docs/simulator.md, "Rule sets")."""
        self._ghosts: dict[str, esmini_ghost.Ghost] = {}
        if not self.rules.scenario_runner:
            # esmini's ghosts (on the ego only when the SUT never takes it over)
            ego = pick_ego(scenario, sut.ego)
            sut_ego = sut.takeover is not Takeover.NEVER and ego is not None
            skip = frozenset({ego} if sut_ego and ego is not None else ())
            scenario, self._ghosts = esmini_ghost.setup(scenario, skip=skip)
        self._scenario = scenario
        actors = [Actor(obj, index) for index, obj in enumerate(scenario.entities)]
        self.world = World(
            roads=roads,
            actors=actors,
            dt=backend_config.step_length,
            seed=backend_config.seed,
            parameters={p.name: p.value for p in scenario.parameters},
            variables={v.name: v.value for v in scenario.variables},
            controllers=scenario.road_network.controllers,
        )
        self.world.monitors.update((m.name, m.value) for m in scenario.monitors)
        self.world.ghosts = frozenset(ghost.name for ghost in self._ghosts.values())
        self._traffic = Traffic(seed=backend_config.seed)
        header = scenario.header
        self.ego = pick_ego(scenario, sut.ego, scenario_runner=self.rules.scenario_runner)
        scenario_runner = self.rules.scenario_runner
        self._dispatcher = Dispatcher(
            self.world,
            ego=self.ego,
            switch=self._switch_driver,
            traffic=self._traffic,
            host=backend.traffic(),
            scenario_runner=scenario_runner,
            ghosts=self._ghosts,
        )
        if scenario_runner:
            carla.spawn_walkers(actors)
        self._conditions = Conditions(
            self.world,
            self._state_query,
            signed_longitudinal=(header.rev_major, header.rev_minor) == (1, 0)
            and not scenario_runner,
            scenario_runner=scenario_runner,
        )
        self._storyboard = Storyboard(
            scenario.storyboard,
            raw=self._conditions,
            start_action=self._dispatcher.start,
            scenario_runner=scenario_runner,
        )
        self._steps = 0
        self._init_runs: list[Run] = []
        """The Init actions' runs in declaration order: the reference player steps actions in
        storyboard order (Init first, as declared, then the stories), so a trajectory declared
        before the longitudinal action driving its speed moves the entity before that action
        changes the speed in the same step."""
        self._external_ids: dict[str, int] = {}
        self._sut_engaged = False
        self._snapshot = WorldSnapshot(time=0.0, entities=())

    # --- public -------------------------------------------------------------------------------

    @property
    def time(self) -> float:
        return self.world.time

    @property
    def complete(self) -> bool:
        """The storyboard has completed (stop trigger fired, or all stories ended)."""
        return self._storyboard.complete

    @property
    def ignored(self) -> tuple[str, ...]:
        """Elements accepted but not simulated, from the file and met during the run."""
        return tuple(dict.fromkeys((*self._scenario.ignored_kinds, *self.world.ignored)))

    @property
    def monitors(self) -> Mapping[str, bool]:
        """The 1.3 monitors' values now (at the end: whether each passed)."""
        return dict(self.world.monitors)

    @property
    def intended_differences(self) -> tuple[str, ...]:
        """Ways this run deliberately differs from a reference player (for comparisons)."""
        labels = []
        if self._sut_engaged:
            labels.append(f"{self.ego} driven by the SUT model")
        imitates = not self.rules.scenario_runner
        for obj in self._scenario.entities:
            replaced = obj.name == self.ego and self._sut_engaged
            declared: list[object] = [e.controller for e in obj.object_controllers]
            declared = declared or [obj.controller]
            for controller in declared:
                if not isinstance(controller, model.Controller) or replaced:
                    continue
                if imitates and esmini_controllers.kind_of(controller) is not None:
                    continue
                if imitates and esmini_acc.is_acc(controller):
                    continue
                if imitates and esmini_alks.imitated(controller):
                    continue
                if self._dispatcher.imitates(obj.name, controller.name):
                    continue
                label = f"controller {controller.name} of {obj.name} not imitated"
                if label not in labels:
                    labels.append(label)
        for entity, name in self._dispatcher.assigned:
            label = f"controller {name} of {entity} not imitated"
            replaced = entity == self.ego and self._sut_engaged
            if not replaced and not self._dispatcher.imitates(entity, name) and label not in labels:
                labels.append(label)
        if self._backend_config.sumo_config is not None:
            labels.append("SUMO background traffic")
        return tuple(labels)

    @property
    def environments(self) -> tuple[tuple[float, model.Environment], ...]:
        """Environments the scenario set (time, environment): recorded, not rendered."""
        return tuple(self.world.environments)

    @property
    def discontinuities(self) -> tuple[Discontinuity, ...]:
        """Jumps the scenario commanded (teleports, trajectory starts, ...), for the recording."""
        return tuple(self.world.discontinuities)

    def off_road(self, state: EntityState) -> bool:
        """Whether an entity is off the drivable road (for the online evaluation)."""
        actor = self.world.actors.get(state.name)
        if actor is None or self.world.roads is None:
            return False
        return actor.offroad_time > 0.0

    def coupled(self, first: str, second: str) -> bool:
        """Whether two entities may overlap without colliding: hitched together (a trailer's box
        may overlap its tow vehicle's), or one is an esmini ghost (a phantom)."""
        ghosts = self.world.ghosts
        return first in ghosts or second in ghosts or self.world.hitches.coupled(first, second)

    def start(self) -> WorldSnapshot:
        """Run the Init actions, start the backend and return the snapshot at t = 0."""
        world = self.world
        world.signal_controllers.update(world.time)
        init = self._scenario.storyboard.init
        if self.rules.scenario_runner:
            init, unread = carla_init.scenario_runner_init(init)
            world.ignored.extend(u for u in unread if u not in world.ignored)
        for entity, body in init_order(init):
            self._init_runs.append(self._dispatcher.start_private(world.actor(entity), body))
        for global_action in init.global_actions:
            self._dispatcher.start_global(global_action)
        self._initial_takeover()
        for name, override in self._dispatcher.overrides.items():
            # the Init's SpeedActions after the activation do not reach the controller's speed
            actor = world.actor(name)
            if override.longitudinal and actor.driver is None:
                actor.speed = override.speed
        self._pull_trailers(0.0)
        for actor in world.actors.values():
            actor.measure_motion((actor.x, actor.y, actor.heading), 0.0, teleported=True)
        self._head_start()
        self._backend.start(self._backend_config)
        for actor in world.actors.values():
            self._backend.add(
                ActorSpec(
                    name=actor.name,
                    kind=actor.kind,
                    length=actor.box.length,
                    width=actor.box.width,
                    front_offset=actor.front_offset,
                )
            )
        world.refresh()
        return self._sync()

    def step(self) -> WorldSnapshot:
        """Advance by one step; raises ScenarioError (incl. unsupported elements) on bad input."""
        world = self.world
        dt = world.dt
        world.refresh()
        # Triggers see the world as it is (time and poses of the previous step); then actions and
        # motion take it one step further.
        self._dispatcher.teleported.clear()
        self._storyboard.update(world.time)
        # Every action measures the others at time t, whichever of them moved first this step
        # (the reference player moves entities only after all actions stepped).
        world.freeze()
        self._dispatcher.drive_controllers()
        for actor in world.actors.values():
            if actor.placed and not world.hitches.towed(actor.name):
                self._advance(actor, dt)
        self._pull_trailers(dt)
        world.refresh()
        for run in self._dispatcher.active():
            run.after_motion(world)
        self._steps += 1
        world.time = round(self._steps * dt, 9)
        self._record_ghosts()
        self._restart_ghosts()
        world.signal_controllers.update(world.time)
        world.refresh()
        self._storyboard.settle(world.time)
        world.refresh()
        return self._sync()

    def attach_pilot(self, pilot: Pilot) -> None:
        """Let an external SUT decide the ego's steps instead of the in-process driver model
        (before :meth:`start`; the takeover policy still decides when it drives)."""
        self._pilot = pilot

    def close(self) -> None:
        self._backend.close()

    # --- internals ----------------------------------------------------------------------------

    def _state_query(
        self, kind: model.StoryboardElementType, name: str, state: model.StoryboardElementState
    ) -> bool:
        if not self._storyboard.known(kind, name):
            raise ScenarioError(
                f"storyboard element {kind} {name!r} does not exist",
                element="StoryboardElementStateCondition",
            )
        return self._storyboard.is_in(kind, name, state)

    def _initial_takeover(self) -> None:
        if self.ego is None:
            return
        ego = self.world.actor(self.ego)
        takeover = self._sut.takeover
        has_controller = isinstance(ego.obj.controller, model.Controller)
        if takeover is Takeover.AFTER_INIT or (
            takeover is Takeover.ON_CONTROLLER and has_controller
        ):
            self._switch_driver(ego, True)
        controller = ego.obj.controller
        external = isinstance(controller, model.Controller) and (
            carla.module_of(controller) is carla.Module.EXTERNAL
        )
        if external and ego.driver is not None:
            carla.start_moving(ego.driver)
        autopilot = isinstance(controller, model.Controller) and (
            carla.module_of(controller) is carla.Module.AUTOPILOT
        )
        if autopilot and ego.driver is not None:
            carla.engage_autopilot(self.world, ego, ego.driver)

    def _switch_driver(self, actor: Actor, engage: bool) -> None:
        if self._sut.takeover is Takeover.NEVER or actor.name != self.ego:
            return
        if not engage:
            actor.driver = None
        elif actor.driver is None:
            actor.driver = DriverModel(self._sut, set_speed=actor.speed)
            self._sut_engaged = True

    def _pull_trailers(self, dt: float) -> None:
        """Trailers follow their tow vehicles' new poses (after every tow vehicle moved)."""
        world = self.world
        before = {
            name: (a.x, a.y, a.heading)
            for name, a in world.actors.items()
            if world.hitches.towed(name)
        }
        for trailer in trailers.pull(world.actors, world.hitches):
            world.attach(trailer)
            motion.update_timers(world, trailer, dt, was_stuck=False)
            trailer.measure_motion(before[trailer.name], dt, teleported=False)

    def _advance(self, actor: Actor, dt: float) -> None:
        world = self.world
        speed_before = actor.speed
        before = (actor.road_id, actor.lane_id, actor.offset)
        start = (actor.x, actor.y, actor.heading)
        runs = self._dispatcher.runs(actor)
        longitudinal = runs.get(Domain.LONGITUDINAL)
        lateral = runs.get(Domain.LATERAL)
        driver = actor.driver
        if driver is not None and driver.follows_limits:
            carla.keep_to_limit(world, actor, driver)
        path_first = (
            isinstance(lateral, PathRun)
            and longitudinal is not None
            and lateral is not longitudinal
            and self._init_index(lateral) < self._init_index(longitudinal)
        )
        if path_first:
            assert lateral is not None
            lateral.step(world, dt)
        if longitudinal is not None:
            longitudinal.step(world, dt)
        elif driver is not None and self._pilot is not None and actor.name == self.ego:
            view = PilotView(
                snapshot=self._snapshot, ego_id=actor.id, set_speed=driver.set_speed, dt=dt
            )
            order = self._pilot.drive(view)
            actor.speed = max(order.speed, 0.0)
            if lateral is None and actor.mode is Mode.ROAD:
                actor.offset += order.lateral
        elif driver is not None:
            ahead = perception.leader(world, actor, self._sut.sensor_range)
            lines = (
                perception.signals_ahead(world, actor, signal_horizon(actor.speed, driver.config))
                if driver.config.traffic_signals
                else ()
            )
            command = driver.command(speed=actor.speed, leader=ahead, signals=lines, dt=dt)
            actor.speed = max(actor.speed + command.acceleration * dt, 0.0)
        if lateral is not None and lateral is not longitudinal and not path_first:
            lateral.step(world, dt)
        elif (
            lateral is None
            and driver is not None
            and self._pilot is None
            and actor.mode is Mode.ROAD
        ):
            # lane keeping of the in-process model (an external SUT steers through its order):
            # the lateral motion is part of the distance driven, at a heading it can steer
            heading = driver.steer(
                offset=actor.offset,
                heading=motion.relative_heading(actor, speed_before),
                speed=actor.speed,
                dt=dt,
                steering=actor.steering,
            )
            actor.offset += actor.speed * math.sin(heading) * dt
            actor.lane_changing = True
        # A trajectory placed the actor for the end of this step (also when it just ended and
        # the actor rejoined its lane): it must not move a second time.
        # An actor teleported by an action started this step stays where it was put until the
        # next step (esmini's default motion skips an entity an action positioned).
        placed = (
            actor.mode is Mode.PATH
            or (isinstance(lateral, PathRun) and lateral.finished and not lateral.stopped)
            or actor.name in self._dispatcher.teleported
        )
        if actor.mode is Mode.PATH and Domain.LATERAL not in self._dispatcher.runs(actor):
            world.attach(actor)
        acc = self._dispatcher.accs.get(actor.name)
        if acc is not None and acc.active and driver is None:
            acc.step(world, actor, dt)  # esmini's ACC sets the speed the lane motion drives at
        alks = self._dispatcher.alks.get(actor.name)
        if alks is not None and alks.active and driver is None:
            alks.step(world, actor, dt)
        override = self._dispatcher.overrides.get(actor.name)
        if override is not None and driver is None:
            # an imitated esmini controller overrides the storyboard in its domains
            esmini_controllers.drive_speed(world, actor, override)
            if esmini_controllers.steer(world, actor, override, dt):
                placed = True
        follower = self._dispatcher.followers.get(actor.name)
        if follower is not None and driver is None and follower.drive(world, actor, dt):
            placed = True  # an esmini ghost-following controller overrides the storyboard
        motion.move(world, actor, dt, before=before, start=start[:2], placed=placed)
        actor.acceleration = (actor.speed - speed_before) / dt if dt > 0 else 0.0
        actor.measure_motion(start, dt, teleported=actor.name in self._dispatcher.teleported)

    def _head_start(self) -> None:
        """esmini's negative time before 0 (the longest ghost head start): the storyboard runs
        and only the ghosts move, each from its own head start on, leaving their trails."""
        if self._ghosts:
            lead = max(ghost.headstart for ghost in self._ghosts.values())
            self._ghosts_alone(list(self._ghosts.values()), lead)

    def _restart_ghosts(self) -> None:
        """Ghosts restarted this step replay their head start from the entity (esmini sets its
        clock back by it; everything else waits), and the events that teleported them may fire
        again."""
        restarted = []
        for entity, follower in self._dispatcher.followers.items():
            if follower.restarting:
                follower.replay()
                restarted.append(self._ghosts[entity])
        if not restarted:
            return
        for ghost in restarted:
            self._storyboard.rearm(ghost.rearm)
        now = self.world.time
        self._ghosts_alone(restarted, max(ghost.headstart for ghost in restarted))
        self.world.time = now

    def _ghosts_alone(self, ghosts: list[esmini_ghost.Ghost], lead: float) -> None:
        """Run the storyboard from ``lead`` seconds before now to now moving only ``ghosts``
        (each from its own head start on), recording their trails."""
        world = self.world
        dt = world.dt
        now = world.time
        steps = round(lead / dt)
        world.time = round(now - steps * dt, 9)
        self._record_ghosts()
        for step in range(steps):
            world.refresh()
            self._dispatcher.teleported.clear()
            self._storyboard.update(world.time)
            world.freeze()
            for ghost in ghosts:
                actor = world.actors[ghost.name]
                if actor.placed and world.time >= now - ghost.headstart - dt / 2:
                    self._advance(actor, dt)
            world.refresh()
            for run in self._dispatcher.active():
                run.after_motion(world)
            world.time = round(now + (step + 1 - steps) * dt, 9)
            self._storyboard.settle(world.time)
            self._record_ghosts()
        world.refresh()

    def _record_ghosts(self) -> None:
        for entity, follower in self._dispatcher.followers.items():
            ghost = self.world.actors.get(self._ghosts[entity].name)
            if ghost is not None and ghost.placed:
                follower.record(ghost, self.world.time)

    def _init_index(self, run: Run) -> int:
        """Where ``run`` is in the Init actions (after all of them if a story started it)."""
        for index, other in enumerate(self._init_runs):
            if other is run:
                return index
        return len(self._init_runs)

    def _sync(self) -> WorldSnapshot:
        """Push poses to the backend, step it, and build the snapshot."""
        backend = self._backend
        entities = list(self.world.states())
        for state in entities:
            backend.place(
                state.name, x=state.x, y=state.y, heading=state.heading, speed=state.speed
            )
        self.world.date_jumps()
        host = backend.traffic()
        if self._traffic.active and host is not None:
            self._traffic.update(self.world, host, entities, backend.states())
        backend.step()
        traffic: list[EntityState] = []
        previous = {state.name: state for state in self.world.traffic}
        for other in backend.states().values():
            if not other.external:
                continue
            # Ids follow first appearance and are never reused: a vehicle that leaves retires
            # its id, so every id's frames are contiguous.
            ident = self._external_ids.setdefault(
                other.name, len(self.world.actors) + len(self._external_ids)
            )
            traffic.append(
                EntityState(
                    id=ident,
                    name=other.name,
                    kind=EntityKind.VEHICLE,
                    category=other.category,
                    x=other.x,
                    y=other.y,
                    heading=other.heading,
                    speed=other.speed,
                    box=BoundingBox(
                        center_x=other.front_offset - other.length / 2.0,
                        length=other.length,
                        width=other.width,
                    ),
                )
            )
        moved = [(previous[s.name], s) for s in traffic if s.name in previous]
        self.world.discontinuities.extend(
            Discontinuity(time=self.world.time, entity=after.id, cause=JumpCause.TRAFFIC_MODEL)
            for after in _jumped(moved, self.world.dt)
        )
        self.world.traffic = tuple(traffic)
        self._snapshot = WorldSnapshot(
            time=self.world.time,
            entities=(*entities, *traffic),
            signals=tuple(self.world.signals.items()),
            phantoms=self.world.ghosts,
        )
        return self._snapshot


def init_order(init: model.Init) -> list[tuple[str, model.PrivateAction]]:
    """The Init's private actions in the order they run: as written, except that a teleport
    relative to an entity placed by a later action swaps places with that action (esmini's
    ``ScenarioReader::parseInit``: each action is checked against every earlier one, so a chain
    of references is resolved too)."""
    order = [(p.entity_ref, action) for p in init.private for action in p.actions]
    for i in range(1, len(order)):
        for j in range(i):
            action = order[j][1]
            if (
                isinstance(action, model.TeleportAction)
                and isinstance(
                    action.position, model.RelativeLanePosition | model.RelativeObjectPosition
                )
                and action.position.entity_ref == order[i][0]
            ):
                order[i], order[j] = order[j], order[i]
    return order


TRAFFIC_JUMP = 0.25
"""Metres of displacement a backend-driven vehicle's speeds leave unexplained in one step before
the step is declared a :attr:`JumpCause.TRAFFIC_MODEL` jump: half the evidence check's default
tolerance, well above rounding."""


def _jumped(moved: list[tuple[EntityState, EntityState]], dt: float) -> list[EntityState]:
    """The states (after) of the (before, after) pairs whose displacement their velocities
    leave more than :data:`TRAFFIC_JUMP` unexplained; one vectorised check per step."""
    if not moved:
        return []
    pairs = np.array(
        [(b.x, b.y, b.speed, b.heading, a.x, a.y, a.speed, a.heading) for b, a in moved]
    )
    bx, by, bv, bh, ax, ay, av, ah = pairs.T
    # each pair is a two-frame track; rows 0 and 1 of the velocities are its two frames
    error = unexplained_displacement(
        np.full(len(moved), dt),
        ax - bx,
        ay - by,
        np.stack([bv * np.cos(bh), av * np.cos(ah)]),
        np.stack([bv * np.sin(bh), av * np.sin(ah)]),
    )
    wrong = error.reshape(-1) > TRAFFIC_JUMP
    return [after for (_, after), jumped in zip(moved, wrong, strict=True) if jumped]


__all__ = ["Simulation", "pick_ego"]
