"""OSI ground truth to ROS 2 messages and the stack's command back to a desired state.

Conventions (REP 103/105): positions are the OSI bounding-box centres in the map frame
(``map``, metres, ENU like OpenDRIVE's inertial frame), orientations quaternions from OSI's
roll/pitch/yaw. The ego's ``nav_msgs/Odometry`` has its twist in the child frame (``base_link``:
x forward, y left), as REP 105 asks; the objects of ``derived_object_msgs/ObjectArray`` carry
velocity and acceleration in the map frame (the array's ``header.frame_id``), as CARLA's ROS bridge
publishes them. Stamps are the simulation time of the step (what ``/clock`` says).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from rosbags.typesys.store import Typestore

from simtest_operator.sut.reference import Perceived
from simtest_operator.sut.ros2 import interfaces

# derived_object_msgs/Object classification
_UNKNOWN, _UNKNOWN_MEDIUM, _PEDESTRIAN, _BIKE, _CAR, _TRUCK, _MOTORCYCLE, _OTHER_VEHICLE = (
    0, 2, 4, 5, 6, 7, 8, 9,
)  # fmt: skip
_VEHICLE_CLASSES = {
    2: _CAR, 3: _CAR, 4: _CAR, 5: _CAR, 6: _CAR, 7: _TRUCK, 8: _TRUCK, 9: _TRUCK,
    10: _OTHER_VEHICLE, 11: _MOTORCYCLE, 12: _BIKE, 13: _OTHER_VEHICLE, 14: _OTHER_VEHICLE,
    15: _OTHER_VEHICLE, 16: _PEDESTRIAN,
}  # fmt: skip
"""OSI VehicleClassification.Type -> derived_object_msgs classification."""
_OBJECT_TRACKED = 1
_BOX = 1  # shape_msgs/SolidPrimitive.BOX
_CERTAIN = 255


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Frames:
    """The frame ids the messages name."""

    map: str = "map"
    base: str = "base_link"


def quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of the intrinsic Z-Y'-X'' rotation yaw, pitch, roll (OSI's and ROS's)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


class Messages:
    """Builds the bridge's ROS 2 messages (``rosbags`` instances) of one typestore."""

    def __init__(self, store: Typestore, frames: Frames = Frames()) -> None:
        self._t = store.types
        self.frames = frames

    def time(self, nanos: int) -> Any:
        seconds, rest = divmod(nanos, 1_000_000_000)
        return self._t["builtin_interfaces/msg/Time"](sec=seconds, nanosec=rest)

    def header(self, nanos: int, frame: str) -> Any:
        return self._t["std_msgs/msg/Header"](stamp=self.time(nanos), frame_id=frame)

    def clock(self, nanos: int) -> Any:
        return self._t[interfaces.CLOCK](clock=self.time(nanos))

    def float64(self, value: float) -> Any:
        return self._t[interfaces.FLOAT64](data=value)

    def _vector(self, x: float, y: float, z: float) -> Any:
        return self._t["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)

    def _pose(self, item: Perceived) -> Any:
        s = item.state
        qx, qy, qz, qw = quaternion(s.roll, s.pitch, s.heading)
        return self._t["geometry_msgs/msg/Pose"](
            position=self._t["geometry_msgs/msg/Point"](x=s.x, y=s.y, z=s.z),
            orientation=self._t["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
        )

    def odometry(self, ego: Perceived, nanos: int) -> Any:
        """The ego's odometry: pose in the map frame, twist in ``base_link``."""
        t = self._t
        c, s = math.cos(ego.state.heading), math.sin(ego.state.heading)
        twist = t["geometry_msgs/msg/Twist"](
            linear=self._vector(ego.vx * c + ego.vy * s, -ego.vx * s + ego.vy * c, 0.0),
            angular=self._vector(0.0, 0.0, 0.0),
        )
        return t[interfaces.ODOMETRY](
            header=self.header(nanos, self.frames.map),
            child_frame_id=self.frames.base,
            pose=t["geometry_msgs/msg/PoseWithCovariance"](
                pose=self._pose(ego), covariance=np.zeros(36)
            ),
            twist=t["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
        )

    def command_sample(self, ros_type: str) -> Any:
        """A zero command of ``ros_type`` (one of :data:`interfaces.COMMAND_TYPES`)."""
        t = self._t
        zero = self._vector(0.0, 0.0, 0.0)
        twist = t[interfaces.TWIST](linear=zero, angular=zero)
        if ros_type == interfaces.TWIST:
            return twist
        header = self.header(0, self.frames.base)
        if ros_type == interfaces.TWIST_STAMPED:
            return t[interfaces.TWIST_STAMPED](header=header, twist=twist)
        drive = t["ackermann_msgs/msg/AckermannDrive"](
            steering_angle=0.0, steering_angle_velocity=0.0, speed=0.0, acceleration=0.0, jerk=0.0
        )
        return t[interfaces.ACKERMANN](header=header, drive=drive)

    def objects(self, others: Sequence[Perceived], nanos: int) -> Any:
        """Every other object as a tracked, classified ``derived_object_msgs/Object``."""
        t = self._t
        header = self.header(nanos, self.frames.map)
        items = []
        for item in others:
            box = item.state.box
            items.append(
                t["derived_object_msgs/msg/Object"](
                    header=header,
                    id=item.state.id & 0xFFFFFFFF,
                    detection_level=_OBJECT_TRACKED,
                    object_classified=True,
                    pose=self._pose(item),
                    twist=t["geometry_msgs/msg/Twist"](
                        linear=self._vector(item.vx, item.vy, 0.0),
                        angular=self._vector(0.0, 0.0, 0.0),
                    ),
                    accel=t["geometry_msgs/msg/Accel"](
                        linear=self._vector(item.ax, item.ay, 0.0),
                        angular=self._vector(0.0, 0.0, 0.0),
                    ),
                    polygon=t["geometry_msgs/msg/Polygon"](points=[]),
                    shape=t["shape_msgs/msg/SolidPrimitive"](
                        type=_BOX,
                        dimensions=np.array([box.length, box.width, box.height]),
                        polygon=t["geometry_msgs/msg/Polygon"](points=[]),
                    ),
                    classification=classification(item),
                    classification_certainty=_CERTAIN,
                    classification_age=0,
                )
            )
        return t[interfaces.OBJECT_ARRAY](header=header, objects=items)


def classification(item: Perceived) -> int:
    """The derived_object_msgs classification of an OSI moving object."""
    if item.object_type == 2:
        return _VEHICLE_CLASSES.get(item.vehicle_class, _OTHER_VEHICLE)
    if item.object_type == 3:
        return _PEDESTRIAN
    if item.object_type == 4:
        return _UNKNOWN_MEDIUM
    return _UNKNOWN


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Command:
    """What the stack asked for, in the bridge's terms."""

    stamp: int | None
    """Its header stamp (ns of simulation time), None for an unstamped type."""
    speed: float
    """Desired speed (m/s, forward)."""
    acceleration: float
    """Limit on the speed change (m/s^2, absolute); 0: reach ``speed`` at once."""
    yaw_rate: float
    """Desired yaw rate (rad/s, left positive)."""


def command(message: Any, ros_type: str, *, wheelbase: float) -> Command:
    """A command message (one of :data:`interfaces.COMMAND_TYPES`) as a :class:`Command`."""
    if ros_type == interfaces.ACKERMANN:
        drive = message.drive
        speed = float(drive.speed)
        return Command(
            stamp=_nanos(message.header.stamp),
            speed=speed,
            acceleration=abs(float(drive.acceleration)),
            yaw_rate=speed * math.tan(float(drive.steering_angle)) / wheelbase,
        )
    if ros_type in (interfaces.TWIST, interfaces.TWIST_STAMPED):
        stamped = ros_type == interfaces.TWIST_STAMPED
        twist = message.twist if stamped else message
        return Command(
            stamp=_nanos(message.header.stamp) if stamped else None,
            speed=float(twist.linear.x),
            acceleration=0.0,
            yaw_rate=float(twist.angular.z),
        )
    raise ValueError(f"unsupported command type {ros_type}")


def _nanos(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def next_motion(current_speed: float, wanted: Command, dt: float) -> tuple[float, float]:
    """(speed at t + dt, lateral displacement over the step) the command asks for: the speed
    moves toward the wanted one within its acceleration limit (none: at once; reverse is not
    driven, so it stops), the yaw rate turns the step's path by ``yaw_rate * dt`` (a circular
    arc's sideways offset at its end; the simulator keeps the ego on its lane's path otherwise)."""
    target = wanted.speed
    if wanted.acceleration > 0.0:
        step = wanted.acceleration * dt
        target = current_speed + min(max(target - current_speed, -step), step)
    speed = max(target, 0.0)
    travelled = (current_speed + speed) / 2.0 * dt
    lateral = travelled * math.sin(wanted.yaw_rate * dt / 2.0)
    if not all(math.isfinite(v) for v in (speed, lateral)):
        raise ValueError("the command is not finite")
    return speed, lateral
