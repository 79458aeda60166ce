"""esmini's InteractiveController and ExternalController as they behave with nobody at the wheel.

The reference player runs headless: no key is ever pressed and no external process reports an
entity's state. esmini's controllers then still override the storyboard in the domains they are
active on (the storyboard's actions run, their output is not used):

- ``InteractiveController`` keeps its own vehicle model. On activation it takes the entity's
  speed at that moment (0 when the ActivateControllerAction comes before the Init's SpeedAction),
  then without throttle only the engine brake acts (the speed shrinks by a per mille per step),
  capped at the road's speed limit times ``speedFactor`` (without a limit: 110 km/h where the
  side has more than one driving lane, else 60 km/h) and the entity's maximum speed. Without
  steering input the wheels stay straight: with the lateral domain it drives straight along its
  heading; with the longitudinal domain alone it follows its lane at its own speed.
- ``ExternalController`` without ``useGhost`` does nothing: nobody reports, so the entity stands
  where it was (speed 0) in the domains it controls.

Controllers that need a ghost (FollowGhost, ExternalController with ``useGhost``) are imitated
in :mod:`~simtest_operator.sim.esmini_ghost`.
"""

from __future__ import annotations

import dataclasses
import enum
import math

from simtest_operator.opendrive import DRIVABLE_LANE_TYPES
from simtest_operator.openscenario import model
from simtest_operator.sim import carla
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World

ENGINE_BRAKE = 0.001
"""Share of its speed esmini's vehicle model loses per step without throttle."""
MULTI_LANE_LIMIT = 110.0 / 3.6
"""m/s the interactive driver allows on a road without a limit with several lanes its way."""
SINGLE_LANE_LIMIT = 60.0 / 3.6
"""m/s it allows there with a single lane its way."""


class Kind(enum.StrEnum):
    """The esmini controllers imitated (values: their ``esminiController`` property)."""

    INTERACTIVE = "InteractiveController"
    EXTERNAL = "ExternalController"


def kind_of(controller: model.Controller) -> Kind | None:
    """The imitated controller ``controller`` is, if any (an external one only without ghost);
    without an ``esminiController`` property esmini takes the controller's name as its type."""
    name = controller.property("esminiController") or controller.name
    if name == Kind.INTERACTIVE:
        return Kind.INTERACTIVE
    if name == Kind.EXTERNAL:
        ghost = (controller.property("useGhost") or "").strip().lower()
        return None if ghost in ("true", "1") else Kind.EXTERNAL
    return None


@dataclasses.dataclass(slots=True)
class Override:
    """An imitated controller active on an entity: the domains it drives and its own speed."""

    kind: Kind
    longitudinal: bool
    lateral: bool
    speed: float
    speed_factor: float = 1.0

    @property
    def active(self) -> bool:
        return self.longitudinal or self.lateral


def activate(
    current: Override | None,
    controller: model.Controller,
    actor: Actor,
    *,
    longitudinal: bool | None,
    lateral: bool | None,
) -> Override | None:
    """The override after an activation (None attributes: unchanged; both None: both on), or
    None when ``controller`` is not imitated. A new activation restarts the vehicle model at
    the entity's speed now."""
    kind = kind_of(controller)
    if kind is None:
        return None
    both = longitudinal is None and lateral is None
    kept = current if current is not None and current.kind is kind else None
    return Override(
        kind=kind,
        longitudinal=both or _domain(longitudinal, kept.longitudinal if kept else False),
        lateral=both or _domain(lateral, kept.lateral if kept else False),
        speed=actor.speed,
        speed_factor=controller.number("speedFactor", 1.0),
    )


def _domain(flag: bool | None, before: bool) -> bool:
    return before if flag is None else flag


def drive_speed(world: World, actor: Actor, override: Override) -> None:
    """Set the speed the controller drives at this step (longitudinal domain only)."""
    if not override.longitudinal:
        return
    if override.kind is Kind.EXTERNAL:
        override.speed = 0.0
    else:
        speed = override.speed * (1.0 - ENGINE_BRAKE)
        top = _top_speed(world, actor, override)
        override.speed = max(-top, min(speed, top))
    actor.speed = override.speed


def steer(world: World, actor: Actor, override: Override, dt: float) -> bool:
    """Move the entity for this step in the lateral domain: an external one stays put, an
    interactive one drives straight along its heading. False when the lateral domain is not
    the controller's (the storyboard's motion applies)."""
    if not override.lateral:
        return False
    if override.kind is Kind.INTERACTIVE:
        actor.x += actor.speed * math.cos(actor.heading) * dt
        actor.y += actor.speed * math.sin(actor.heading) * dt
    if actor.mode is not Mode.FREE or world.roads is not None:
        world.attach(actor)
    return True


def _top_speed(world: World, actor: Actor, override: Override) -> float:
    limit = carla.speed_limit(world, actor)
    if limit is None or limit <= 0.0:
        limit = SINGLE_LANE_LIMIT
        roads = world.roads
        if roads is not None and actor.mode is Mode.ROAD and actor.road_id is not None:
            side = 1 if actor.lane_id > 0 else -1
            lanes = roads.lanes_at(actor.road_id, actor.s)
            count = sum(
                1 for lane in lanes if lane.lane_id * side > 0 and lane.type in DRIVABLE_LANE_TYPES
            )
            if count > 1:
                limit = MULTI_LANE_LIMIT
    top = override.speed_factor * limit
    performance = actor.obj.performance
    if performance is not None:
        top = min(top, performance.max_speed)
    return top
