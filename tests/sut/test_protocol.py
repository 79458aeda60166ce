"""The SUT protocol's frames and OSI messages: what the simulator sends decodes with betterosi
(an independent OSI implementation) to the values it encodes; what a SUT answers, built with
betterosi, decodes to the right order; malformed input is refused with a reason."""

from __future__ import annotations

import math
import socket

import betterosi
import pytest

from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, WorldSnapshot
from simtest_operator.sut import framing, messages, protowire, reference
from simtest_operator.sut.errors import SutError, SutProtocolError
from simtest_operator.sut.framing import Kind

EGO = EntityState(
    id=0, name="Ego", kind=EntityKind.VEHICLE, category="car", x=10.0, y=5.0,
    heading=0.3, speed=20.0, box=BoundingBox(center_x=1.4, length=4.5, width=1.8),
)  # fmt: skip
LEAD = EntityState(
    id=1, name="Lead", kind=EntityKind.VEHICLE, category="truck", x=60.0, y=20.0,
    heading=0.3, speed=12.0, box=BoundingBox(center_x=2.0, length=8.0, width=2.5),
)  # fmt: skip
FAR = EntityState(id=2, name="Far", kind=EntityKind.PEDESTRIAN, category="", x=900.0, y=0.0)
SNAPSHOT = WorldSnapshot(time=1.25, entities=(EGO, LEAD, FAR))


def pair() -> tuple[socket.socket, socket.socket]:
    return socket.socketpair()


def test_frames_round_trip_with_header_fields() -> None:
    a, b = pair()
    with a, b:
        framing.send(a, Kind.SENSOR_VIEW, 7, b"payload")
        frame = framing.receive(b)
    assert (frame.kind, frame.sequence, frame.payload) == (Kind.SENSOR_VIEW, 7, b"payload")
    assert framing.encode(Kind.GOODBYE, 3)[:4] == b"OSUT"


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        (b"XXXX" + bytes(12), "does not start with"),
        (framing.HEADER.pack(b"OSUT", 2, 5, 0, 0), "protocol version 2"),
        (framing.HEADER.pack(b"OSUT", 1, 99, 0, 0), "unknown frame kind 99"),
        (framing.HEADER.pack(b"OSUT", 1, 5, 0, framing.MAX_PAYLOAD + 1), "exceeds"),
    ],
)
def test_bad_headers_are_refused_with_the_reason(raw: bytes, message: str) -> None:
    a, b = pair()
    with a, b:
        a.sendall(raw)
        with pytest.raises(SutProtocolError, match=message):
            framing.receive(b)


def test_a_closed_connection_mid_frame_is_a_sut_error() -> None:
    a, b = pair()
    with b:
        a.sendall(framing.encode(Kind.MOTION_REQUEST, 1, b"12345")[:-2])
        a.close()
        with pytest.raises(SutError, match="closed the connection"):
            framing.receive(b)


def test_sensor_view_decodes_with_betterosi_and_honours_the_perception_range() -> None:
    encoder = messages.SensorViewEncoder(perception_range=200.0)
    view = betterosi.SensorView.from_binary(encoder.encode(SNAPSHOT, EGO))
    assert view.host_vehicle_id.value == 0
    assert (view.timestamp.seconds, view.timestamp.nanos) == (1, 250_000_000)
    truth = view.global_ground_truth
    assert truth.host_vehicle_id.value == 0
    assert [o.id.value for o in truth.moving_object] == [0, 1]  # Far is out of range
    ego = truth.moving_object[0].base
    assert ego.position.x == pytest.approx(10.0 + 1.4 * math.cos(0.3))
    assert ego.position.y == pytest.approx(5.0 + 1.4 * math.sin(0.3))
    assert ego.orientation.yaw == pytest.approx(0.3)
    assert ego.velocity.x == pytest.approx(20.0 * math.cos(0.3))
    assert (ego.dimension.length, ego.dimension.width) == (4.5, 1.8)
    everything = messages.SensorViewEncoder(perception_range=None).encode(SNAPSHOT, EGO)
    assert len(betterosi.SensorView.from_binary(everything).global_ground_truth.moving_object) == 3


@pytest.mark.parametrize("perception_range", [None, 200.0])
def test_phantoms_are_recorded_but_never_perceived(perception_range: float | None) -> None:
    # esmini's ghosts drive ahead of their entities: no system under test may see them
    haunted = WorldSnapshot(time=1.25, entities=(EGO, LEAD, FAR), phantoms=frozenset({"Lead"}))
    encoder = messages.SensorViewEncoder(perception_range=perception_range)
    truth = betterosi.SensorView.from_binary(encoder.encode(haunted, EGO)).global_ground_truth
    assert 1 not in [o.id.value for o in truth.moving_object]
    assert 0 in [o.id.value for o in truth.moving_object]


def test_reference_parser_reads_what_the_encoder_writes() -> None:
    payload = messages.SensorViewEncoder(perception_range=None).encode(SNAPSHOT, EGO)
    nanos, host, objects = reference.parse_sensor_view(payload)
    assert (nanos, host, [o.state.id for o in objects]) == (1_250_000_000, 0, [0, 1, 2])
    assert objects[1].state.box.length == 8.0
    assert objects[1].state.speed == pytest.approx(12.0)


def test_traffic_command_decodes_with_betterosi() -> None:
    raw = messages.traffic_command(nanos=2_000_000_000, ego_id=4, action_id=9, target_speed=13.5)
    command = betterosi.TrafficCommand.from_binary(raw)
    assert command.traffic_participant_id.value == 4
    action = command.action[0].speed_action
    assert action.absolute_target_speed == 13.5
    assert action.action_header.action_id.value == 9
    assert reference.parse_target_speed(raw, 4) == 13.5
    assert reference.parse_target_speed(raw, 5) is None


def test_reference_motion_request_decodes_with_betterosi_and_back_to_the_order() -> None:
    raw = reference.motion_request(
        nanos=1_300_000_000, position=(11.0, 5.0), yaw=0.0, speed=21.0, acceleration=2.0
    )
    request = betterosi.MotionRequest.from_binary(raw)
    assert request.desired_state.velocity.x == 21.0
    assert request.desired_state.acceleration.x == 2.0
    order = messages.decode_motion_request(raw, EGO, nanos=1_250_000_000, dt=0.05)
    assert order.speed == pytest.approx(21.0)


def test_desired_state_velocity_sets_speed_and_position_steers() -> None:
    c, s = math.cos(0.3), math.sin(0.3)
    cx, cy = 10.0 + 1.4 * c, 5.0 + 1.4 * s
    state = betterosi.MotionRequest(
        motion_request_type=betterosi.MotionRequest.MotionRequestType(0),
        desired_state=betterosi.MotionRequest.DesiredState(
            # one metre ahead and 0.2 m to the left of the box centre
            position=betterosi.Vector3d(x=cx + c - 0.2 * s, y=cy + s + 0.2 * c, z=0.0),
            velocity=betterosi.Vector3d(x=18.0 * c, y=18.0 * s, z=0.0),
        ),
    ).to_binary()
    order = messages.decode_motion_request(state, EGO, nanos=0, dt=0.05)
    assert order.speed == pytest.approx(18.0)
    assert order.lateral == pytest.approx(0.2)


def test_trajectory_uses_the_first_point_after_now() -> None:
    c, s = math.cos(0.3), math.sin(0.3)
    cx, cy = 10.0 + 1.4 * c, 5.0 + 1.4 * s

    def point(t: float, d: float) -> betterosi.StatePoint:
        seconds, nanos = divmod(round(t * 1e9), 1_000_000_000)
        return betterosi.StatePoint(
            timestamp=betterosi.Timestamp(seconds=seconds, nanos=nanos),
            position=betterosi.Vector3d(x=cx + d * c, y=cy + d * s, z=0.0),
        )

    raw = betterosi.MotionRequest(
        motion_request_type=betterosi.MotionRequest.MotionRequestType(1),
        desired_trajectory=betterosi.MotionRequest.DesiredTrajectory(
            trajectory_point=[point(1.0, -5.0), point(1.5, 4.0), point(2.0, 9.0)]
        ),
    ).to_binary()
    order = messages.decode_motion_request(raw, EGO, nanos=1_250_000_000, dt=0.05)
    assert order.speed == pytest.approx(16.0)  # 4 m in 0.25 s
    assert order.lateral == 0.0


def test_traffic_update_gives_the_ego_its_next_speed() -> None:
    raw = betterosi.TrafficUpdate(
        update=[
            betterosi.MovingObject(
                id=betterosi.Identifier(value=0),
                base=betterosi.BaseMoving(
                    velocity=betterosi.Vector3d(x=3.0 * math.cos(0.3), y=3.0 * math.sin(0.3), z=0)
                ),
            )
        ]
    ).to_binary()
    assert messages.decode_traffic_update(raw, EGO, dt=0.05).speed == pytest.approx(3.0)
    with pytest.raises(ValueError, match="no update for the ego"):
        messages.decode_traffic_update(raw, LEAD, dt=0.05)


@pytest.mark.parametrize(
    ("payload", "message"),
    [
        (b"\x18\x00", "without desired_state"),
        (b"\x18\x07", "unknown motion_request_type 7"),
        (b"\x22\x10\x00", "claims 16 bytes"),
        (b"\x18", "truncated varint"),
        (b"\x18\x01*\x00", "no point after"),
        (b"\x22\x00", "none of position, velocity, acceleration"),
        (b"\x1b", "unsupported wire type 3"),
    ],
)
def test_malformed_motion_requests_are_refused(payload: bytes, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        messages.decode_motion_request(payload, EGO, nanos=0, dt=0.05)


def test_protowire_rejects_overlong_varints() -> None:
    with pytest.raises(ValueError, match="longer than 10 bytes"):
        protowire.read_varint(b"\xff" * 11, 0)
