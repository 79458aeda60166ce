"""World snapshots: what the simulator emits at every step.

The simulator produces them; evaluation, recording and the runner consume them. They are plain
frozen values so those consumers never depend on the simulator backend.

Conventions (OpenDRIVE/OpenSCENARIO, right-handed): ``x``/``y``/``z`` in metres are the entity's
*reference point* (for vehicles the rear-axle centre projected to the ground); ``heading`` in
radians counter-clockwise from +x; ``speed`` in m/s along the heading (along the direction of
travel when ``travel`` gives one); ``acceleration`` in m/s^2 along the heading. ``box`` gives the
bounding box relative to the reference point, so consumers can derive the box centre
(:meth:`EntityState.box_center`) and its velocity (:meth:`EntityState.box_velocity`).
"""

from __future__ import annotations

import dataclasses
import enum
import math


class EntityKind(enum.StrEnum):
    """OpenSCENARIO entity families."""

    VEHICLE = "vehicle"
    PEDESTRIAN = "pedestrian"
    MISC_OBJECT = "miscObject"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BoundingBox:
    """An entity's box: centre offset from the reference point (entity frame) and dimensions."""

    center_x: float = 0.0
    center_y: float = 0.0
    center_z: float = 0.0
    length: float = 4.5
    width: float = 1.8
    height: float = 1.5


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EntityState:
    """One entity at one instant."""

    id: int
    """Stable integer id >= 0, unique within a run (OSI object ids need integers)."""
    name: str
    kind: EntityKind
    category: str
    """OpenSCENARIO category, e.g. ``car``, ``truck``, ``pedestrian``, ``obstacle``."""
    x: float
    y: float
    z: float = 0.0
    heading: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0
    speed: float = 0.0
    acceleration: float = 0.0
    travel: tuple[float, float] | None = None
    """World-frame velocity (m/s) of the reference point where it is not ``speed`` along
    ``heading``: moving sideways (a lane change, a lane offset), a car crabbing at an angle to
    its lane, a trajectory whose headings are not its direction."""
    yaw_rate: float = 0.0
    """rad/s, counter-clockwise: turns the box centre round the reference point."""
    box: BoundingBox = dataclasses.field(default_factory=BoundingBox)
    road_id: str | None = None
    lane_id: int | None = None
    s: float | None = None
    t: float | None = None

    def box_center(self) -> tuple[float, float, float]:
        """World coordinates of the bounding-box centre."""
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        return (
            self.x + self.box.center_x * cos_h - self.box.center_y * sin_h,
            self.y + self.box.center_x * sin_h + self.box.center_y * cos_h,
            self.z + self.box.center_z,
        )

    def velocity(self) -> tuple[float, float]:
        """World-frame velocity vector (vx, vy) of the reference point."""
        if self.travel is not None:
            return self.travel
        return self.speed * math.cos(self.heading), self.speed * math.sin(self.heading)

    def box_velocity(self) -> tuple[float, float]:
        """World-frame velocity of the bounding-box centre: the reference point's plus the
        turn of the centre round it (what a recording of box centres moves by)."""
        vx, vy = self.velocity()
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        box, rate = self.box, self.yaw_rate
        return (
            vx - rate * (box.center_x * sin_h + box.center_y * cos_h),
            vy + rate * (box.center_x * cos_h - box.center_y * sin_h),
        )


# The slot descriptors' setters, in field order (unpacking fails loudly if a field is added).
(
    _set_id,
    _set_name,
    _set_kind,
    _set_category,
    _set_x,
    _set_y,
    _set_z,
    _set_heading,
    _set_pitch,
    _set_roll,
    _set_speed,
    _set_acceleration,
    _set_travel,
    _set_yaw_rate,
    _set_box,
    _set_road_id,
    _set_lane_id,
    _set_s,
    _set_t,
) = (getattr(EntityState, field.name).__set__ for field in dataclasses.fields(EntityState))


def fast_entity_state(
    id: int,
    name: str,
    kind: EntityKind,
    category: str,
    x: float,
    y: float,
    z: float,
    heading: float,
    pitch: float,
    roll: float,
    speed: float,
    acceleration: float,
    travel: tuple[float, float] | None,
    yaw_rate: float,
    box: BoundingBox,
    road_id: str | None,
    lane_id: int | None,
    s: float | None,
    t: float | None,
    /,
) -> EntityState:
    """The same value as ``EntityState(id=id, name=name, ...)``, built about three times faster.

    For the simulator's per-step hot path, which builds every entity's state each step: the
    dataclass ``__init__`` of a frozen slotted class goes through ``object.__setattr__`` per
    field with keyword arguments; this sets the slots directly. The result is an ordinary
    :class:`EntityState` (frozen, same equality, hash and repr).
    """
    state: EntityState = object.__new__(EntityState)
    _set_id(state, id)
    _set_name(state, name)
    _set_kind(state, kind)
    _set_category(state, category)
    _set_x(state, x)
    _set_y(state, y)
    _set_z(state, z)
    _set_heading(state, heading)
    _set_pitch(state, pitch)
    _set_roll(state, roll)
    _set_speed(state, speed)
    _set_acceleration(state, acceleration)
    _set_travel(state, travel)
    _set_yaw_rate(state, yaw_rate)
    _set_box(state, box)
    _set_road_id(state, road_id)
    _set_lane_id(state, lane_id)
    _set_s(state, s)
    _set_t(state, t)
    return state


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class WorldSnapshot:
    """All entities at one simulated instant, ``time`` seconds after the scenario start."""

    time: float
    entities: tuple[EntityState, ...]
    signals: tuple[tuple[str, str], ...] = ()
    """Traffic signal states set so far, ``(name, state)`` as the scenario's
    TrafficSignalStateActions gave them (a signal never set is absent: its state is unknown)."""
    phantoms: frozenset[str] = frozenset()
    """Entities recorded but seen by no one (esmini's ghosts): a system under test never
    perceives them."""

    def entity(self, name: str) -> EntityState | None:
        """The entity called ``name``, or None when it is not (yet) in the world."""
        for state in self.entities:
            if state.name == name:
                return state
        return None


class JumpCause(enum.StrEnum):
    """Why the simulation moved an entity discontinuously on purpose (what the scenario asked)."""

    TELEPORT = "teleport"
    """A TeleportAction put it elsewhere."""
    TRAJECTORY_START = "trajectoryStart"
    """A FollowTrajectoryAction put it on its trajectory's start (elsewhere, or turned to the
    start's heading)."""
    LATERAL_STEP = "lateralStep"
    """A lane change or lane offset of ``step`` shape (or zero time), or a lateral distance
    without limits, moved it across at once; or a lateral distance without an acceleration
    limit stepped its lateral speed (and heading)."""
    ROAD_END = "roadEnd"
    """It reached the end of its road and stands there, its speed dropped a step later (as
    esmini does)."""
    ADDED = "added"
    """An AddEntityAction (re)placed it."""
    DELETED = "deleted"
    """A DeleteEntityAction took it out of the world."""
    HITCHED = "hitched"
    """A ConnectTrailerAction hitched it (a parked trailer) to its tow vehicle, which pulls it
    onto the hitch at once (as esmini does)."""
    TRAFFIC_MODEL = "trafficModel"
    """The backend's own traffic model (SUMO) moved a vehicle it drives farther in one step than
    its speeds explain: a junction's internal lane that does not meet its approach, a turn about
    a radius shorter than the car. Not the engine's doing, so not its evidence to fault."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Discontinuity:
    """A discontinuity the scenario commands: ``entity`` (:attr:`EntityState.id`) is first shown
    in its new state by the frame at ``time``, so the evidence checks excuse the frame interval
    that ends there, for that entity alone."""

    time: float
    entity: int
    cause: JumpCause
    object_id: int | None = None
    """The OSI moving object id the entity had in a recording (it changes when an entity
    comes back after a gap); None in the simulation."""
