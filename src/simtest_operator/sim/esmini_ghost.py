"""esmini's ghost: FollowGhostController and ExternalController with ``useGhost``.

What esmini does (``ScenarioEngine::SetupGhost``, ``ControllerFollowGhost``, ``vehicle.cpp``):

- An entity whose controller needs a ghost gets a copy, the entity ``<name>_ghost``, which no
  controller drives. It gets a copy of each of the entity's Init actions except
  ActivateControllerAction (after all other Init actions), and the storyboard's speed, speed
  profile, lane change, lane offset, synchronize, trajectory, route and teleport actions on the
  entity are handed to it (their references to the entity then name the ghost).
- The simulation starts ``headstartTime`` seconds (default 3) before 0: during that time only
  ghosts move. Act start triggers, and the triggers of events handed to a ghost, have their
  SimulationTime values moved earlier by the head start; in those events' triggers the entity's
  collision, reach-position, traveled-distance, speed, acceleration, end-of-road, off-road and
  stand-still conditions watch the ghost instead. Any other condition there makes the event
  teleport the ghost onto the entity first (:data:`RESTART`); after 0 that is a "ghost restart":
  the ghost takes the entity's speed, drops its trail and replays its head start while
  everything else waits, and the events that teleported the ghost may fire again. A restart in
  an event with other actors than the entity is not imitated (the controller stays labelled).
- FollowGhostController (from its activation, at t >= 0) drives the entity along the ghost's
  trail with its own vehicle model: in ``followMode`` ``time`` the speed of the trail point
  ``lookaheadSpeed`` seconds after ``t - headstartTime`` and a steering target
  ``lookaheadSteering`` seconds after it; in ``position`` mode the points that many metres per
  m/s (at least the minimum) ahead of the trail point closest to the entity. The vehicle model
  accelerates at 10 m/s^2 per m/s of speed error (at most 10 m/s^2), turns its wheels towards
  the target (at most 60 degrees, less at speed: ``steeringSpeedInertia``) and moves as a
  kinematic bicycle whose pivot is 15 % of its length from the rear.
- ExternalController with ``useGhost``: nobody reports a state, so the entity stands still in
  the domains it controls (like without ghost); the ghost drives ahead.

Ghosts are phantoms: no collisions, not seen by the SUT model (``World.ghosts``).
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from collections.abc import Iterable
from typing import TypeVar

from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor
from simtest_operator.sim.world import World
from simtest_operator.snapshots import EntityKind

SUFFIX = "_ghost"
RESTART = "AddedGhostTeleport"
"""esmini's name for the teleport it puts first in an event that restarts the ghost."""
"""esmini names the ghost of ``X`` ``X_ghost``."""
DEFAULT_HEADSTART = 3.0
"""Seconds the ghost starts before the entity, unless ``headstartTime`` says otherwise."""
MAX_ACCELERATION = 10.0
"""m/s^2 (and per m/s of speed error) of the follower's vehicle model."""
MAX_SPEED = 100.0
MAX_WHEEL_ANGLE = math.radians(60.0)
PIVOT = 0.15
"""Share of its length from the rear where the vehicle model turns."""

_T = TypeVar("_T")

HANDED_ACTIONS = (
    model.SpeedAction,
    model.SpeedProfileAction,
    model.LaneChangeAction,
    model.LaneOffsetAction,
    model.SynchronizeAction,
    model.FollowTrajectoryAction,
    model.AssignRouteAction,
    model.TeleportAction,
)
"""Storyboard actions on the entity that esmini hands to its ghost."""
_HANDED_CONDITIONS = (
    model.CollisionCondition,
    model.ReachPositionCondition,
    model.TraveledDistanceCondition,
    model.SpeedCondition,
    model.AccelerationCondition,
    model.EndOfRoadCondition,
    model.OffRoadCondition,
    model.StandStillCondition,
)
"""Entity conditions of handed events that watch the ghost instead of the entity."""


def uses_ghost(controller: model.Controller) -> bool:
    """Whether esmini gives the controller's entity a ghost."""
    kind = controller.property("esminiController") or controller.name
    if kind == "FollowGhostController":
        return True
    ghost = (controller.property("useGhost") or "").strip().lower()
    return kind == "ExternalController" and ghost in ("true", "1")


def ghost_controller(obj: model.ScenarioObject) -> model.Controller | None:
    """The entity's first declared controller that needs a ghost (esmini sets the ghost up for
    the controllers an ObjectController declares)."""
    declared: Iterable[object] = [entry.controller for entry in obj.object_controllers] or [
        obj.controller
    ]
    for controller in declared:
        if isinstance(controller, model.Controller) and uses_ghost(controller):
            return controller
    return None


@dataclasses.dataclass(frozen=True, slots=True)
class Ghost:
    """An entity's ghost as set up before the run."""

    entity: str
    name: str
    controller: model.Controller
    headstart: float
    restarts: tuple[str, ...]
    """Events whose triggers need a ghost restart that is not imitated (the event has other
    actors than the entity)."""
    rearm: tuple[str, ...]
    """Events a ghost restart sets back to standby: those that teleport the ghost."""


def setup(
    scenario: model.Scenario, *, skip: frozenset[str] = frozenset()
) -> tuple[model.Scenario, dict[str, Ghost]]:
    """The scenario with esmini's ghosts added and the storyboard rewired for them (entities in
    ``skip``, e.g. an ego the SUT drives, get none), and the ghosts by entity."""
    ghosts: dict[str, Ghost] = {}
    entities = list(scenario.entities)
    storyboard = scenario.storyboard
    for obj in scenario.entities:
        controller = ghost_controller(obj)
        if controller is None or obj.name in skip or obj.kind is not EntityKind.VEHICLE:
            continue
        name = obj.name + SUFFIX
        if any(other.name == name for other in entities):
            continue
        headstart = max(controller.number("headstartTime", DEFAULT_HEADSTART), 0.0)
        entities.append(
            dataclasses.replace(
                obj, name=name, controller=None, object_controller_name=None, object_controllers=()
            )
        )
        restarts: list[str] = []
        rearm: list[str] = []
        storyboard = _rewire(storyboard, obj.name, name, headstart, restarts, rearm)
        ghosts[obj.name] = Ghost(
            entity=obj.name,
            name=name,
            controller=controller,
            headstart=headstart,
            restarts=tuple(restarts),
            rearm=tuple(rearm),
        )
    if not ghosts:
        return scenario, ghosts
    return dataclasses.replace(scenario, entities=tuple(entities), storyboard=storyboard), ghosts


def _rewire(
    storyboard: model.Storyboard,
    entity: str,
    ghost: str,
    headstart: float,
    restarts: list[str],
    rearm: list[str],
) -> model.Storyboard:
    copies = tuple(
        action
        for private in storyboard.init.private
        if private.entity_ref == entity
        for action in private.actions
        if not isinstance(action, model.ActivateControllerAction)
    )
    init = dataclasses.replace(
        storyboard.init,
        private=(*storyboard.init.private, model.PrivateInit(entity_ref=ghost, actions=copies)),
    )
    stories = []
    for story in storyboard.stories:
        acts = []
        for act in story.acts:
            start = _retarget(act.start_trigger, entity, ghost, headstart, None)
            groups = []
            for group in act.maneuver_groups:
                if entity not in group.actors.entity_refs:
                    groups.append(group)
                    continue
                maneuvers = []
                for maneuver in group.maneuvers:
                    events = []
                    for event in maneuver.events:
                        handed = any(
                            a.is_private and isinstance(a.body, HANDED_ACTIONS)
                            for a in event.actions
                        )
                        if handed:
                            needs: list[str] = []
                            trigger = _retarget(
                                event.start_trigger, entity, ghost, headstart, needs, event.name
                            )
                            actions = tuple(
                                dataclasses.replace(a, body=_swap_refs(a.body, entity, ghost))
                                if a.is_private and isinstance(a.body, HANDED_ACTIONS)
                                else a
                                for a in event.actions
                            )
                            alone = group.actors.entity_refs == (entity,)
                            if needs and alone and not group.actors.select_triggering_entities:
                                actions = (_restart_teleport(entity), *actions)
                            elif needs:
                                restarts.extend(needs)
                            if any(isinstance(a.body, model.TeleportAction) for a in actions):
                                rearm.append(event.name)
                            event = dataclasses.replace(
                                event, start_trigger=trigger, actions=actions
                            )
                        events.append(event)
                    maneuvers.append(dataclasses.replace(maneuver, events=tuple(events)))
                groups.append(dataclasses.replace(group, maneuvers=tuple(maneuvers)))
            acts.append(
                dataclasses.replace(act, start_trigger=start, maneuver_groups=tuple(groups))
            )
        stories.append(dataclasses.replace(story, acts=tuple(acts)))
    return dataclasses.replace(storyboard, init=init, stories=tuple(stories))


def _swap_refs(value: _T, entity: str, ghost: str) -> _T:
    """``value`` with every ``*entity_ref`` naming the entity naming the ghost instead (esmini's
    ``ReplaceObjectRefs`` on the actions it hands over: targets relative to the entity become
    relative to the ghost)."""
    if isinstance(value, tuple):
        items = tuple(_swap_refs(item, entity, ghost) for item in value)
        same = all(new is old for new, old in zip(items, value, strict=True))
        return value if same else items  # type: ignore[return-value]
    if not dataclasses.is_dataclass(value) or isinstance(value, type):
        return value
    changes: dict[str, object] = {}
    for field in dataclasses.fields(value):
        item = getattr(value, field.name)
        if isinstance(item, str):
            if field.name.endswith("entity_ref") and item == entity:
                changes[field.name] = ghost
        elif isinstance(item, tuple) or dataclasses.is_dataclass(item):
            swapped = _swap_refs(item, entity, ghost)
            if swapped is not item:
                changes[field.name] = swapped
    return dataclasses.replace(value, **changes) if changes else value


def _restart_teleport(entity: str) -> model.Action:
    """The teleport esmini puts first in an event that restarts the ghost: onto the entity."""
    here = model.RelativeObjectPosition(
        entity_ref=entity,
        dx=0.0,
        dy=0.0,
        orientation=model.Orientation(type=model.ReferenceContext.RELATIVE),
    )
    return model.Action(name=RESTART, body=model.TeleportAction(position=here), is_private=True)


def _retarget(
    trigger: model.Trigger | None,
    entity: str,
    ghost: str,
    headstart: float,
    restarts: list[str] | None,
    event: str = "",
) -> model.Trigger | None:
    """The trigger with its SimulationTime values moved ``headstart`` earlier and, in a handed
    event's trigger (``restarts`` not None), the entity's conditions watching the ghost; a
    condition that would make esmini restart the ghost is noted in ``restarts``."""
    if trigger is None:
        return None
    groups = []
    for group in trigger.condition_groups:
        conditions = []
        for condition in group.conditions:
            body = condition.body
            restart = False
            if isinstance(body, model.ByValue):
                inner = body.condition
                if isinstance(inner, model.SimulationTimeCondition):
                    shifted = dataclasses.replace(inner, value=inner.value - headstart)
                    body = dataclasses.replace(body, condition=shifted)
                else:
                    restart = True
            elif isinstance(body.condition, _HANDED_CONDITIONS):
                refs = body.triggering_entities
                restart = any(ref != entity for ref in refs)
                if restarts is not None:
                    body = dataclasses.replace(
                        body, triggering_entities=tuple(ghost if r == entity else r for r in refs)
                    )
            else:
                restart = True
            if restart and restarts is not None and event not in restarts:
                restarts.append(event)
            conditions.append(dataclasses.replace(condition, body=body))
        groups.append(dataclasses.replace(group, conditions=tuple(conditions)))
    return dataclasses.replace(trigger, condition_groups=tuple(groups))


@dataclasses.dataclass(slots=True)
class _Point:
    t: float
    x: float
    y: float
    speed: float
    s: float


class Follower:
    """The controller of an entity with a ghost: the ghost's trail and the vehicle model."""

    __slots__ = (
        "_index",
        "_synced",
        "_times",
        "_trail",
        "external",
        "ghost",
        "heading",
        "inertia",
        "lateral",
        "longitudinal",
        "lookahead_speed",
        "lookahead_steering",
        "min_lookahead_speed",
        "min_lookahead_steering",
        "position_mode",
        "restarting",
        "speed",
        "x",
        "y",
    )

    def __init__(self, ghost: Ghost) -> None:
        controller = ghost.controller
        self.ghost = ghost
        kind = controller.property("esminiController") or controller.name
        self.external = kind == "ExternalController"
        self.position_mode = (controller.property("followMode") or "").strip() == "position"
        self.lookahead_speed = controller.number("lookaheadSpeed", 0.1)
        self.min_lookahead_speed = controller.number("minLookaheadSpeed", 0.1)
        self.lookahead_steering = controller.number("lookaheadSteering", 1.0)
        self.min_lookahead_steering = controller.number("minLookaheadSteering", 1.0)
        self.inertia = controller.number("steeringSpeedInertia", 0.01)
        self.longitudinal = self.lateral = False
        self.x = self.y = self.heading = self.speed = 0.0
        self._synced = False
        """The vehicle model holds the entity's pose (taken at the first step after an
        activation: an Init teleport may come after the Init's activation; the speed is the
        one at activation)."""
        self._trail: list[_Point] = []
        self._times: list[float] = []
        self._index = 0
        self.restarting = False
        """A ghost restart happened this step: the ghost replays its head start next."""

    @property
    def active(self) -> bool:
        return self.longitudinal or self.lateral

    def activate(self, actor: Actor, longitudinal: bool | None, lateral: bool | None) -> None:
        """(De)activate in the domains given (both None: both on); an activation restarts the
        vehicle model with the entity's speed now and its pose at the next step."""
        both = longitudinal is None and lateral is None
        self.longitudinal = both or (self.longitudinal if longitudinal is None else longitudinal)
        self.lateral = both or (self.lateral if lateral is None else lateral)
        self.speed = actor.speed
        self._synced = False

    def restart(self, ghost: Actor, entity: Actor, time: float) -> None:
        """The ghost was put onto the entity by a restarting event: after 0 it takes the
        entity's speed, drops its trail and replays its head start (before 0 it only moved)."""
        if time <= 1e-9:
            return
        ghost.speed = entity.speed
        self.restarting = True

    def replay(self) -> None:
        """Drop the trail before the ghost replays its head start (the entity followed the old
        one up to now)."""
        self.restarting = False
        self._trail.clear()
        self._times.clear()
        self._index = 0

    def record(self, ghost: Actor, time: float) -> None:
        """Add the ghost's pose at ``time`` to its trail."""
        s = 0.0
        if self._trail:
            last = self._trail[-1]
            s = last.s + math.hypot(ghost.x - last.x, ghost.y - last.y)
        self._trail.append(_Point(time, ghost.x, ghost.y, ghost.speed, s))
        self._times.append(time)

    def drive(self, world: World, actor: Actor, dt: float) -> bool:
        """Move the entity one step (False when not active: the storyboard moves it)."""
        if not self.active:
            return False
        if not self._synced:
            self.x, self.y, self.heading = actor.x, actor.y, actor.heading
            self._synced = True
        if self.external:
            actor.speed = 0.0
        elif self._trail:
            self._follow(actor, world.time, dt)
            actor.x, actor.y, actor.heading, actor.speed = self.x, self.y, self.heading, self.speed
        world.attach(actor)
        return True

    def _follow(self, actor: Actor, now: float, dt: float) -> None:
        if self.position_mode:
            s = self._closest_s()
            speed_point = self._at_s(
                s + max(self.min_lookahead_speed, self.lookahead_speed * self.speed)
            )
            target = self._at_s(
                s + max(self.min_lookahead_steering, self.lookahead_steering * self.speed)
            )
        else:
            base = now - self.ghost.headstart
            speed_point = self._at_time(base + max(self.min_lookahead_speed, self.lookahead_speed))
            target = self._at_time(base + max(self.min_lookahead_steering, self.lookahead_steering))
        dx, dy = target.x - self.x, target.y - self.y
        length = math.hypot(dx, dy)
        cross = 0.0
        if length > 1e-10:
            cross = math.cos(self.heading) * dy / length - math.sin(self.heading) * dx / length
        wanted = math.asin(max(-1.0, min(1.0, cross)))
        error = speed_point.speed - self.speed
        acceleration = max(-MAX_ACCELERATION, min(MAX_ACCELERATION * error, MAX_ACCELERATION))
        self.speed = max(-MAX_SPEED, min(self.speed + acceleration * dt, MAX_SPEED))
        scale = 1.0 / (1.0 + self.inertia * self.speed * self.speed)
        wheel = max(-scale * MAX_WHEEL_ANGLE, min(wanted, scale * MAX_WHEEL_ANGLE))
        slip = math.atan(PIVOT * math.tan(wheel))
        direction = self.heading + slip
        wheelbase = max(actor.box.length, 1e-3) * PIVOT
        self.heading = (self.heading + dt * self.speed * math.sin(slip) / wheelbase) % math.tau
        self.x += dt * self.speed * math.cos(direction)
        self.y += dt * self.speed * math.sin(direction)

    def _at_time(self, time: float) -> _Point:
        trail = self._trail
        i = bisect.bisect_right(self._times, time)
        if i <= 0:
            return trail[0]
        if i >= len(trail):
            return trail[-1]
        a, b = trail[i - 1], trail[i]
        f = (time - a.t) / (b.t - a.t) if b.t > a.t else 0.0
        return _Point(
            time, a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), a.speed + f * (b.speed - a.speed), 0
        )

    def _closest_s(self) -> float:
        """s of the trail point closest to the vehicle, searched from the last one found on."""
        trail = self._trail
        best, best_s = math.inf, trail[self._index].s
        for i in range(self._index, len(trail) - 1):
            a, b = trail[i], trail[i + 1]
            ex, ey = b.x - a.x, b.y - a.y
            span = ex * ex + ey * ey
            f = 0.0 if span <= 0.0 else ((self.x - a.x) * ex + (self.y - a.y) * ey) / span
            f = max(0.0, min(1.0, f))
            d = math.hypot(a.x + f * ex - self.x, a.y + f * ey - self.y)
            if d < best:
                best, best_s, self._index = d, a.s + f * (b.s - a.s), i
        return best_s

    def _at_s(self, s: float) -> _Point:
        trail = self._trail
        for i in range(self._index, len(trail) - 1):
            a, b = trail[i], trail[i + 1]
            if b.s >= s:
                f = (s - a.s) / (b.s - a.s) if b.s > a.s else 0.0
                return _Point(
                    a.t + f * (b.t - a.t),
                    a.x + f * (b.x - a.x),
                    a.y + f * (b.y - a.y),
                    a.speed + f * (b.speed - a.speed),
                    s,
                )
        return trail[-1]
