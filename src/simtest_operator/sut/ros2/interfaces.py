"""The ROS 2 interfaces the bridge speaks: message types (a ``rosbags`` typestore with the two
packages it lacks registered), ROS 2's DDS naming, and the QoS profiles of ROS 2's ``rmw``.

ROS 2 maps a topic ``/a/b`` to the DDS topic ``rt/a/b`` and a message type ``pkg/msg/Type`` to
the DDS type ``pkg::msg::dds_::Type_`` (rmw's naming, the same for every RMW). Payloads are CDR
with the 4-byte encapsulation header, exactly what ``rosbags`` serialises.

Message packages: ``nav_msgs``, ``geometry_msgs``, ``rosgraph_msgs`` and ``std_msgs`` ship with
ROS 2 and with ``rosbags``' Jazzy store. ``ackermann_msgs`` (ros2/common_interfaces' sibling,
what CARLA's and F1TENTH's stacks take) and ``derived_object_msgs`` (the object list CARLA's ROS
bridge publishes as ground truth) do not ship with rosbags: their definitions below are copied
field for field from the packages' ``.msg`` files (constants included, since they name values),
and registered into the store.
"""

from __future__ import annotations

import dataclasses
import enum
import functools

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

ACKERMANN_DRIVE = """\
float32 steering_angle
float32 steering_angle_velocity
float32 speed
float32 acceleration
float32 jerk
"""

ACKERMANN_DRIVE_STAMPED = """\
std_msgs/Header header
ackermann_msgs/AckermannDrive drive
"""

DERIVED_OBJECT = """\
std_msgs/Header header
uint32 id
uint8 detection_level
uint8 OBJECT_DETECTED=0
uint8 OBJECT_TRACKED=1
bool object_classified
geometry_msgs/Pose pose
geometry_msgs/Twist twist
geometry_msgs/Accel accel
geometry_msgs/Polygon polygon
shape_msgs/SolidPrimitive shape
uint8 classification
uint8 CLASSIFICATION_UNKNOWN=0
uint8 CLASSIFICATION_UNKNOWN_SMALL=1
uint8 CLASSIFICATION_UNKNOWN_MEDIUM=2
uint8 CLASSIFICATION_UNKNOWN_BIG=3
uint8 CLASSIFICATION_PEDESTRIAN=4
uint8 CLASSIFICATION_BIKE=5
uint8 CLASSIFICATION_CAR=6
uint8 CLASSIFICATION_TRUCK=7
uint8 CLASSIFICATION_MOTORCYCLE=8
uint8 CLASSIFICATION_OTHER_VEHICLE=9
uint8 CLASSIFICATION_BARRIER=10
uint8 CLASSIFICATION_SIGN=11
uint8 classification_certainty
uint32 classification_age
"""

DERIVED_OBJECT_ARRAY = """\
std_msgs/Header header
derived_object_msgs/Object[] objects
"""

_EXTRA = {
    "ackermann_msgs/msg/AckermannDrive": ACKERMANN_DRIVE,
    "ackermann_msgs/msg/AckermannDriveStamped": ACKERMANN_DRIVE_STAMPED,
    "derived_object_msgs/msg/Object": DERIVED_OBJECT,
    "derived_object_msgs/msg/ObjectArray": DERIVED_OBJECT_ARRAY,
}

ODOMETRY = "nav_msgs/msg/Odometry"
OBJECT_ARRAY = "derived_object_msgs/msg/ObjectArray"
CLOCK = "rosgraph_msgs/msg/Clock"
FLOAT64 = "std_msgs/msg/Float64"
ACKERMANN = "ackermann_msgs/msg/AckermannDriveStamped"
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
COMMAND_TYPES = (ACKERMANN, TWIST, TWIST_STAMPED)
"""The command messages the bridge turns into a MotionRequest."""


@functools.cache
def typestore() -> Typestore:
    """ROS 2 Jazzy's message types plus ``ackermann_msgs`` and ``derived_object_msgs``."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for name, text in _EXTRA.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def dds_topic(name: str) -> str:
    """``/ego/odom`` -> ``rt/ego/odom`` (ROS 2 topics live under the ``rt`` prefix in DDS)."""
    if not name.startswith("/") or name.endswith("/") or "//" in name:
        raise ValueError(f"ROS 2 topic {name!r} must be absolute (/a/b), without empty parts")
    return "rt" + name


def dds_type(ros_type: str) -> str:
    """``nav_msgs/msg/Odometry`` -> ``nav_msgs::msg::dds_::Odometry_``."""
    package, kind, name = _split(ros_type)
    return f"{package}::{kind}::dds_::{name}_"


def _split(ros_type: str) -> tuple[str, str, str]:
    parts = ros_type.split("/")
    if len(parts) != 3 or not all(parts):
        raise ValueError(f"ROS 2 type {ros_type!r} is not package/msg/Type")
    return parts[0], parts[1], parts[2]


class Reliability(enum.StrEnum):
    BEST_EFFORT = "best_effort"
    RELIABLE = "reliable"


class Durability(enum.StrEnum):
    VOLATILE = "volatile"
    TRANSIENT_LOCAL = "transient_local"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class QosProfile:
    """The QoS a ROS 2 profile sets (history is always KEEP_LAST with ``depth``)."""

    reliability: Reliability
    durability: Durability
    depth: int

    def describe(self) -> str:
        return f"{self.reliability}, keep last {self.depth}, {self.durability}"


SENSOR_DATA = QosProfile(
    reliability=Reliability.BEST_EFFORT, durability=Durability.VOLATILE, depth=5
)
"""``rmw_qos_profile_sensor_data`` (rclcpp ``SensorDataQoS``)."""
DEFAULT = QosProfile(reliability=Reliability.RELIABLE, durability=Durability.VOLATILE, depth=10)
"""``rmw_qos_profile_default`` (rclcpp ``QoS(10)``): what a command topic uses."""
CLOCK_QOS = QosProfile(reliability=Reliability.BEST_EFFORT, durability=Durability.VOLATILE, depth=1)
"""rclcpp ``ClockQoS``: how nodes with ``use_sim_time`` subscribe to ``/clock``."""
LATCHED = QosProfile(
    reliability=Reliability.RELIABLE, durability=Durability.TRANSIENT_LOCAL, depth=1
)
"""A "latched" topic (rclcpp ``QoS(1).transient_local()``): a late subscriber gets the value."""
