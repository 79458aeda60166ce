"""esmini's ACCController: an adaptive cruise control in the longitudinal domain.

The reference player's controller drives at a set speed and, behind a lead vehicle, keeps a
following distance of 3 m plus ``timeGap`` seconds of the larger of its own and the lead's speed.
Its law, per step of ``dt``:

- A speed that differs from the controller's own by more than 1e-3 m/s was set by someone else
  (a SpeedAction of the storyboard): it becomes the new set speed (the controller's speed stays).
- The lead is the nearest entity ahead whose reference point is within ``lookahead`` (50 m, or
  twice the stopping distance plus 6 m) along the road in the same lane and less than
  ``lateralDist`` across, its bumper gap positive; or an entity close ahead whatever its lane
  (free-space gap less than 1 m plus its length plus half the closing speed, less than 0.2 m to
  the left and 0.5 m to the right).
- With a lead at a gap under 1 m the speed drops to 0. Otherwise, with ``d`` the following
  distance and ``f = min(1, (gap - d) / d)``, the acceleration is
  ``2.5 f - f (v - v_set) - (1 - f) (v - min(v_set, v_lead))``, clamped to the vehicle's
  deceleration and acceleration limits, the speed never negative.
- Without a lead it approaches the set speed at ``0.7 a_max (v_set - v)``, clamped to
  ``[-d_max, 0.7 a_max]``, never overshooting it.

The storyboard still moves the entity along its lane (its lateral actions apply). Properties
(esmini's defaults): ``timeGap`` (1.5 s), ``setSpeed`` (the speed at activation, also in
``additive`` mode, the default without a ``mode`` property), ``lateralDist`` (5 m); ``virtual``
true: the controller only computes, the entity keeps the storyboard's speed.
"""

from __future__ import annotations

import dataclasses
import math

from simtest_operator import geometry
from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World
from simtest_operator.snapshots import EntityState

NAMES = ("ACCController", "ALKSController")
"""esmini's ACC and its older ALKS controller (the ACC under another name)."""
MIN_DISTANCE = 3.0
"""m the controller keeps to its lead at standstill."""
SET_SPEED_GAIN = 0.7
"""Share of the maximum acceleration per m/s of set-speed error without a lead."""
GAP_GAIN = 2.5
"""m/s^2 of acceleration when the gap is at least twice the following distance."""
SPEED_SET_ELSEWHERE = 1e-3
"""m/s by which the entity's speed differs from the controller's when something else set it."""
DEFAULT_LIMIT = 10.0
"""m/s^2 acceleration and deceleration assumed for a vehicle without Performance."""


def is_acc(controller: model.Controller) -> bool:
    """Whether ``controller`` is esmini's ACCController or ALKSController (its type: the
    ``esminiController`` property, else its name)."""
    return (controller.property("esminiController") or controller.name) in NAMES


@dataclasses.dataclass(slots=True)
class Acc:
    """One entity's ACC controller: its parameters and state."""

    name: str
    time_gap: float = 1.5
    lateral_dist: float = 5.0
    set_speed: float = 0.0
    set_speed_given: bool = False
    additive: bool = True
    virtual: bool = False
    active: bool = False
    speed: float = 0.0

    @classmethod
    def of(cls, controller: model.Controller) -> Acc:
        """The controller with its Properties (esmini's defaults where absent)."""
        given = controller.property("setSpeed")
        mode = controller.property("mode")
        return cls(
            name=controller.name,
            time_gap=controller.number("timeGap", 1.5),
            lateral_dist=controller.number("lateralDist", 5.0),
            set_speed=controller.number("setSpeed", 0.0),
            set_speed_given=given is not None,
            additive=mode is None or mode.strip().lower() == "additive",
            virtual=(controller.property("virtual") or "").strip().lower() == "true",
        )

    def activate(self, actor: Actor) -> None:
        """Start at the entity's speed; without a given set speed (or additive) it is the set
        speed too."""
        self.active = True
        self.speed = actor.speed
        if self.additive or not self.set_speed_given:
            self.set_speed = actor.speed

    def step(self, world: World, actor: Actor, dt: float) -> None:
        """Set the entity's speed for this step (after the storyboard's longitudinal action)."""
        if self.virtual:
            return
        if self.additive and abs(actor.speed - self.speed) > SPEED_SET_ELSEWHERE:
            self.set_speed = actor.speed
        performance = actor.obj.performance
        max_acc = performance.max_acceleration if performance else DEFAULT_LIMIT
        max_dec = performance.max_deceleration if performance else DEFAULT_LIMIT
        lead = _lead(world, actor, self, max_dec)
        if lead is not None:
            gap, lead_speed = lead
            if gap < 1.0:
                self.speed = 0.0
            else:
                follow = MIN_DISTANCE + self.time_gap * abs(max(self.speed, lead_speed))
                factor = min(1.0, (gap - follow) / follow)
                dv_min = self.speed - min(self.set_speed, lead_speed)
                dv_set = self.speed - self.set_speed
                acc = GAP_GAIN * factor - factor * dv_set - (1.0 - factor) * dv_min
                acc = max(-max_dec, min(acc, max_acc))
                self.speed = max(0.0, self.speed + acc * dt)
        else:
            acc = (self.set_speed - self.speed) * SET_SPEED_GAIN * max_acc
            acc = max(-max_dec, min(acc, SET_SPEED_GAIN * max_acc))
            speed = self.speed + acc * dt
            passed = abs(speed - self.set_speed) > abs(self.speed - self.set_speed)
            self.speed = self.set_speed if passed else speed
        actor.speed = self.speed


def _lead(world: World, actor: Actor, acc: Acc, max_dec: float) -> tuple[float, float] | None:
    """(bumper gap, speed) of the entity the controller adapts to, or None."""
    stopping = acc.speed**2 / max_dec if max_dec > 0.0 else 0.0
    lookahead = max(50.0, 2.0 * MIN_DISTANCE + stopping)
    on_road = actor.mode is Mode.ROAD and actor.road_id is not None and world.roads is not None
    lane = world.current_lane(actor) if on_road else 0
    own_t = 0.0
    if on_road:
        assert actor.road_id is not None
        own_t = world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset
    state = world.state(actor.name)
    best: tuple[float, float] | None = None
    for other in world.actors.values():
        if other is actor or not other.placed:
            continue
        gap: float | None = None
        if on_road and other.mode is Mode.ROAD and other.road_id == actor.road_id:
            assert actor.road_id is not None
            ds = (other.s - actor.s) * actor.direction
            other_t = world.lane_t(actor.road_id, other.s, other.lane_id) + other.offset
            if 0.0 <= ds <= lookahead and abs(other_t - own_t) < acc.lateral_dist:
                same_way = math.cos(other.heading - actor.heading) > 0.0
                rear = other.box.length - other.front_offset if same_way else other.front_offset
                bumper = ds - actor.front_offset - rear
                if world.current_lane(other) == lane and bumper > 0.0:
                    gap = bumper
        if gap is None:
            gap = _close_ahead(state, world, other, acc.speed)
        if gap is not None and (best is None or gap < best[0]):
            best = (gap, other.speed)
    return best


def _close_ahead(state: EntityState, world: World, other: Actor, speed: float) -> float | None:
    """Free-space gap to ``other`` when it is just ahead whatever its lane, else None."""
    theirs = world.state(other.name)
    ahead = geometry.longitudinal_gap(state, theirs, freespace=True)
    across = geometry.lateral_gap(state, theirs, freespace=True)
    reach = 1.0 + other.box.length + 0.5 * max(0.0, speed - other.speed)
    if 0.0 < ahead < reach and -0.5 < across < 0.2:
        return ahead
    return None
