"""A small ROS 2-style "stack" for the bridge's tests: an independent DDS participant.

It knows nothing of the bridge: its DDS types are written out here as ``idlc`` would generate them
from the ROS 2 ``.idl`` files (module ``pkg::msg::dds_``, struct ``Type_``), payloads are
``rosbags``' CDR, topics follow ROS 2's ``rt/`` naming and QoS its rmw profiles. Its logic is the
reference SUT's: the driver model (IDM + ACC + AEB) on the nearest object ahead, fed from the ego's
``nav_msgs/Odometry``, the ``derived_object_msgs/ObjectArray`` and the set speed on a latched
``std_msgs/Float64``; it answers each odometry with an ``ackermann_msgs/AckermannDriveStamped``
stamped with the odometry's time (the ``/clock`` time under ``use_sim_time``).

    python tests/sut/ros2_stack.py --domain-id 17 [--command-type geometry_msgs/msg/Twist]

Runs until SIGTERM; a clock that goes back starts a new run (the next scenario).
"""

import argparse
import dataclasses
import json
import math
import signal
import sys
from collections.abc import Sequence
from typing import Any

import numpy
from cyclonedds._clayer import ddspy_take, ddspy_write
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct, types
from cyclonedds.idl.types import float32, float64, int32, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from simtest_operator.drivermodel import DriverModel, SutConfig
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState
from simtest_operator.sut.reference import Perceived, leader

# --- the DDS types, as idlc generates them from the ROS 2 interfaces ---------------------------


class Time(IdlStruct, typename="builtin_interfaces.msg.dds_.Time_"):
    sec: int32
    nanosec: uint32


class Header(IdlStruct, typename="std_msgs.msg.dds_.Header_"):
    stamp: Time
    frame_id: str


class Point(IdlStruct, typename="geometry_msgs.msg.dds_.Point_"):
    x: float64
    y: float64
    z: float64


class Point32(IdlStruct, typename="geometry_msgs.msg.dds_.Point32_"):
    x: float32
    y: float32
    z: float32


class Vector3(IdlStruct, typename="geometry_msgs.msg.dds_.Vector3_"):
    x: float64
    y: float64
    z: float64


class Quaternion(IdlStruct, typename="geometry_msgs.msg.dds_.Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


class Pose(IdlStruct, typename="geometry_msgs.msg.dds_.Pose_"):
    position: Point
    orientation: Quaternion


class Twist(IdlStruct, typename="geometry_msgs.msg.dds_.Twist_"):
    linear: Vector3
    angular: Vector3


class Accel(IdlStruct, typename="geometry_msgs.msg.dds_.Accel_"):
    linear: Vector3
    angular: Vector3


class Polygon(IdlStruct, typename="geometry_msgs.msg.dds_.Polygon_"):
    points: types.sequence[Point32]


class PoseWithCovariance(IdlStruct, typename="geometry_msgs.msg.dds_.PoseWithCovariance_"):
    pose: Pose
    covariance: types.array[float64, 36]


class TwistWithCovariance(IdlStruct, typename="geometry_msgs.msg.dds_.TwistWithCovariance_"):
    twist: Twist
    covariance: types.array[float64, 36]


class Odometry(IdlStruct, typename="nav_msgs.msg.dds_.Odometry_"):
    header: Header
    child_frame_id: str
    pose: PoseWithCovariance
    twist: TwistWithCovariance


class SolidPrimitive(IdlStruct, typename="shape_msgs.msg.dds_.SolidPrimitive_"):
    type: uint8
    dimensions: types.sequence[float64, 3]
    polygon: Polygon


class Object(IdlStruct, typename="derived_object_msgs.msg.dds_.Object_"):
    header: Header
    id: uint32
    detection_level: uint8
    object_classified: bool
    pose: Pose
    twist: Twist
    accel: Accel
    polygon: Polygon
    shape: SolidPrimitive
    classification: uint8
    classification_certainty: uint8
    classification_age: uint32


class ObjectArray(IdlStruct, typename="derived_object_msgs.msg.dds_.ObjectArray_"):
    header: Header
    objects: types.sequence[Object]


class Float64(IdlStruct, typename="std_msgs.msg.dds_.Float64_"):
    data: float64


class AckermannDrive(IdlStruct, typename="ackermann_msgs.msg.dds_.AckermannDrive_"):
    steering_angle: float32
    steering_angle_velocity: float32
    speed: float32
    acceleration: float32
    jerk: float32


class AckermannDriveStamped(IdlStruct, typename="ackermann_msgs.msg.dds_.AckermannDriveStamped_"):
    header: Header
    drive: AckermannDrive


# --- rosbags for the payloads ------------------------------------------------------------------

ACKERMANN_MSGS = {
    "ackermann_msgs/msg/AckermannDrive": (
        "float32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\n"
        "float32 acceleration\nfloat32 jerk\n"
    ),
    "ackermann_msgs/msg/AckermannDriveStamped": (
        "std_msgs/Header header\nackermann_msgs/AckermannDrive drive\n"
    ),
    "derived_object_msgs/msg/Object": (
        "std_msgs/Header header\nuint32 id\nuint8 detection_level\nbool object_classified\n"
        "geometry_msgs/Pose pose\ngeometry_msgs/Twist twist\ngeometry_msgs/Accel accel\n"
        "geometry_msgs/Polygon polygon\nshape_msgs/SolidPrimitive shape\nuint8 classification\n"
        "uint8 classification_certainty\nuint32 classification_age\n"
    ),
    "derived_object_msgs/msg/ObjectArray": (
        "std_msgs/Header header\nderived_object_msgs/Object[] objects\n"
    ),
}
STORE = get_typestore(Stores.ROS2_JAZZY)
for _name, _text in ACKERMANN_MSGS.items():
    STORE.register(get_types_from_msg(_text, _name))

ANY = SampleState.Any | ViewState.Any | InstanceState.Any
SENSOR = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5))
COMMAND = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.Volatile,
    Policy.History.KeepLast(10),
)
LATCHED = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.TransientLocal,
    Policy.History.KeepLast(1),
)


def take(reader: DataReader[Any], ros_type: str) -> list[Any]:
    taken = ddspy_take(reader._ref, ANY, 64)
    return [STORE.deserialize_cdr(bytes(d), ros_type) for d, info in taken if info.valid_data]


def publish(writer: DataWriter[Any], message: Any, ros_type: str) -> None:
    payload = bytes(STORE.serialize_cdr(message, ros_type))
    assert ddspy_write(writer._ref, payload + b"\0" * (-len(payload) % 4)) >= 0


def zero(ros_type: str) -> Any:
    """A message of ``ros_type`` with every field zero or empty."""
    _, fields = STORE.fielddefs[ros_type]
    values = {}
    for name, (kind, detail) in fields:
        if int(kind) == 2:  # a nested message
            values[name] = zero(detail)
        elif int(kind) == 1:  # a base type
            values[name] = "" if detail[0] == "string" else False if detail[0] == "bool" else 0
        elif int(kind) == 3:  # a fixed array of numbers (covariances)
            values[name] = numpy.zeros(detail[1])
        else:  # a sequence
            values[name] = []
    return STORE.types[ros_type](**values)


def warm_up(*ros_types: str) -> None:
    """rosbags compiles a type's codec on first use (0.1 s or more): do it before the first step."""
    for ros_type in ros_types:
        STORE.deserialize_cdr(STORE.serialize_cdr(zero(ros_type), ros_type), ros_type)


def yaw_of(q: Any) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def perceived(ident: int, pose: Any, vx: float, vy: float, box: BoundingBox) -> Perceived:
    p = pose.position
    state = EntityState(
        id=ident,
        name=str(ident),
        kind=EntityKind.VEHICLE,
        category="car",
        x=p.x,
        y=p.y,
        z=p.z,
        heading=yaw_of(pose.orientation),
        speed=math.hypot(vx, vy),
        box=box,
    )
    return Perceived(state=state, vx=vx, vy=vy)


@dataclasses.dataclass
class Stack:
    config: SutConfig
    ego_box: BoundingBox
    step: int
    """Nanoseconds from one step to the next."""
    model: DriverModel | None = None
    target: float | None = None
    last: int = -1
    new_target: float | None = None
    objects: dict[int, Any] = dataclasses.field(default_factory=dict)

    def decide(self, odometry: Any, dt: float) -> tuple[int, float]:
        """(stamp, speed at t + dt) for one odometry, as the reference SUT decides."""
        stamp = odometry.header.stamp
        nanos = stamp.sec * 1_000_000_000 + stamp.nanosec
        if self.is_new_run(nanos):  # not the step after the last: the next scenario
            self.model, self.target = None, self.new_target
        self.new_target = None
        self.last = nanos
        lin = odometry.twist.twist.linear
        yaw = yaw_of(odometry.pose.pose.orientation)
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = lin.x * c - lin.y * s, lin.x * s + lin.y * c
        ego = perceived(0, odometry.pose.pose, vx, vy, self.ego_box)
        ego = dataclasses.replace(
            ego, state=dataclasses.replace(ego.state, speed=math.hypot(lin.x, lin.y))
        )
        array = self.objects.pop(nanos)
        others = [
            perceived(
                o.id,
                o.pose,
                o.twist.linear.x,
                o.twist.linear.y,
                BoundingBox(
                    length=o.shape.dimensions[0],
                    width=o.shape.dimensions[1],
                    height=o.shape.dimensions[2],
                ),
            )
            for o in array.objects
        ]
        speed = ego.state.speed
        if self.model is None:
            start = self.target if self.target is not None else speed
            self.model = DriverModel(self.config, set_speed=start)
            print(
                f"stack: run from t={nanos / 1e9:.3f} s, set speed {start:.2f} m/s",
                file=sys.stderr,
                flush=True,
            )
        command = self.model.command(
            speed=speed, leader=leader(ego, others, self.config.sensor_range)
        )
        return nanos, max(speed + command.acceleration * dt, 0.0)

    def is_new_run(self, nanos: int) -> bool:
        return self.last >= 0 and abs(nanos - self.last - self.step) > self.step // 2

    def set_target(self, value: float, nanos: int) -> None:
        """A set speed that arrived with the odometry of ``nanos`` (it was sent before it)."""
        if self.is_new_run(nanos):  # the first of a new run: decide() starts the model with it
            self.new_target = value
        elif self.model is None:
            self.target = value
        else:
            self.model.set_speed = value


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--domain-id", type=int, required=True)
    parser.add_argument("--step", type=float, default=0.05)
    parser.add_argument("--driver-model", default="{}", help="SutConfig fields as JSON")
    parser.add_argument("--ego-length", type=float, default=4.5)
    parser.add_argument("--ego-width", type=float, default=1.8)
    parser.add_argument("--ego-height", type=float, default=1.5)
    parser.add_argument("--command-type", default="ackermann_msgs/msg/AckermannDriveStamped")
    args = parser.parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))

    participant = DomainParticipant(args.domain_id)

    def reader(name: str, kind: type, qos: Qos) -> DataReader[Any]:
        return DataReader(participant, Topic(participant, "rt" + name, kind), qos=qos)

    odometry = reader("/simtest/ego/odometry", Odometry, SENSOR)
    objects = reader("/simtest/objects", ObjectArray, SENSOR)
    targets = reader("/simtest/ego/target_speed", Float64, LATCHED)
    twist = args.command_type == "geometry_msgs/msg/Twist"
    command_kind = Twist if twist else AckermannDriveStamped
    command = DataWriter(
        participant, Topic(participant, "rt/simtest/ego/command", command_kind), qos=COMMAND
    )
    waitset = WaitSet(participant)
    waitset.attach(ReadCondition(odometry, ANY))
    stack = Stack(
        config=SutConfig(**json.loads(args.driver_model)),
        ego_box=BoundingBox(length=args.ego_length, width=args.ego_width, height=args.ego_height),
        step=round(args.step * 1e9),
    )
    arrived = WaitSet(participant)
    arrived.attach(ReadCondition(objects, ANY))

    def collect_objects() -> None:
        for array in take(objects, "derived_object_msgs/msg/ObjectArray"):
            stamp = array.header.stamp
            stack.objects[stamp.sec * 1_000_000_000 + stamp.nanosec] = array

    t = STORE.types
    warm_up(
        "nav_msgs/msg/Odometry",
        "derived_object_msgs/msg/ObjectArray",
        "std_msgs/msg/Float64",
        args.command_type,
    )
    print("stack: up", flush=True)
    while True:
        waitset.wait(duration(seconds=1))
        for odom in take(odometry, "nav_msgs/msg/Odometry"):
            stamp = odom.header.stamp
            now = stamp.sec * 1_000_000_000 + stamp.nanosec
            collect_objects()
            while now not in stack.objects:  # sent before the odometry; may be a moment behind
                arrived.wait(duration(seconds=1))
                collect_objects()
            for value in take(targets, "std_msgs/msg/Float64"):
                stack.set_target(value.data, now)
            nanos, speed = stack.decide(odom, args.step)
            if twist:
                zero = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
                message = t["geometry_msgs/msg/Twist"](
                    linear=t["geometry_msgs/msg/Vector3"](x=speed, y=0.0, z=0.0), angular=zero
                )
                publish(command, message, "geometry_msgs/msg/Twist")
                continue
            seconds, rest = divmod(nanos, 1_000_000_000)
            message = t["ackermann_msgs/msg/AckermannDriveStamped"](
                header=t["std_msgs/msg/Header"](
                    stamp=t["builtin_interfaces/msg/Time"](sec=seconds, nanosec=rest),
                    frame_id="base_link",
                ),
                drive=t["ackermann_msgs/msg/AckermannDrive"](
                    steering_angle=0.0,
                    steering_angle_velocity=0.0,
                    speed=speed,
                    acceleration=0.0,
                    jerk=0.0,
                ),
            )
            publish(command, message, "ackermann_msgs/msg/AckermannDriveStamped")


if __name__ == "__main__":
    raise SystemExit(main())
