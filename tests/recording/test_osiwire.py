"""Hand-rolled OSI wire encoding against betterosi: a GroundTruth packed through a precompiled
frame layout decodes with betterosi to the same values (ids, type, classification, dimension,
pose, velocity, acceleration, version, timestamp, host id, country code, map reference, projection
offset) and is byte-identical to betterosi's own serialisation, also for a frame without objects
or host; the MapAsamOpenDrive message; varints of one to six bytes; the trimmed descriptor set
keeps exactly GroundTruth's and MapAsamOpenDrive's dependencies."""

from __future__ import annotations

import betterosi
import pytest

from simtest_operator.recording import descriptors, osiwire

osi = betterosi.v3_7_0


def build_with_betterosi() -> bytes:
    mo = osi.MovingObject
    vc = mo.VehicleClassification
    objects = [
        mo(
            id=osi.Identifier(value=object_id),
            base=osi.BaseMoving(
                dimension=osi.Dimension3d(length=4.5, width=1.8, height=1.5),
                position=osi.Vector3d(x=1.5 + object_id, y=-2.25, z=0.75),
                orientation=osi.Orientation3d(roll=0.0, pitch=0.01, yaw=-3.0),
                velocity=osi.Vector3d(x=12.0, y=-0.5, z=0.0),
                acceleration=osi.Vector3d(x=0.0, y=0.0, z=0.0),
            ),
            type=mo.Type.VEHICLE,
            vehicle_classification=vc(
                type=vc.Type.HEAVY_TRUCK, has_trailer=False, role=vc.Role.CIVIL
            ),
        )
        for object_id in (0, 300)
    ]
    return bytes(
        osi.GroundTruth(
            version=osi.InterfaceVersion(version_major=3, version_minor=7, version_patch=0),
            timestamp=osi.Timestamp(seconds=12, nanos=350_000_000),
            host_vehicle_id=osi.Identifier(value=0),
            moving_object=objects,
            country_code=276,
            map_reference="road",
            proj_frame_offset=osi.GroundTruth.ProjFrameOffset(
                position=osi.Vector3d(x=0.0, y=0.0, z=0.0), yaw=0.0
            ),
        ).to_binary()
    )


def build_by_hand() -> bytes:
    layouts = [
        osiwire.object_layout(
            object_id=object_id,
            object_type=2,
            dimension=(4.5, 1.8, 1.5),
            classification_type=7,
            classification_role=2,
        )
        for object_id in (0, 300)
    ]
    tail = osiwire.ground_truth_tail(country_code=276, map_reference="road")
    frame = osiwire.frame_layout(layouts, host_id=0, tail=tail)
    values = [
        value
        for object_id in (0, 300)
        for value in (1.5 + object_id, -2.25, 0.75, 0.0, 0.01, -3.0, 12.0, -0.5, 0.0, 0.0)
    ]
    assert len(values) == frame.objects * osiwire.DYNAMIC_VALUES
    return frame.encode(12_350_000_000, values)


def test_ground_truth_is_byte_identical_to_betterosi() -> None:
    assert build_by_hand() == build_with_betterosi()


def test_ground_truth_decodes_with_betterosi() -> None:
    gt = osi.GroundTruth.from_binary(build_by_hand())
    assert (gt.version.version_major, gt.version.version_minor, gt.version.version_patch) == (
        3,
        7,
        0,
    )
    assert (gt.timestamp.seconds, gt.timestamp.nanos) == (12, 350_000_000)
    assert gt.host_vehicle_id.value == 0
    assert gt.country_code == 276
    assert gt.map_reference == "road"
    assert [mv.id.value for mv in gt.moving_object] == [0, 300]
    truck = gt.moving_object[1]
    assert truck.type == osi.MovingObject.Type.VEHICLE
    assert (
        truck.vehicle_classification.type == osi.MovingObject.VehicleClassification.Type.HEAVY_TRUCK
    )
    assert truck.vehicle_classification.has_trailer is False
    assert (truck.base.position.x, truck.base.position.y, truck.base.position.z) == (
        301.5,
        -2.25,
        0.75,
    )
    assert truck.base.orientation.yaw == -3.0
    assert truck.base.orientation.pitch == 0.01
    assert truck.base.dimension.height == 1.5


def test_frame_without_objects_or_host() -> None:
    tail = osiwire.ground_truth_tail(country_code=276, map_reference="road")
    data = osiwire.frame_layout((), host_id=None, tail=tail).encode(2_000_000_123, [])
    gt = osi.GroundTruth.from_binary(data)
    assert (gt.timestamp.seconds, gt.timestamp.nanos) == (2, 123)
    assert gt.moving_object == []
    assert gt.map_reference == "road"
    assert data == bytes(
        osi.GroundTruth(
            version=osi.InterfaceVersion(version_major=3, version_minor=7, version_patch=0),
            timestamp=osi.Timestamp(seconds=2, nanos=123),
            country_code=276,
            map_reference="road",
            proj_frame_offset=osi.GroundTruth.ProjFrameOffset(
                position=osi.Vector3d(x=0.0, y=0.0, z=0.0), yaw=0.0
            ),
        ).to_binary()
    )


def test_map_message_decodes() -> None:
    message = osi.MapAsamOpenDrive.from_binary(osiwire.map_message("road", "<OpenDRIVE/>"))
    assert message.map_reference == "road"
    assert message.open_drive_xml_content == "<OpenDRIVE/>"


@pytest.mark.parametrize(
    ("value", "encoded"),
    [(0, b"\x00"), (1, b"\x01"), (300, b"\xac\x02"), (2**35, b"\x80" * 5 + b"\x01")],
)
def test_varint(value: int, encoded: bytes) -> None:
    assert osiwire.varint(value) == encoded
    assert osiwire.read_varint(encoded, 0) == (value, len(encoded))


def test_trimmed_descriptor_set_keeps_dependencies() -> None:
    trimmed = descriptors.osi_descriptor_set()
    names = {
        osiwire.payload(raw).decode()
        for _, _, file_raw in osiwire.fields(trimmed)
        for field, _, raw in osiwire.fields(osiwire.payload(file_raw))
        if field == 1
    }
    assert {"osi_groundtruth.proto", "osi_mapasamopendrive.proto", "osi_object.proto"} <= names
    assert "osi_sensordata.proto" not in names
    assert len(trimmed) < 120_000
