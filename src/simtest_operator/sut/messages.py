"""The OSI messages of the SUT protocol: encoding what the simulator sends, decoding what the SUT
answers into the engine's :class:`~simtest_operator.sim.sut.Order`.

``SensorView`` wraps the ``GroundTruth`` the recorder's fast encoder writes (same layout, ids and
conventions as the recording: every entity an ``osi3.MovingObject`` at its bounding-box centre),
so the SUT sees exactly what is recorded, the map's traffic lights (their bulbs as lit now) and
stop signs included. Frame layouts are cached per set of objects, which keeps encoding at a few
microseconds per object.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from typing import TYPE_CHECKING

from simtest_operator.recording import osiwire
from simtest_operator.sim.sut import Order
from simtest_operator.snapshots import EntityKind, EntityState, WorldSnapshot
from simtest_operator.sut import protowire as pw

if TYPE_CHECKING:  # a SUT process imports this without the road network (numpy)
    from simtest_operator.opendrive import TrafficControl
    from simtest_operator.recording import signalwire

OSI_VERSION = osiwire.OSI_VERSION
_VEHICLE_CLASSES = {
    "car": 4, "van": 6, "truck": 7, "semitrailer": 9, "trailer": 10, "motorbike": 11,
    "bicycle": 12, "bus": 13, "tram": 14, "train": 15, "wheelchair": 16,
}  # fmt: skip
_SIGNATURE = operator.attrgetter("id", "box", "kind", "category")
LATERAL_DEADBAND = 1e-6
"""Lateral displacements (m) below this are rounding, not steering."""

# MotionRequest.MotionRequestType (OSI 3.7.0: MOTION_REQUEST_TYPE_DESIRED_STATE, ..._TRAJECTORY)
DESIRED_STATE, TRAJECTORY = 0, 1


def _object_layout(state: EntityState) -> osiwire.ObjectLayout:
    category = state.category.lower()
    if state.kind is EntityKind.VEHICLE:
        kind, class_type, role = 2, _VEHICLE_CLASSES.get(category, 1), 2
    elif state.kind is EntityKind.PEDESTRIAN:
        kind, class_type, role = (4 if category == "animal" else 3), 1, 0
    else:
        kind, class_type, role = 1, 1, 0
    box = state.box
    return osiwire.object_layout(
        object_id=state.id,
        object_type=kind,
        dimension=(max(box.length, 0.01), max(box.width, 0.01), max(box.height, 0.0)),
        classification_type=class_type,
        classification_role=role,
    )


def _kinematics(state: EntityState) -> tuple[float, ...]:
    """The ten changing doubles of an object (as the recorder writes them)."""
    heading = state.heading
    c, s = math.cos(heading), math.sin(heading)
    box = state.box
    acceleration = state.acceleration
    vx, vy = state.box_velocity()
    return (
        state.x + box.center_x * c - box.center_y * s,
        state.y + box.center_x * s + box.center_y * c,
        state.z + box.center_z,
        math.remainder(state.roll, math.tau),
        math.remainder(state.pitch, math.tau),
        math.remainder(heading, math.tau),
        vx,
        vy,
        acceleration * c,
        acceleration * s,
    )


class SensorViewEncoder:
    """Encodes ``osi3.SensorView`` messages of one run (layouts cached across steps)."""

    __slots__ = ("_frame", "_layouts", "_range", "_signals", "_signature", "_tail")

    def __init__(
        self,
        *,
        perception_range: float | None,
        map_reference: str = "map",
        signals: Sequence[TrafficControl] = (),
    ) -> None:
        self._range = perception_range
        self._signals: signalwire.SignalWire | None = None
        """The map's traffic lights (with their states) and stop signs, in every SensorView."""
        if signals:
            from simtest_operator.recording import signalwire

            self._signals = signalwire.SignalWire(signals)
        self._tail = osiwire.ground_truth_tail(country_code=276, map_reference=map_reference)
        self._signature: tuple[tuple[object, ...], ...] | None = None
        self._frame = osiwire.frame_layout((), host_id=None, tail=self._tail)
        self._layouts: dict[tuple[object, ...], osiwire.ObjectLayout] = {}

    def visible(self, snapshot: WorldSnapshot, ego: EntityState) -> Sequence[EntityState]:
        """The entities within the perception range of the ego (the ego always; phantoms never)."""
        phantoms = snapshot.phantoms
        if self._range is None and not phantoms:
            return snapshot.entities
        limit = self._range * self._range if self._range is not None else math.inf
        return [
            e
            for e in snapshot.entities
            if e.id == ego.id
            or (e.name not in phantoms and (e.x - ego.x) ** 2 + (e.y - ego.y) ** 2 <= limit)
        ]

    def encode(self, snapshot: WorldSnapshot, ego: EntityState) -> bytes:
        """SensorView: version(1), timestamp(2), global_ground_truth(7), host_vehicle_id(8)."""
        entities = self.visible(snapshot, ego)
        signature = tuple(map(_SIGNATURE, entities))
        if signature != self._signature:
            layouts = []
            for state, key in zip(entities, signature, strict=True):
                layout = self._layouts.get(key)
                if layout is None:
                    layout = self._layouts[key] = _object_layout(state)
                layouts.append(layout)
            self._frame = osiwire.frame_layout(layouts, host_id=ego.id, tail=self._tail)
            self._signature = signature
        values: list[float] = []
        for state in entities:
            values.extend(_kinematics(state))
        nanos = round(snapshot.time * 1e9)
        ground_truth = self._frame.encode(nanos, values)
        if self._signals is not None:
            ground_truth += self._signals.encode(snapshot.signals)
        head = osiwire.ground_truth_head(nanos=nanos)  # version and timestamp, shared layout
        return (
            head
            + osiwire.length_delimited(7, ground_truth)
            + osiwire.length_delimited(8, osiwire.identifier(ego.id))
        )


def traffic_command(*, nanos: int, ego_id: int, action_id: int, target_speed: float) -> bytes:
    """TrafficCommand with one SpeedAction: the scenario asks the ego for ``target_speed``."""
    header = osiwire.length_delimited(1, osiwire.identifier(action_id))  # ActionHeader.action_id
    speed = osiwire.length_delimited(1, header) + osiwire.double_field(2, target_speed)
    action = osiwire.length_delimited(5, speed)
    return (
        osiwire.ground_truth_head(nanos=nanos)
        + osiwire.length_delimited(3, osiwire.identifier(ego_id))
        + osiwire.length_delimited(4, action)
    )


def _order_from(
    ego: EntityState,
    dt: float,
    *,
    position: tuple[float, float, float] | None,
    velocity: tuple[float, float, float] | None,
    acceleration: tuple[float, float, float] | None,
    horizon: float,
) -> Order:
    """The engine order for a desired state ``horizon`` seconds ahead (position of the box
    centre, velocity, acceleration, each optional; the first given decides the speed)."""
    c, s = math.cos(ego.heading), math.sin(ego.heading)
    cx = ego.x + ego.box.center_x * c - ego.box.center_y * s
    cy = ego.y + ego.box.center_x * s + ego.box.center_y * c
    if velocity is not None:
        along = velocity[0] * c + velocity[1] * s
        speed = math.hypot(velocity[0], velocity[1]) if along > 0.0 else 0.0
    elif acceleration is not None:
        speed = ego.speed + (acceleration[0] * c + acceleration[1] * s) * dt
    elif position is not None:
        speed = max(((position[0] - cx) * c + (position[1] - cy) * s) / horizon, 0.0)
    else:
        raise ValueError("desired state has none of position, velocity, acceleration")
    lateral = 0.0
    if position is not None:
        lateral = (-(position[0] - cx) * s + (position[1] - cy) * c) * min(dt / horizon, 1.0)
        if abs(lateral) < LATERAL_DEADBAND:
            lateral = 0.0
    if not all(math.isfinite(v) for v in (speed, lateral)):
        raise ValueError("non-finite desired state")
    return Order(speed=speed, lateral=lateral)


def decode_motion_request(payload: bytes, ego: EntityState, *, nanos: int, dt: float) -> Order:
    """The order a MotionRequest asks for (ValueError when malformed or unusable)."""
    values = pw.message_fields(payload)
    kind = pw.integer(values, 3, DESIRED_STATE)
    if kind == DESIRED_STATE:
        state = pw.sub_message(values, 4)
        if state is None:
            raise ValueError("motion_request_type DESIRED_STATE without desired_state")
        fields = pw.message_fields(state)
        return _order_from(
            ego,
            dt,
            position=pw.vector(pw.sub_message(fields, 2)),
            velocity=pw.vector(pw.sub_message(fields, 4)),
            acceleration=pw.vector(pw.sub_message(fields, 5)),
            horizon=dt,
        )
    if kind == TRAJECTORY:
        trajectory = pw.sub_message(values, 5)
        if trajectory is None:
            raise ValueError("motion_request_type TRAJECTORY without desired_trajectory")
        for raw in pw.message_fields(trajectory).get(1, []):
            if not isinstance(raw, bytes):
                raise ValueError("trajectory_point should be a message")
            point = pw.message_fields(raw)
            when = pw.timestamp_nanos(pw.sub_message(point, 1))
            position = pw.vector(pw.sub_message(point, 2))
            if when is None or position is None:
                raise ValueError("trajectory_point without timestamp or position")
            if when > nanos:
                horizon = (when - nanos) / 1e9
                return _order_from(
                    ego, dt, position=position, velocity=None, acceleration=None, horizon=horizon
                )
        raise ValueError("desired_trajectory has no point after the current time")
    raise ValueError(f"unknown motion_request_type {kind}")


def decode_traffic_update(payload: bytes, ego: EntityState, *, dt: float) -> Order:
    """The order a TrafficUpdate (the ego's next state) implies."""
    values = pw.message_fields(payload)
    for raw in values.get(3, []):
        if not isinstance(raw, bytes):
            raise ValueError("update should be a MovingObject")
        moving = pw.message_fields(raw)
        ident = pw.sub_message(moving, 1)
        if ident is not None and pw.integer(pw.message_fields(ident), 1, -1) != ego.id:
            continue
        base = pw.sub_message(moving, 2)
        if base is None:
            raise ValueError("update of the ego without base")
        fields = pw.message_fields(base)
        return _order_from(
            ego,
            dt,
            position=pw.vector(pw.sub_message(fields, 2)),
            velocity=pw.vector(pw.sub_message(fields, 4)),
            acceleration=None,
            horizon=dt,
        )
    raise ValueError(f"TrafficUpdate has no update for the ego (id {ego.id})")
