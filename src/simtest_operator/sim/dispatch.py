"""Starting actions: model actions -> running :class:`~simtest_operator.sim.runs.Run` objects.

Instant actions (teleport, routing, controller switches, parameter/variable changes) take effect
here and return a finished run. Continuous ones become runs registered per actor and control
domain; a new run in an occupied domain cancels the old one (the standard's conflict rule).

The system under test: while the driver model drives the ego, a SpeedAction on the ego becomes the
driver's new set speed (a request to the driver, like a driver turning the cruise-control knob),
and other longitudinal actions on the ego are not executed and are listed as ignored. Lateral
actions still run (the model only keeps its lane). esmini's interactive and external (no ghost)
controllers (:mod:`~simtest_operator.sim.esmini_controllers`), its FollowRouteController
(:mod:`~simtest_operator.sim.esmini_route`) and its ghost followers
(:mod:`~simtest_operator.sim.esmini_ghost`: the actions esmini hands to the ghost go to it) are
imitated on other entities, and on the ego when
the SUT does not take it; other controllers of other entities are not simulated: those entities
keep following the storyboard, and the controller is listed as ignored.

Under ScenarioRunner's rules (``scenario_runner``) speed and routing actions last as long as
ScenarioRunner lets them (:mod:`~simtest_operator.sim.lifetimes`), and lateral actions aimed at an
``external_control`` actor are ignored (listed), as ScenarioRunner's ExternalControl ignores them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim import (
    carla,
    esmini_acc,
    esmini_alks,
    esmini_controllers,
    esmini_ghost,
    esmini_route,
    placements,
    positions,
    random_routes,
    route_legs,
    route_planning,
    trailers,
)
from simtest_operator.sim.actors import Actor, Domain, Mode
from simtest_operator.sim.backends import TrafficHost
from simtest_operator.sim.following import DistanceRun
from simtest_operator.sim.lateral import LaneChangeRun, LaneOffsetRun, LateralDistanceRun
from simtest_operator.sim.lifetimes import IgnoredLateral, RouteHold, SpeedHold
from simtest_operator.sim.runs import Done, Run
from simtest_operator.sim.speeds import SpeedProfileRun, SpeedRun, target_speed
from simtest_operator.sim.synchronize import SynchronizeRun
from simtest_operator.sim.traffic import Traffic
from simtest_operator.sim.trajectories import PathRun
from simtest_operator.sim.world import World
from simtest_operator.snapshots import JumpCause

ControllerSwitch = Callable[[Actor, bool], None]
"""Engages (True) or releases (False) the SUT driver model on an actor."""

_SUT_LONGITUDINAL = (
    model.SpeedProfileAction,
    model.LongitudinalDistanceAction,
    model.SynchronizeAction,
)


class Dispatcher:
    """Starts actions on actors and keeps the per-actor, per-domain registry of runs."""

    __slots__ = (
        "_active",
        "_controllers",
        "_ego",
        "_external",
        "_host",
        "_imitated",
        "_scenario_runner",
        "_switch",
        "_traffic",
        "_watched",
        "_world",
        "accs",
        "alks",
        "assigned",
        "followers",
        "overrides",
        "routers",
        "teleported",
    )

    def __init__(
        self,
        world: World,
        *,
        ego: str | None,
        switch: ControllerSwitch,
        traffic: Traffic | None = None,
        host: TrafficHost | None = None,
        scenario_runner: bool = False,
        ghosts: Mapping[str, esmini_ghost.Ghost] | None = None,
    ) -> None:
        self._world = world
        self._scenario_runner = scenario_runner
        """The file runs under ScenarioRunner's rules: its controllers and action lifetimes."""
        self._traffic = traffic if traffic is not None else Traffic(seed=0)
        self._host = host
        self._ego = ego
        self._switch = switch
        self._active: dict[str, dict[Domain, Run]] = {}
        self._watched: dict[tuple[str, str], Run] = {}
        """Running actions that steer nothing (ScenarioRunner's lifetimes), by (entity, kind)."""
        self._external = {
            actor.name
            for actor in world.actors.values()
            if isinstance(actor.obj.controller, model.Controller)
            and carla.module_of(actor.obj.controller) is carla.Module.EXTERNAL
        }
        """Entities an ``external_control`` controller drives (ScenarioRunner's rules only)."""
        self.assigned: dict[tuple[str, str], None] = {}
        """(entity, controller) pairs assigned during the run, in order (an ordered set)."""
        self._controllers: dict[str, model.Controller] = {}
        self._imitated: set[tuple[str, str]] = set()
        """(entity, controller) pairs assigned during the run that the engine imitates."""
        """Controllers an AssignControllerAction gave entities (replacing the declared one)."""
        self.overrides: dict[str, esmini_controllers.Override] = {}
        """Imitated esmini controllers activated on entities (see :mod:`esmini_controllers`)."""
        self.routers: dict[str, esmini_route.FollowRoute] = {}
        """esmini FollowRoute controllers imitated, by entity (never under ScenarioRunner's
        rules)."""
        self.followers = {
            entity: esmini_ghost.Follower(ghost) for entity, ghost in (ghosts or {}).items()
        }
        """esmini ghost-following controllers by entity (:mod:`esmini_ghost`)."""
        self.accs: dict[str, esmini_acc.Acc] = {}
        """esmini ACC controllers activated on entities (never under ScenarioRunner's rules)."""
        self.alks: dict[str, esmini_alks.Alks] = {}
        """esmini ALKS R157 controllers (imitated models) activated on entities."""
        for actor in world.actors.values():
            controller = actor.obj.controller
            if isinstance(controller, model.Controller) and not scenario_runner:
                self._adopt(actor, controller)
        self.teleported: set[str] = set()
        """Entities a TeleportAction moved since the engine last cleared it (it holds them there
        for that step; an entity an AddEntityAction puts in the world moves at once)."""

    def imitates(self, entity: str, controller: str) -> bool:
        """Whether ``entity``'s controller of that name is imitated: an interactive or external
        one it was assigned, a FollowRoute, ACC or ALKS R157 controller, or a ghost follower
        that never restarts."""
        assigned = self._controllers.get(entity)
        router = self.routers.get(entity)
        follower = self.followers.get(entity)
        acc = self.accs.get(entity)
        return (
            (assigned is not None and assigned.name == controller)
            or (entity, controller) in self._imitated
            or (router is not None and router.name == controller)
            or (acc is not None and acc.name == controller)
            or (entity in self.alks and self.alks[entity].name == controller)
            or (
                follower is not None
                and follower.ghost.controller.name == controller
                and not follower.ghost.restarts
            )
        )

    def runs(self, actor: Actor) -> dict[Domain, Run]:
        """The actor's active runs by domain (finished ones pruned)."""
        mine = self._active.get(actor.name)
        if mine is None:
            return {}
        for domain in [d for d, run in mine.items() if run.finished]:
            ended = mine.pop(domain)
            # An action ScenarioRunner let end before its speed change did hands it on.
            rest = ended.successor if isinstance(ended, SpeedHold) else None
            if rest is not None:
                mine[domain] = rest
        return mine

    def active(self) -> list[Run]:
        """Every registered, unfinished run (each once)."""
        seen: dict[int, Run] = {}
        for mine in self._active.values():
            for run in mine.values():
                if not run.finished:
                    seen[id(run)] = run
        for run in self._watched.values():
            if not run.finished:
                seen[id(run)] = run
        return list(seen.values())

    def start(self, action: model.Action, actors: tuple[str, ...]) -> Sequence[Run]:
        """Storyboard callback: start ``action`` for each actor (global: once)."""
        body = action.body
        if not action.is_private:
            return [self.start_global(body)]
        if not actors:
            raise ScenarioError(
                f"private action {action.name!r} has no actors", element="Action", line=action.line
            )
        runs = [
            self.start_private(self._world.actor(self._handed(name, body)), body) for name in actors
        ]
        if action.name == esmini_ghost.RESTART:
            world = self._world
            for name in actors:
                follower = self.followers.get(name)
                if follower is not None:
                    ghost = world.actor(follower.ghost.name)
                    follower.restart(ghost, world.actor(name), world.time)
        return runs

    def _handed(self, entity: str, body: model.AnyAction) -> str:
        """The entity a storyboard action moves: its ghost for the actions esmini hands it."""
        follower = self.followers.get(entity)
        if follower is not None and isinstance(body, esmini_ghost.HANDED_ACTIONS):
            return follower.ghost.name
        return entity

    def start_global(self, body: model.AnyAction) -> Run:
        world = self._world
        if isinstance(body, model.SetValueAction):
            store = (
                world.parameters if body.scope is model.ValueScope.PARAMETER else world.variables
            )
            current = store.get(body.ref)
            store[body.ref] = _typed_like(current, body.value)
            return Done()
        if isinstance(body, model.ModifyValueAction):
            store = (
                world.parameters if body.scope is model.ValueScope.PARAMETER else world.variables
            )
            current = store.get(body.ref)
            if isinstance(current, bool) or not isinstance(current, int | float):
                raise ScenarioError(
                    f"cannot modify non-numeric {body.scope} {body.ref!r}",
                    element="ModifyAction",
                    line=body.line,
                )
            value = (
                current + body.value if body.rule is model.ModifyRule.ADD else current * body.value
            )
            store[body.ref] = type(current)(value)
            return Done()
        if isinstance(body, model.TrafficSignalStateAction):
            world.signals[body.name] = body.state
            return Done()
        if isinstance(body, model.TrafficSignalControllerAction):
            world.signal_controllers.switch(body.controller_ref, body.phase, world.time)
            return Done()
        if isinstance(
            body,
            model.TrafficSwarmAction
            | model.TrafficSourceAction
            | model.TrafficSinkAction
            | model.TrafficStopAction,
        ):
            # Traffic persists after its action completes, until a TrafficStopAction.
            self._traffic.start(world, self._host, body)
            return Done()
        if isinstance(body, model.AddEntityAction):
            actor = world.actor(body.entity_ref)
            if actor.placed:
                # Already in the world: the action fails and changes nothing (as in esmini).
                self._ignore(f"AddEntityAction of {actor.name}, which is already in the world")
                return Done(actor)
            # It comes back with the speed it had (esmini keeps a deleted entity's state).
            self.teleport(
                actor, positions.resolve(world, body.position, placing=True, mover=actor.name)
            )
            world.declare(actor, JumpCause.ADDED)
            return Done(actor)
        if isinstance(body, model.DeleteEntityAction):
            self.remove(world.actor(body.entity_ref))
            return Done()
        if isinstance(body, model.EnvironmentAction):
            world.environments.append((world.time, body.environment))
            return Done()
        if isinstance(body, model.SetMonitorAction):
            if body.monitor_ref not in world.monitors:
                raise ScenarioError(
                    f"monitor {body.monitor_ref!r} is not declared (MonitorDeclarations)",
                    element="SetMonitorAction",
                    line=body.line,
                )
            world.monitors[body.monitor_ref] = body.value
            return Done()
        if isinstance(body, model.IgnoredAction):
            self._ignore(body.kind)
            return Done()
        if isinstance(body, model.Unsupported):
            raise placements.unsupported(body)
        raise ScenarioError(f"{type(body).__name__} is not a global action")

    def remove(self, actor: Actor) -> None:
        """Take ``actor`` out of the world (DeleteEntityAction): its actions stop, it has no pose
        in the snapshots and no part in conditions until an AddEntityAction brings it back."""
        for run in self._active.pop(actor.name, {}).values():
            run.cancel()
        for (name, _), run in self._watched.items():
            if name == actor.name:
                run.cancel()
        actor.placed = False
        actor.driver = None
        self._world.declare(actor, JumpCause.DELETED)

    def start_private(self, actor: Actor, body: model.AnyAction) -> Run:
        world = self._world
        if isinstance(body, model.Unsupported):
            raise placements.unsupported(body)
        if isinstance(body, model.IgnoredAction):
            self._ignore(body.kind)
            return Done(actor)
        if actor.obj.unsupported is not None:
            raise placements.unsupported(actor.obj.unsupported)
        if isinstance(body, model.TeleportAction):
            if world.hitches.towed(actor.name):
                return Done(actor)  # its tow vehicle places it (esmini)
            moved = actor.placed  # the first pose (in Init) is no jump
            self.teleport(
                actor, positions.resolve(world, body.position, placing=True, mover=actor.name)
            )
            self.teleported.add(actor.name)
            if moved:
                world.declare(actor, JumpCause.TELEPORT)
            for trailer in trailers.align(world.actors, world.hitches, actor):
                world.attach(trailer)
                if moved:
                    world.declare(trailer, JumpCause.TELEPORT)
            return Done(actor)
        if isinstance(body, model.TrailerAction):
            if body.trailer_ref is None:
                world.hitches.disconnect(actor.name)
            else:
                trailer = world.actor(body.trailer_ref)
                world.hitches.connect(actor.obj, trailer.obj)
                if trailer.placed:
                    world.declare(trailer, JumpCause.HITCHED)
            return Done(actor)
        if isinstance(body, model.ActivateControllerAction):
            switched = self._controller_of(actor, body)
            imitated = self._imitate(actor, switched, body.longitudinal, body.lateral)
            if not imitated or actor.name == self._ego:
                self._activate(
                    actor, body.longitudinal, body.lateral, autopilot=self._scenario_runner
                )
            return Done(actor)
        if isinstance(body, model.AssignControllerAction):
            controller = body.controller
            if isinstance(controller, model.Unsupported):
                raise placements.unsupported(controller)
            self._assign(actor, controller, body)
            return Done(actor)
        if isinstance(body, model.AssignRouteAction):
            route = body.route
            if isinstance(route, model.Unsupported):
                raise placements.unsupported(route)
            self._route(actor, [wp.position for wp in route.waypoints[:1]])
            if world.roads is not None:
                legs = route_legs.legs(world, route, lambda p: positions.resolve(world, p))
                leg_roads = [leg.road_id for leg in legs]
                approach = list(actor.route)
                if approach and leg_roads and approach[-1] == leg_roads[0]:
                    approach.pop()
                actor.route = tuple(approach + leg_roads)
                actor.route_index = 0
            router = self.routers.get(actor.name)
            if router is not None:
                router.assign(self._route_waypoints(route))
            return self._routed(actor, route.waypoints[-1].position)
        if isinstance(body, model.RandomRouteAction):
            if world.roads is None or actor.mode is not Mode.ROAD or actor.road_id is None:
                raise ScenarioError(
                    f"a random route needs {actor.name} on a road",
                    element="RandomRouteAction",
                    line=body.line,
                )
            actor.route = random_routes.draw(
                world.roads, (actor.road_id, actor.direction), world.rng
            )
            actor.route_index = 0
            return Done(actor)
        if isinstance(body, model.AcquirePositionAction):
            self._route(actor, [body.position])
            return self._routed(actor, body.position)
        if (
            self._scenario_runner
            and actor.name in self._external
            and isinstance(body, model.LaneOffsetAction | model.LaneChangeAction)
        ):
            self._ignore(f"{type(body).__name__} on the externally controlled {actor.name}")
            return self._watch("waypoints", IgnoredLateral(actor, body))
        if actor.driver is not None:
            if isinstance(body, model.SpeedAction) and actor.driver.follows_limits:
                # CARLA's autopilot takes no speed requests (ScenarioRunner's CarlaAutopilot).
                self._ignore(f"SpeedAction on the autopilot of {actor.name}")
                return Done(actor)
            if isinstance(body, model.SpeedAction):
                actor.driver.set_speed = target_speed(world, body.target)
                if self._scenario_runner:
                    return self._watch("speed", SpeedHold(world, actor, body, None))
                return Done(actor)
            if isinstance(body, _SUT_LONGITUDINAL):
                self._ignore(f"{type(body).__name__} on the SUT-driven {actor.name}")
                return Done(actor)
        return self._register(actor, self._make(actor, body))

    def _routed(self, actor: Actor, last: model.Position) -> Run:
        """A routing action's run: done at once, or, under ScenarioRunner's rules, once the
        actor reached the last waypoint (an ``external_control`` actor: never)."""
        if not self._scenario_runner:
            return Done(actor)
        external = actor.name in self._external
        goal = None if external else positions.resolve(self._world, last)
        return self._watch("waypoints", RouteHold(actor, goal))

    def _watch(self, kind: str, run: Run) -> Run:
        """Keep a run that steers nothing until it ends; it ends an older one of its ``kind``
        on the same actor (ScenarioRunner's newer command replaces the goal)."""
        assert run.actor is not None
        key = (run.actor.name, kind)
        old = self._watched.get(key)
        if old is not None:
            old.finished = True
        self._watched[key] = run
        return run

    def _make(self, actor: Actor, body: model.AnyAction) -> Run:
        world = self._world
        if isinstance(body, model.SpeedAction):
            if self._scenario_runner:
                return SpeedHold(world, actor, body, SpeedRun(world, actor, body))
            return SpeedRun(world, actor, body)
        if isinstance(body, model.SpeedProfileAction):
            return SpeedProfileRun(world, actor, body)
        if isinstance(body, model.LaneChangeAction):
            return LaneChangeRun(world, actor, body)
        if isinstance(body, model.LaneOffsetAction):
            return LaneOffsetRun(world, actor, body)
        if isinstance(body, model.LateralDistanceAction):
            return LateralDistanceRun(world, actor, body)
        if isinstance(body, model.FollowTrajectoryAction):
            return PathRun(world, actor, body)
        if isinstance(body, model.LongitudinalDistanceAction):
            return DistanceRun(world, actor, body)
        if isinstance(body, model.SynchronizeAction):
            return SynchronizeRun(world, actor, body)
        raise ScenarioError(
            f"{type(body).__name__} is not supported",
            element=type(body).__name__,
            line=getattr(body, "line", None),
        )

    def _register(self, actor: Actor, run: Run) -> Run:
        """Cancel what ran in ``run``'s domains (even if ``run`` already finished, as a step
        speed change does) and register ``run`` while it keeps going."""
        if not run.domains:
            return run
        mine = self._active.setdefault(actor.name, {})
        for domain in run.domains:
            old = mine.get(domain)
            if old is not None and old is not run:
                old.cancel()
                for d in [d for d, r in mine.items() if r is old]:
                    del mine[d]
        if not run.finished:
            for domain in run.domains:
                mine[domain] = run
        return run

    def teleport(self, actor: Actor, placement: placements.Placement) -> None:
        world = self._world
        actor.x, actor.y, actor.z, actor.heading = (
            placement.x,
            placement.y,
            placement.z,
            placement.heading,
        )
        actor.placed = True
        lane = placement.lane
        walker = self._scenario_runner and carla.is_walker(actor)
        if walker:
            actor.mode = Mode.FREE  # ScenarioRunner's walkers go where they face, off the lanes
        elif lane is not None and world.roads is not None:
            world.set_lane(
                actor, lane.road_id, lane.lane_id, lane.s, lane.offset, direction=lane.direction
            )
        elif actor.mode is not Mode.PATH:
            world.attach(actor)
        # A teleport ends any path the actor was following.
        path = self._active.get(actor.name, {}).get(Domain.LATERAL)
        if isinstance(path, PathRun):
            path.cancel()
            if not walker:
                world.attach(actor)

    def _assign(
        self, actor: Actor, controller: model.Controller, body: model.AssignControllerAction
    ) -> None:
        """Assign a controller; ScenarioRunner's controller modules map to built-in drivers."""
        module = carla.module_of(controller)
        if not self._scenario_runner:
            self.routers.pop(actor.name, None)
            self._adopt(actor, controller)
        if module is carla.Module.NPC and actor.name != self._ego:
            return  # lane following at the SpeedActions' speed: what the engine does anyway
        if module is carla.Module.AUTOPILOT and actor.name != self._ego:
            carla.autopilot(self._world, actor, on=body.activate_longitudinal is not False)
            return
        self.assigned.setdefault((actor.name, controller.name), None)
        if not self._scenario_runner and (
            esmini_controllers.kind_of(controller) is not None
            or esmini_acc.is_acc(controller)
            or esmini_alks.imitated(controller)
        ):
            self._controllers[actor.name] = controller
            self._imitated.add((actor.name, controller.name))
            self.overrides.pop(actor.name, None)
            longitudinal, lateral = body.activate_longitudinal, body.activate_lateral
            if longitudinal is None and lateral is None:
                return  # assigned, not yet active
            self._imitate(actor, controller, longitudinal, lateral)
            if actor.name != self._ego:
                return
        if module is carla.Module.EXTERNAL:
            self._external.add(actor.name)
        self._activate(
            actor,
            body.activate_longitudinal,
            body.activate_lateral,
            autopilot=module is carla.Module.AUTOPILOT,
        )
        if module is carla.Module.EXTERNAL and actor.driver is not None:
            carla.start_moving(actor.driver)

    def _controller_of(
        self, actor: Actor, body: model.ActivateControllerAction
    ) -> model.Controller | None:
        """The controller an ActivateControllerAction switches: the named ObjectController,
        else the one assigned last, else the declared one."""
        name = body.object_controller_ref or body.controller_ref
        if name is not None:
            for entry in actor.obj.object_controllers:
                if entry.name == name and isinstance(entry.controller, model.Controller):
                    return entry.controller
        assigned = self._controllers.get(actor.name)
        if assigned is not None:
            return assigned
        controller = actor.obj.controller
        return controller if isinstance(controller, model.Controller) else None

    def _imitate(
        self,
        actor: Actor,
        controller: model.Controller | None,
        longitudinal: bool | None,
        lateral: bool | None,
    ) -> bool:
        """Activate an imitated esmini controller (not under ScenarioRunner's rules); False
        when ``controller`` is none of them (it then takes over the domains it activates)."""
        if self._scenario_runner or controller is None:
            return False
        follower = self.followers.get(actor.name)
        if follower is not None and esmini_ghost.uses_ghost(controller):
            follower.activate(actor, longitudinal, lateral)
            return True
        both = longitudinal is None and lateral is None
        acc = self.accs.get(actor.name)
        if esmini_acc.is_acc(controller):
            if acc is None or acc.name != controller.name:
                acc = self.accs[actor.name] = esmini_acc.Acc.of(controller)
            if both or longitudinal is True:
                acc.activate(actor)  # its only domain: the others' longitudinal ends
                if actor.name in self.alks:
                    self.alks[actor.name].active = False
                current = self.overrides.get(actor.name)
                if current is not None:
                    current.longitudinal = False
            elif longitudinal is False:
                acc.active = False
            return True
        alks = self.alks.get(actor.name)
        if esmini_alks.is_alks(controller):
            if alks is None or alks.name != controller.name:
                made = esmini_alks.Alks.of(controller)
                if made is None:
                    return False  # a model not imitated: the controller takes over
                alks = self.alks[actor.name] = made
            if both or longitudinal is True:
                alks.activate(actor)
                current = self.overrides.get(actor.name)
                if current is not None:
                    current.longitudinal = False
                if acc is not None:
                    acc.active = False
            elif longitudinal is False:
                alks.active = False
            return True
        if both or longitudinal is True:  # another controller takes the longitudinal domain
            if acc is not None:
                acc.active = False
            if alks is not None:
                alks.active = False
        override = esmini_controllers.activate(
            self.overrides.get(actor.name),
            controller,
            actor,
            longitudinal=longitudinal,
            lateral=lateral,
        )
        if override is None:
            current = self.overrides.get(actor.name)
            if current is not None:  # the other controller takes the domains it activates
                current.longitudinal = current.longitudinal and not (both or longitudinal is True)
                current.lateral = current.lateral and not (both or lateral is True)
            return False
        self.overrides[actor.name] = override
        return True

    def _activate(
        self, actor: Actor, longitudinal: bool | None, lateral: bool | None, *, autopilot: bool
    ) -> None:
        """Hand ``actor`` to a built-in driver or take it back; ``autopilot``: CARLA's (the
        road's speed limit), as ScenarioRunner's ActivateControllerAction switches it."""
        if actor.name != self._ego and self._scenario_runner:
            carla.autopilot(self._world, actor, on=longitudinal is not False or lateral is True)
            return
        router = self.routers.get(actor.name)
        if router is not None:
            # esmini's FollowRoute works in the lateral domain (lane changes), whatever else
            if lateral is False:
                router.active = False
            elif lateral is True or (lateral is None and longitudinal is None):
                router.activate()
            if actor.name != self._ego:
                return
        if actor.name != self._ego:
            controller = actor.obj.controller
            name = controller.name if isinstance(controller, model.Controller) else "controller"
            self._ignore(f"Controller {name} of {actor.name}")
            return
        if longitudinal is False:
            self._switch(actor, False)
        elif longitudinal is True or lateral is True or (longitudinal is None and lateral is None):
            self._switch(actor, True)
            if autopilot and actor.driver is not None:
                carla.engage_autopilot(self._world, actor, actor.driver)

    def _route(self, actor: Actor, targets: list[model.Position]) -> None:
        world = self._world
        roads = world.roads
        if roads is None:
            raise ScenarioError("routing needs a road network", element="RoutingAction")
        goals: list[str] = []
        for position in targets:
            placement = positions.resolve(world, position)
            if placement.lane is not None:
                goals.append(placement.lane.road_id)
                continue
            coord = world.road_coord(placement.x, placement.y, placement.heading)
            if coord is not None:
                goals.append(coord.road_id)
        if actor.mode is Mode.ROAD and actor.road_id is not None:
            roads_on_route = route_planning.plan_through(
                roads, (actor.road_id, actor.direction), goals
            )
        else:
            roads_on_route = goals
        actor.route = tuple(roads_on_route)
        actor.route_index = 0

    def _adopt(self, actor: Actor, controller: model.Controller) -> None:
        """Imitate ``controller`` on ``actor`` if the engine knows its kind."""
        if esmini_route.is_follow_route(controller):
            self.routers[actor.name] = esmini_route.FollowRoute(controller)

    def _route_waypoints(self, route: model.Route) -> list[esmini_route.Waypoint]:
        found: list[esmini_route.Waypoint] = []
        for waypoint in route.waypoints:
            lane = positions.resolve(self._world, waypoint.position).lane
            if lane is not None:
                found.append(esmini_route.Waypoint(lane.road_id, lane.lane_id, lane.s))
        return found

    def drive_controllers(self) -> None:
        """Step the imitated controllers of the actors no driver model drives (before motion)."""
        world = self._world
        for name, router in self.routers.items():
            actor = world.actors.get(name)
            if actor is None or not actor.placed or actor.driver is not None:
                continue
            lateral = self.runs(actor).get(Domain.LATERAL)
            changing = isinstance(lateral, LaneChangeRun) and lateral is router.change
            lane = router.step(world, actor, changing=changing)
            if lane is not None:
                action = model.LaneChangeAction(
                    dynamics=model.TransitionDynamics(
                        shape=model.DynamicsShape.SINUSOIDAL,
                        dimension=model.DynamicsDimension.TIME,
                        value=router.lane_change_time,
                    ),
                    target=model.AbsoluteTargetLane(lane_id=lane),
                )
                run = self._register(actor, LaneChangeRun(world, actor, action))
                router.change = run

    def _ignore(self, what: str) -> None:
        if what not in self._world.ignored:
            self._world.ignored.append(what)


def _typed_like(current: model.ParameterValue | None, text: str) -> model.ParameterValue:
    if isinstance(current, bool):
        return text.strip().lower() in ("true", "1")
    if isinstance(current, int):
        return int(float(text))
    if isinstance(current, float):
        return float(text)
    return text
