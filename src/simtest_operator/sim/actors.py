"""Actors: the mutable runtime state of every scenario entity during a run.

An actor moves in one of three modes: ``ROAD`` (following its lane at an offset from the lane
centre, direction set by its heading, continuing through the lane graph), ``FREE`` (straight along
its heading, for open space and entities placed off the lanes) and ``PATH`` (a trajectory action
sets its pose every step). Scenario values never mutate; actors are the one place that does, and
:meth:`Actor.state` freezes them into snapshot values.
"""

from __future__ import annotations

import enum
import math
import operator

from simtest_operator.drivermodel import DriverModel, Steering
from simtest_operator.openscenario import model
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, fast_entity_state


class Mode(enum.StrEnum):
    """How an actor's position advances each step."""

    ROAD = "road"
    FREE = "free"
    PATH = "path"


class Domain(enum.StrEnum):
    """Control domains; a new action in a domain replaces the running one there."""

    LONGITUDINAL = "longitudinal"
    LATERAL = "lateral"


def steering_of(obj: model.ScenarioObject) -> Steering:
    """How the object steers: wheelbase and front-wheel limit from its axles, a passenger car's
    where they are missing or implausible."""
    axles = obj.axles
    if axles is None or axles.front is None:
        return Steering()
    wheelbase = axles.front.position_x - axles.rear.position_x
    angle = axles.front.max_steering
    if not (0.0 < wheelbase < math.inf and 0.0 < angle < math.pi / 2.0):
        return Steering()
    return Steering(wheelbase=wheelbase, max_angle=angle)


class Actor:
    """One entity during a run (OpenDRIVE conventions, reference point)."""

    __slots__ = (
        "_state",
        "_state_inputs",
        "acceleration",
        "acceleration_xy",
        "box",
        "category",
        "direction",
        "driver",
        "end_of_road_time",
        "heading",
        "heading_offset",
        "id",
        "kind",
        "lane_changing",
        "lane_id",
        "lateral_speed",
        "mode",
        "name",
        "obj",
        "odometer",
        "offroad_time",
        "offset",
        "pitch",
        "placed",
        "road_id",
        "roll",
        "route",
        "route_index",
        "s",
        "speed",
        "standstill_time",
        "steer_rate",
        "steering",
        "stretch",
        "stuck",
        "travel",
        "travel_speed",
        "velocity_xy",
        "x",
        "y",
        "yaw_rate",
        "z",
    )

    def __init__(self, obj: model.ScenarioObject, actor_id: int) -> None:
        self.obj = obj
        self.name = obj.name
        self.id = actor_id
        self.kind: EntityKind = obj.kind
        self.category = obj.category
        self.box: BoundingBox = obj.bounding_box
        self.x = self.y = self.z = 0.0
        self.heading = self.pitch = self.roll = 0.0
        self.speed = 0.0
        self.acceleration = 0.0
        """Change of speed over the last step (signed, along the heading)."""
        self.velocity_xy = (0.0, 0.0)
        """World-frame velocity over the last step: displacement / dt (speed along the heading
        after a teleport), as esmini measures it."""
        self.acceleration_xy = (0.0, 0.0)
        """World-frame acceleration: change of ``velocity_xy`` over the last step (includes the
        centripetal part in curves; what AccelerationCondition reads)."""
        self.lateral_speed = 0.0
        """Rate (m/s) of the lateral position across the lane (+t) over the last step."""
        self.travel: tuple[float, float] | None = None
        """World-frame velocity the motion model gave the reference point over the last step,
        where it is not ``speed`` along ``heading`` (see :attr:`EntityState.travel`); None:
        along the heading."""
        self.travel_speed = 0.0
        """``speed`` when ``travel`` was set: a speed set after the motion (an action started
        at the step's end) scales it."""
        self.yaw_rate = 0.0
        """Change of heading over the last step (rad/s); 0 after a teleport."""
        self.mode = Mode.FREE
        self.road_id: str | None = None
        self.lane_id = 0
        self.s = 0.0
        self.offset = 0.0
        """Lateral offset (m) from the centre of ``lane_id``, positive towards +t."""
        self.direction = 1
        """+1 when moving towards increasing s on ``road_id``, else -1."""
        self.heading_offset = 0.0
        """Heading relative to the lane's travel direction, kept while following the lane (an
        entity placed at an angle keeps that angle, as in esmini)."""
        self.placed = False
        """False until a Teleport (or the first pose) puts the actor into the world."""
        self.odometer = 0.0
        self.standstill_time = 0.0
        self.offroad_time = 0.0
        self.end_of_road_time = 0.0
        self.stuck = False
        """True while the lane it follows has ended (no successor)."""
        self.route: tuple[str, ...] = ()
        """Roads of an assigned route in order; the next ones are preferred at forks."""
        self.route_index = 0
        """Position of the actor's current road in ``route``."""
        self.stretch = 1.0
        """Reference-line metres per metre driven at the actor's lateral position (from its
        last lane pose; more than 1 inside a curve)."""
        self.lane_changing = False
        """Set by a lane change for the coming motion step: its lateral motion is part of the
        distance driven (esmini), not added to it."""
        self.steer_rate: float | None = None
        """Lateral speed (m/s) whose part of this step's travel a lane change takes from the
        longitudinal motion (its rate at the step start, as esmini); None: the measured one."""
        self.driver: DriverModel | None = None
        """Set while the system-under-test driver model controls this actor."""
        self.steering = steering_of(obj)
        self._state: EntityState | None = None
        self._state_inputs: tuple[object, ...] = ()

    def measure_motion(
        self, start: tuple[float, float, float], dt: float, *, teleported: bool
    ) -> None:
        """Update ``velocity_xy``, ``acceleration_xy`` and ``yaw_rate`` after a step from the
        pose ``start`` (x, y, heading); with ``dt`` 0 or after a teleport, the velocity from the
        speed along the heading and no yaw rate."""
        if teleported or dt <= 0.0:
            velocity = (
                self.speed * math.cos(self.heading),
                self.speed * math.sin(self.heading),
            )
            self.yaw_rate = 0.0
        else:
            velocity = ((self.x - start[0]) / dt, (self.y - start[1]) / dt)
            self.yaw_rate = math.remainder(self.heading - start[2], 2.0 * math.pi) / dt
        if dt > 0.0:
            self.acceleration_xy = (
                (velocity[0] - self.velocity_xy[0]) / dt,
                (velocity[1] - self.velocity_xy[1]) / dt,
            )
        self.velocity_xy = velocity

    def set_travel(self, travel: tuple[float, float] | None) -> None:
        """Record the velocity this step's motion gave the reference point (None: ``speed``
        along the heading)."""
        self.travel = travel
        self.travel_speed = self.speed

    def _travel(self) -> tuple[float, float] | None:
        """The state's ``travel``: the motion's velocity at the speed the actor has now."""
        travel, speed = self.travel, self.speed
        if travel is None or speed == self.travel_speed:
            return travel
        if self.travel_speed == 0.0:
            return None
        scale = speed / self.travel_speed
        return travel[0] * scale, travel[1] * scale

    @property
    def front_offset(self) -> float:
        """Distance from the reference point to the front bumper."""
        return self.box.center_x + self.box.length / 2.0

    def state(self) -> EntityState:
        """A frozen snapshot of this actor.

        Built once per change: while none of the attributes it is made of has been reassigned
        since the last call (checked by identity, so exactly, signed zeros included), that same
        value comes back. A step asks for every state more than once (before actors advance,
        after they moved, and again at the next step's start) but most actors only change in
        between some of those.
        """
        road = self.mode is Mode.ROAD
        road_id, lane_id, s = (self.road_id, self.lane_id, self.s) if road else (None, None, None)
        inputs = (
            self.x,
            self.y,
            self.heading,
            self.speed,
            self.acceleration,
            self.travel,
            self.travel_speed,
            self.yaw_rate,
            self.z,
            self.pitch,
            self.roll,
            road_id,
            lane_id,
            s,
            self.box,
            self.id,
            self.name,
            self.kind,
            self.category,
        )
        last = self._state
        if last is not None and all(map(operator.is_, inputs, self._state_inputs)):
            return last
        state = fast_entity_state(
            self.id,
            self.name,
            self.kind,
            self.category,
            self.x,
            self.y,
            self.z,
            (self.heading + math.pi) % (2.0 * math.pi) - math.pi,
            self.pitch,
            self.roll,
            self.speed,
            self.acceleration,
            self._travel(),
            self.yaw_rate,
            self.box,
            road_id,
            lane_id,
            s,
            None,
        )
        self._state = state
        self._state_inputs = inputs
        return state
