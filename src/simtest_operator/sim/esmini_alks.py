"""esmini's ALKS_R157SM_Controller: UN R157 safety models driving the longitudinal domain.

The reference player's controller scans the entities ahead (within the model's range, in the
own or a neighbouring lane, pedestrians in any lane), keeps the closest one that is a threat in
focus, decides whether the situation is critical and then brakes, else cruises (towards the speed
at activation, following a lead at the model's minimum distance; ``cruise=false``: the speed
stays). Three of its four models are imitated:

- ``Regulation`` (reaction 0.35 s, 6 m/s^2, 46 m range): an entity in the own lane is a
  deceleration threat, one whose front wheel is 0.3 m inside the own lane a cut-in; critical when
  the time to collision is under ``dv / 12 + 0.45`` s; it then brakes at 6 m/s^2 (with
  ``fullStop``: until standing).
- ``ReferenceDriver`` (the regulation's reference driver; 100 m range): a threat is perceived
  (a cut-in once the entity wandered 0.375 m towards the own lane and then for 0.72 m or
  ``cutInPerceptionDelayMode=Time`` 0.4 s more, a cut-out or a lead decelerating harder than
  5 m/s^2 after 0.4 s, a pedestrian closing in after ``pedestrianRiskEvaluationTime``), the
  driver reacts after 0.75 s (0.4 m/s^2 of engine drag), and if the situation is still critical
  (time to collision or headway under 2 s, always with ``alwaysTrigOnScenario``) brakes with a
  jerk of 0.774 g / 0.6 s up to 0.774 g; an AEB brakes up to 0.85 g once the time to collision
  falls under ``aebTTC`` (1.5 s) with the entity across the whole front.
- ``FSM`` (fuzzy safety model; 46 m range): a cut-in when the entity reaches the lane before
  the ego reaches it; critical while its proactive or critical fuzzy surrogate (safe and unsafe
  distances for 4 and 6 m/s^2 of braking, a lead braking at 7 m/s^2, 2 + 2 m of margin) is
  positive; after 0.75 s of reaction it brakes with a jerk of 12.65 m/s^3 to between 4 and
  6 m/s^2 as the surrogates say.

``RSS`` is not imitated (the controller stays labelled). Measures are taken in the
frame of the lane the entity drives (its travel direction): gaps between the boxes, speeds from
the last step's motion.
"""

from __future__ import annotations

import dataclasses
import enum
import math

from simtest_operator import geometry
from simtest_operator.openscenario import model
from simtest_operator.sim import motion
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.world import World
from simtest_operator.snapshots import EntityKind, EntityState

NAME = "ALKS_R157SM_Controller"
SMALL = 1e-10
LARGE = 1e10
CRITICAL_TIME = 2.0
"""s of time to collision (cut-in) or headway (cut-out, deceleration) the reference driver
deems critical."""


class ModelType(enum.StrEnum):
    REGULATION = "Regulation"
    REFERENCE_DRIVER = "ReferenceDriver"
    FSM = "FSM"


class Threat(enum.Enum):
    NONE = 0
    CUT_IN = 1
    CUT_OUT = 2
    DECELERATION = 3


class ModelMode(enum.Enum):
    CRITICAL = 0
    TARGET_IN_SIGHT = 1
    NO_TARGET = 2


class Phase(enum.Enum):
    INACTIVE = 0
    PERCEIVE = 1
    REACT = 2
    BRAKE_REF = 3


def is_alks(controller: model.Controller) -> bool:
    """Whether ``controller`` is esmini's ALKS_R157SM_Controller."""
    return (controller.property("esminiController") or controller.name) == NAME


def imitated(controller: model.Controller) -> bool:
    """Whether ``controller`` is an ALKS R157 controller running an imitated model."""
    return is_alks(controller) and model_of(controller) is not None


def model_of(controller: model.Controller) -> ModelType | None:
    """The imitated model ``controller`` runs (esmini's default: ReferenceDriver), or None."""
    name = controller.property("model")
    try:
        return ModelType(name) if name is not None else ModelType.REFERENCE_DRIVER
    except ValueError:
        return None


@dataclasses.dataclass(slots=True)
class Seen:
    """What the controller measures of one entity ahead (esmini's ObjectInfo)."""

    actor: Actor | None = None
    dist_long: float = LARGE
    dist_lat: float = LARGE
    dv_s: float = 0.0
    dv_t: float = 0.0
    ttc: float = LARGE
    thw: float = LARGE
    d_lane: int = 0
    their_v_t: float = 0.0
    """The entity's lateral speed (towards the ego frame's left)."""
    threat: Threat = Threat.NONE


@dataclasses.dataclass(slots=True)
class Trigger:
    """The reference driver's lane-wandering trigger: armed on an entity moving towards the
    own lane, fired once it moved ``threshold`` across."""

    threshold: float = 0.0
    actor: Actor | None = None
    t0: float = 0.0


@dataclasses.dataclass(slots=True)
class Alks:
    """One entity's ALKS R157 controller: parameters and state."""

    name: str
    kind: ModelType
    additive: bool = False
    cruise: bool = True
    full_stop: bool = False
    always_trig: bool = False
    time_perception: bool = False
    pedestrian_time: float = 0.4
    aeb_ttc: float = 1.5
    lateral_trig: float | None = None
    overlap_tolerance: float = 0.2
    driver_dec: float = 0.774 * 9.81
    aeb_dec: float = 0.85 * 9.81
    aeb_available: bool = True
    active: bool = False
    speed: float = 0.0
    set_speed: float = 0.0
    acc: float = 0.0
    mode: ModelMode = ModelMode.NO_TARGET
    threat: Threat = Threat.NONE
    focus: Seen = dataclasses.field(default_factory=Seen)
    phase: Phase = Phase.INACTIVE
    timer: float = 0.0
    perception_t: float = 0.0
    aeb: bool = False
    trigger: Trigger = dataclasses.field(default_factory=Trigger)
    reaction_left: float = 0.0
    """FSM: reaction time left before braking (counting down)."""
    cfs: float = 0.0
    pfs: float = 0.0

    @classmethod
    def of(cls, controller: model.Controller) -> Alks | None:
        """The controller with its Properties, or None when its model is not imitated."""
        kind = model_of(controller)
        if kind is None:
            return None
        lateral = controller.number("lateralTrigDistance", 0.0)
        return cls(
            name=controller.name,
            kind=kind,
            additive=(controller.property("mode") or "").strip().lower() == "additive",
            cruise=controller.flag("cruise", True),
            full_stop=controller.flag("fullStop", False),
            always_trig=controller.flag("alwaysTrigOnScenario", False),
            time_perception=controller.property("cutInPerceptionDelayMode") == "Time",
            pedestrian_time=controller.number("pedestrianRiskEvaluationTime", 0.4),
            aeb_ttc=controller.number("aebTTC", 1.5),
            lateral_trig=lateral if lateral > SMALL else None,
            overlap_tolerance=controller.number("overlapTolerance", 0.2),
            driver_dec=controller.number("driverDeceleration", 0.774 * 9.81),
            aeb_dec=controller.number("aebDeceleration", 0.85 * 9.81),
            aeb_available=controller.flag("aebAvailable", True),
        )

    @property
    def reaction_time(self) -> float:
        return 0.35 if self.kind is ModelType.REGULATION else 0.75

    @property
    def max_range(self) -> float:
        return 100.0 if self.kind is ModelType.REFERENCE_DRIVER else 46.0

    def activate(self, actor: Actor) -> None:
        """Cruise at the entity's speed now."""
        self.active = True
        self.speed = actor.speed
        self.set_speed = actor.speed

    def step(self, world: World, actor: Actor, dt: float) -> None:
        """Set the entity's speed for this step (esmini's Model::Step)."""
        if self.additive:
            self.speed = actor.speed  # the storyboard's speed reaches the model
        driver = self.kind is ModelType.REFERENCE_DRIVER
        if (
            driver
            and self.full_stop
            and self.focus.actor is not None
            and self.phase is not Phase.INACTIVE
        ):
            _measure(world, actor, self, self.focus)  # a reaction under way: no new scan
        else:
            self._detect(world, actor)
        if self._critical(world, actor, dt):
            self.speed = self._brake(dt)
        else:
            self.speed = self._cruise(dt)
        actor.speed = self.speed

    # -- detection ---------------------------------------------------------------------------

    def _detect(self, world: World, actor: Actor) -> None:
        best = Seen()
        seen = Seen()  # one record reused over the entities, as esmini does
        for other in world.actors.values():
            seen.actor = other
            if other is actor or not other.placed or not _measure(world, actor, self, seen):
                continue
            if self._safe(world, actor, seen):
                continue
            closer = seen.dist_long < best.dist_long
            beyond_cut_out = (
                seen.d_lane == 0
                and best.actor is not None
                and best.actor.kind is EntityKind.VEHICLE
                and best.threat is Threat.CUT_OUT
            )
            if not (closer or beyond_cut_out):
                continue
            if (
                other.kind is EntityKind.VEHICLE
                and seen.threat is Threat.CUT_OUT
                and best.actor is not None
                and best.d_lane == 0
            ):
                if seen.ttc < best.ttc:
                    best = dataclasses.replace(seen)
            elif beyond_cut_out:
                if seen.ttc < best.ttc:
                    best = dataclasses.replace(seen, threat=Threat.CUT_OUT)
            else:
                best = dataclasses.replace(seen)
        if (
            best.actor is not None
            and best.threat is not Threat.NONE
            and (best.actor is not self.focus.actor or best.threat is not self.focus.threat)
        ):
            self.threat = best.threat
        self.focus = best

    def _safe(self, world: World, actor: Actor, seen: Seen) -> bool:
        """esmini's CheckSafety: False (and the threat set) when ``seen`` threatens the lane."""
        if seen.actor is None or seen.dist_lat == LARGE:
            return True
        if self.kind is ModelType.REGULATION:
            return self._safe_regulation(world, seen)
        if self.kind is ModelType.FSM:
            return self._safe_fsm(seen)
        other = seen.actor
        self._update_trigger(world, actor, seen)
        if other.kind is EntityKind.PEDESTRIAN:
            if seen.dv_t > SMALL:
                seen.threat = Threat.CUT_IN
                return False
            return True
        if seen.d_lane == 0:
            center = other.offset + other.box.center_x * math.sin(_relative_heading(other))
            if abs(center) > 0.375 and seen.dv_t < -SMALL:
                seen.threat = Threat.CUT_OUT
            elif other.acceleration < -5.0 + SMALL:
                seen.threat = Threat.DECELERATION
            return False
        if self._trigger_fired(world):
            seen.threat = Threat.CUT_IN
            return False
        if seen.threat is Threat.CUT_IN:
            seen.threat = Threat.NONE
        return True

    def _safe_regulation(self, world: World, seen: Seen) -> bool:
        other = seen.actor
        assert other is not None
        if seen.d_lane == 0:
            seen.threat = Threat.DECELERATION
            return False
        if seen.dist_lat <= -SMALL or other.mode is not Mode.ROAD or other.road_id is None:
            return True
        width = _lane_width(world, other)
        axles = other.obj.axles
        if other.kind is EntityKind.VEHICLE and axles is not None and axles.front is not None:
            x = axles.front.position_x
        else:
            x = other.box.length / 2.0
        side = 1.0 if seen.d_lane > 0 else -1.0
        y = -side * other.box.width / 2.0
        heading = _relative_heading(other)
        offset = other.offset + x * math.sin(heading) + y * math.cos(heading)
        if -side * offset > width / 2.0 + 0.3:
            seen.threat = Threat.CUT_IN
            return False
        return True

    def _safe_fsm(self, seen: Seen) -> bool:
        if seen.d_lane == 0:
            seen.threat = Threat.DECELERATION
            return False
        if seen.dist_lat > -SMALL and seen.actor is not None:
            cut_in_speed = (-1.0 if seen.d_lane > 0 else 1.0) * seen.their_v_t
            if cut_in_speed <= 0.0:
                return True
            lateral = abs(seen.dist_lat) / cut_in_speed
            closing = max(SMALL, self.speed - seen.actor.speed)
            if lateral > abs(seen.dist_long) / closing + 0.1:
                return True
        seen.threat = Threat.CUT_IN
        return False

    def _update_trigger(self, world: World, actor: Actor, seen: Seen) -> None:
        trigger = self.trigger
        other = seen.actor
        if other is None or seen.dv_t < SMALL:
            if trigger.actor is not None:
                self.trigger = Trigger()
            return
        if other is trigger.actor:
            return
        t_other, t_own = _t(world, other), _t(world, actor)
        trigger.actor, trigger.t0 = other, t_other
        if self.lateral_trig is not None:
            trigger.threshold = self.lateral_trig
            return
        trigger.threshold = 0.375
        if (t_other > t_own and other.offset > 0.0) or (t_other < t_own and other.offset < 0.0):
            trigger.threshold += abs(other.offset)
        elif other.category != "motorbike":
            trigger.threshold = max(0.0, trigger.threshold - abs(other.offset))

    def _trigger_fired(self, world: World) -> bool:
        trigger = self.trigger
        if trigger.actor is None:
            return False
        return abs(_t(world, trigger.actor) - trigger.t0) > trigger.threshold

    # -- criticality and reaction ------------------------------------------------------------

    def _min_dist(self) -> float:
        """The model's following distance at the current speed."""
        speed = self.speed
        if self.kind is ModelType.REGULATION:
            if speed * 3.6 < 10.0:
                gap = 1.0 + (max(2.0, speed) - 2.0) / 7.8
            else:
                gap = 1.0 + speed * 3.6 / 100.0
            return max(speed * gap, 2.0)
        if self.kind is ModelType.FSM:
            lead = self.focus.actor.speed if self.focus.actor is not None else 0.0
            stop = speed**2 / (2.0 * FSM_BRAKE_MIN) - lead**2 / (2.0 * FSM_LEAD_BRAKE)
            return FSM_MARGIN + speed * FSM_REACTION + stop + FSM_MARGIN
        return 2.0 + speed * 2.0

    def _critical(self, world: World, actor: Actor, dt: float) -> bool:
        if self.kind is ModelType.REGULATION:
            return self._critical_regulation()
        if self.kind is ModelType.FSM:
            return self._critical_fsm(actor)
        focus = self.focus
        if self.phase in (Phase.INACTIVE, Phase.PERCEIVE):
            if self._perceived(world, actor, dt):
                self.phase, self.timer = Phase.REACT, self.reaction_time
        elif self.phase is Phase.REACT:
            self.timer -= dt
        if self.mode is ModelMode.NO_TARGET and focus.actor is not None:
            self.mode = ModelMode.TARGET_IN_SIGHT
        if self.full_stop and self.mode is ModelMode.CRITICAL:
            if self.speed < SMALL:
                self._reset()
                self.mode = self._sighted()
        elif focus.actor is None:
            self._reset()
            self.mode = ModelMode.NO_TARGET
        elif (self.speed > SMALL and focus.dist_long > 0.0) or self.full_stop:
            self._critical_condition()
        if (
            self.aeb_available
            and not self.aeb
            and focus.actor is not None
            and focus.ttc < self.aeb_ttc
            and _covers_front(world, actor, focus.actor, self.overlap_tolerance)
        ):
            self.aeb = True
        return self.mode is ModelMode.CRITICAL or self.aeb

    def _sighted(self) -> ModelMode:
        return ModelMode.TARGET_IN_SIGHT if self.focus.actor is not None else ModelMode.NO_TARGET

    def _reset(self) -> None:
        self.phase = Phase.INACTIVE
        self.threat = Threat.NONE

    def _perceived(self, world: World, actor: Actor, dt: float) -> bool:
        focus = self.focus
        if self.threat is Threat.CUT_IN:
            pedestrian = focus.actor is not None and focus.actor.kind is EntityKind.PEDESTRIAN
            if self.phase is Phase.INACTIVE:
                if pedestrian and focus.dv_s > SMALL:
                    self.timer = self.pedestrian_time
                    self.phase = Phase.PERCEIVE
                elif self._trigger_fired(world) and focus.actor is not None:
                    self.perception_t = _t(world, focus.actor)
                    self.timer = 0.4
                    self.phase = Phase.PERCEIVE
                return False
            if pedestrian:
                if focus.dv_s > SMALL:
                    self.timer -= dt
                    if self.timer < SMALL:
                        self.phase = Phase.REACT
            elif self.time_perception:
                self.timer -= dt
                if self.timer < SMALL:
                    self.phase = Phase.REACT
            elif focus.actor is not None:
                t, own = _t(world, focus.actor), _t(world, actor)
                if (t > own and t < self.perception_t - 0.72) or (
                    t < own and t > self.perception_t + 0.72
                ):
                    self.phase = Phase.REACT
            if self.phase is Phase.REACT:
                self.timer = self.reaction_time
                return True
            return False
        if self.threat is Threat.CUT_OUT:
            start = focus.dv_s > SMALL
        elif self.threat is Threat.DECELERATION:
            start = focus.actor is not None and focus.actor.acceleration < -5.0
        else:
            return False
        if self.phase is Phase.INACTIVE:
            if start:
                self.phase, self.timer = Phase.PERCEIVE, 0.4
            return False
        self.timer -= dt
        return self.timer < SMALL

    def _critical_condition(self) -> None:
        focus = self.focus
        measure = focus.ttc if self.threat is Threat.CUT_IN else focus.thw
        if self.threat is Threat.NONE:
            return
        if self.always_trig or measure < CRITICAL_TIME:
            if self.phase is Phase.REACT and self.timer < SMALL:
                self.mode = ModelMode.CRITICAL
        elif self.phase is Phase.REACT:
            self._reset()
        elif self.mode is ModelMode.CRITICAL and focus.dist_long > self._min_dist():
            self.mode = self._sighted()
            if focus.dv_s < SMALL:
                self._reset()

    def _critical_regulation(self) -> bool:
        focus = self.focus
        if focus.actor is None:
            self.mode = ModelMode.NO_TARGET
            return False
        if self.mode is ModelMode.CRITICAL and self.full_stop:
            return True
        # time to collision under vrel / (2 x 6 m/s^2) + the reaction time + 0.1 s
        limit = focus.dv_s / (2.0 * 6.0) + self.reaction_time + 0.1
        if focus.dv_s > 0.0 and focus.dist_long > 0.0 and focus.ttc < limit:
            self.mode = ModelMode.CRITICAL
            return True
        self.mode = ModelMode.TARGET_IN_SIGHT
        return False

    def _critical_fsm(self, actor: Actor) -> bool:
        focus = self.focus
        if focus.actor is None:
            self.mode = ModelMode.NO_TARGET
            return False
        if focus.dv_s > 0.0 and focus.dist_long > 0.0:
            lead = focus.actor.speed
            self.cfs = _cfs(focus.dist_long, self.speed, lead, actor.acceleration)
            self.pfs = _pfs(focus.dist_long, self.speed, lead)
            if self.cfs + self.pfs >= SMALL:
                if self.mode is not ModelMode.CRITICAL:
                    self.reaction_left = 0.75
                self.mode = ModelMode.CRITICAL
                return True
        self.mode = ModelMode.TARGET_IN_SIGHT
        return False

    def _brake(self, dt: float) -> float:
        if self.kind is ModelType.REGULATION:
            self.acc = -6.0
            return max(0.0, self.speed + self.acc * dt)
        if self.kind is ModelType.FSM:
            if self.reaction_left > 0.0:
                self.acc = min(self.acc, 0.0)  # foot off the accelerator
                self.reaction_left -= dt
                return self.speed + self.acc * dt
            if self.cfs > SMALL:
                wanted = self.cfs * (FSM_BRAKE_MAX - FSM_BRAKE_MIN) + FSM_BRAKE_MIN
            else:
                wanted = self.pfs * FSM_BRAKE_MIN
            self.acc = max(self.acc - 12.65 * dt, -self.driver_dec, -wanted)
            return max(0.0, self.speed + self.acc * dt)
        if self.phase is Phase.REACT and self.timer < SMALL:
            self.phase = Phase.BRAKE_REF
        if (self.phase is Phase.BRAKE_REF or self.aeb) and self.speed < SMALL:
            self.phase, self.aeb, self.timer = Phase.INACTIVE, False, 0.0
        if self.phase is Phase.REACT:
            self.acc = min(-0.4, self.acc)  # foot off the accelerator
        elif self.phase is Phase.BRAKE_REF:
            self.acc -= dt * self.driver_dec / 0.6
        if self.aeb:
            self.acc -= dt * self.aeb_dec / 0.6
        self.acc = max(self.acc, -(self.aeb_dec if self.aeb else self.driver_dec))
        return max(0.0, self.speed + self.acc * dt)

    def _cruise(self, dt: float) -> float:
        focus = self.focus
        if self.cruise:
            if focus.actor is None:
                self.mode = ModelMode.NO_TARGET
                if abs(self.speed - self.set_speed) < SMALL:
                    self.acc = 0.0
                else:
                    self.acc = -2.0 if self.speed > self.set_speed else 2.0
                return max(0.0, min(self.speed + self.acc * dt, self.set_speed))
            if focus.dist_long > 0.0 and focus.ttc > focus.dv_s / 12.0 + 0.35:
                self.mode = ModelMode.TARGET_IN_SIGHT
                if abs(self.speed) < SMALL:
                    self.acc = 0.0  # standing: brake released
                else:
                    wanted = -2.0 * focus.dv_s + (focus.dist_long - self._min_dist())
                    self.acc = max(-4.0, min(wanted, 3.0))
                return max(0.0, min(self.speed + self.acc * dt, self.set_speed))
        self.acc = 0.0
        return self.speed


FSM_MARGIN = 2.0
"""m the FSM model adds twice to its safe distance (margin and safe margin)."""
FSM_BRAKE_MIN = 4.0
"""m/s^2 the FSM model brakes with at the edge of its proactive zone."""
FSM_BRAKE_MAX = 6.0
"""m/s^2 it brakes with at the edge of its critical zone."""
FSM_LEAD_BRAKE = 7.0
"""m/s^2 it assumes the lead can brake with."""
FSM_REACTION = 0.75
"""s of its driver's reaction."""


def _pfs(dist: float, rear: float, lead: float) -> float:
    """The FSM's proactive fuzzy surrogate: 0 (safe) to 1 (unsafe) for a following distance."""
    dist -= FSM_MARGIN
    lead_stop = lead**2 / (2.0 * FSM_LEAD_BRAKE)
    safe = rear * FSM_REACTION + rear**2 / (2.0 * FSM_BRAKE_MIN) - lead_stop + FSM_MARGIN
    if dist > safe:
        return 0.0
    unsafe = rear * FSM_REACTION + rear**2 / (2.0 * FSM_BRAKE_MAX) - lead_stop
    if dist < unsafe:
        return 1.0
    return (dist - safe) / (unsafe - safe)


def _cfs(dist: float, rear: float, lead: float, acc: float) -> float:
    """The FSM's critical fuzzy surrogate for closing in on a slower lead at ``acc``."""
    if rear <= lead:
        return 0.0
    reacting = max(acc, -FSM_BRAKE_MIN)
    if rear + FSM_REACTION * reacting < lead:
        safe = (rear - lead) ** 2 / abs(acc * 2.0) if acc != 0.0 else LARGE
        return 1.0 if dist < safe else 0.0
    travel = (rear + reacting * FSM_REACTION / 2.0 - lead) * FSM_REACTION
    closing = (rear + reacting * FSM_REACTION - lead) ** 2
    safe = travel + closing / (FSM_BRAKE_MIN * 2.0)
    if dist > safe:
        return 0.0
    unsafe = travel + closing / (FSM_BRAKE_MAX * 2.0)
    if dist < unsafe:
        return 1.0
    return (dist - safe) / (unsafe - safe)


def _relative_heading(actor: Actor) -> float:
    """Heading of ``actor`` relative to its lane's travel direction (towards +t positive)."""
    return motion.relative_heading(actor, actor.speed) if actor.mode is Mode.ROAD else 0.0


def _axis(actor: Actor) -> float:
    """World heading of the lane direction ``actor`` travels."""
    return actor.heading - actor.direction * _relative_heading(actor)


def _t(world: World, actor: Actor) -> float:
    """Lateral road coordinate of ``actor``'s reference point."""
    if actor.mode is Mode.ROAD and actor.road_id is not None and world.roads is not None:
        return world.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset
    coord = world.road_coord(actor.x, actor.y)
    return coord.t if coord is not None else 0.0


def _lane_width(world: World, actor: Actor) -> float:
    if world.roads is None or actor.road_id is None:
        return 3.5
    for bounds in world.roads.lanes_at(actor.road_id, actor.s):
        if bounds.lane_id == actor.lane_id:
            return bounds.width
    return 3.5


def _frame(world: World, actor: Actor) -> EntityState:
    """The entity's state turned to its lane's travel direction (the road frame)."""
    return dataclasses.replace(world.state(actor.name), heading=_axis(actor))


def _measure(world: World, actor: Actor, alks: Alks, seen: Seen) -> bool:
    """esmini's Process: fill ``seen`` for the entity ahead, False when it is not considered."""
    other = seen.actor
    if other is None or other is actor or actor.mode is not Mode.ROAD or actor.road_id is None:
        return False
    own = _frame(world, actor)
    theirs = world.state(other.name)
    ahead = geometry.longitudinal_gap(own, theirs, freespace=False)
    if ahead <= SMALL or ahead > alks.max_range:
        return False
    own_lane = world.current_lane(actor)
    if other.mode is Mode.ROAD and other.road_id == actor.road_id:
        their_lane = world.current_lane(other)
    else:
        coord = world.road_coord(other.x, other.y)
        their_lane = coord.lane_id if coord is not None else 99
    d_lane = their_lane - own_lane
    if d_lane == 2 and their_lane == 1 and own_lane == -1:
        d_lane = 1
    elif d_lane == -2 and their_lane == -1 and own_lane == 1:
        d_lane = -1
    if other.kind is not EntityKind.PEDESTRIAN and abs(d_lane) >= 2:
        return False
    seen.d_lane = d_lane
    seen.dist_long = max(0.0, geometry.longitudinal_gap(own, theirs, freespace=True))
    seen.dist_lat = geometry.lateral_gap(own, theirs, freespace=True)
    axis = own.heading
    ux, uy = math.cos(axis), math.sin(axis)
    own_vx, own_vy = actor.velocity_xy
    their_vx, their_vy = other.velocity_xy
    own_s, their_s = own_vx * ux + own_vy * uy, their_vx * ux + their_vy * uy
    own_t, their_t = -own_vx * uy + own_vy * ux, -their_vx * uy + their_vy * ux
    seen.their_v_t = their_t
    seen.dv_s = own_s - their_s
    lateral = geometry.lateral_gap(own, theirs, freespace=False)
    seen.dv_t = (own_t - their_t) * (1.0 if lateral > 0 else -1.0 if lateral < 0 else 0.0)
    if seen.dv_s > 0.0:
        seen.ttc = seen.dist_long / seen.dv_s
        seen.thw = seen.dist_long / own_s if own_s > 0.0 else LARGE
    else:
        seen.ttc = seen.thw = LARGE
    return True


def _covers_front(world: World, actor: Actor, other: Actor, tolerance: float) -> bool:
    """Whether ``other`` lies across the whole of ``actor``'s front or within it (laterally,
    ``tolerance`` m granted): esmini's AEB condition."""
    own = _frame(world, actor)
    theirs = world.state(other.name)
    nx, ny = -math.sin(own.heading), math.cos(own.heading)
    low, high = geometry.extent_along(own, nx, ny)
    their_low, their_high = geometry.extent_along(theirs, nx, ny)
    covers = their_low <= low + tolerance and their_high >= high - tolerance
    inside = their_low >= low - tolerance and their_high <= high + tolerance
    return covers or inside
