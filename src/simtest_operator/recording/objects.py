"""Reading recordings for re-evaluation: every moving object's full state, frame by frame.

:func:`~simtest_operator.recording.reading.read_trajectories` keeps what a plot needs; judging a
run again needs more (box size, object type, velocity and acceleration vectors, the host id, the
map) and must be fast enough that re-scoring 200 recordings costs a tenth of re-simulating them.
``omega_prime.Recording.from_file`` takes seconds per file (betterosi objects, pandera checks),
so this decodes the wire format in one tight loop per object, on byte offsets, without building
intermediate slices. Unknown fields are skipped, so other OSI writers' files read as well.
"""

from __future__ import annotations

import dataclasses
import struct
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader

from simtest_operator.errors import ResultsError
from simtest_operator.recording.writing import GROUND_TRUTH_TOPIC, MAP_TOPIC

_DOUBLE = struct.Struct("<d").unpack_from
_FLOAT = struct.Struct("<f").unpack_from
_VALUES = 18
"""Per sample: t, x, y, z, roll, pitch, yaw, vx, vy, vz, ax, ay, az, length, width, height,
OSI type, vehicle classification type (role is kept per object, it never changes legitimately)."""


@dataclasses.dataclass(slots=True)
class ObjectRecord:
    """One OSI moving object over the frames it appears in (columns of equal length)."""

    object_id: int
    t: list[float] = dataclasses.field(default_factory=list)
    x: list[float] = dataclasses.field(default_factory=list)
    y: list[float] = dataclasses.field(default_factory=list)
    yaw: list[float] = dataclasses.field(default_factory=list)
    roll: list[float] = dataclasses.field(default_factory=list)
    pitch: list[float] = dataclasses.field(default_factory=list)
    vx: list[float] = dataclasses.field(default_factory=list)
    vy: list[float] = dataclasses.field(default_factory=list)
    ax: list[float] = dataclasses.field(default_factory=list)
    ay: list[float] = dataclasses.field(default_factory=list)
    length: list[float] = dataclasses.field(default_factory=list)
    width: list[float] = dataclasses.field(default_factory=list)
    height: list[float] = dataclasses.field(default_factory=list)
    object_type: list[int] = dataclasses.field(default_factory=list)
    """OSI MovingObject.Type per sample (0 unknown, 1 other, 2 vehicle, 3 pedestrian, 4 animal)."""
    vehicle_type: list[int] = dataclasses.field(default_factory=list)
    """OSI VehicleClassification.Type per sample (-1 when the message has none)."""
    role: list[int] = dataclasses.field(default_factory=list)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RecordedObjects:
    """What a recording holds, decoded: frames, host, map and every object."""

    frame_times: tuple[float, ...]
    """Timestamps of the GroundTruth messages, in file order (seconds)."""
    host_ids: tuple[int | None, ...]
    """``host_vehicle_id`` of each frame (``None`` where unset)."""
    objects: dict[int, ObjectRecord]
    map_references: frozenset[str]
    """Distinct ``GroundTruth.map_reference`` values."""
    map_xml: str | None
    """The OpenDRIVE text of the map channel, if present."""
    map_channel_reference: str | None
    metadata: dict[str, dict[str, str]]


def _varint(data: bytes, pos: int) -> tuple[int, int]:
    result = shift = 0
    while True:
        byte = data[pos]
        pos += 1
        result |= (byte & 0x7F) << shift
        if byte < 0x80:
            return result, pos
        shift += 7


def _skip(data: bytes, pos: int, wire: int) -> int:
    if wire == 0:
        while data[pos] & 0x80:
            pos += 1
        return pos + 1
    if wire == 1:
        return pos + 8
    if wire == 5:
        return pos + 4
    if wire == 2:
        size, pos = _varint(data, pos)
        return pos + size
    raise ValueError(f"unsupported wire type {wire}")


_THREE_DOUBLES = struct.Struct("<xdxdxd").unpack_from
_FULL_TRIPLE = 27
"""Bytes of a triple with all three doubles set, in field order (what every writer emits)."""


def _triple(data: bytes, pos: int, end: int, out: list[float], offset: int) -> None:
    """A Vector3d/Dimension3d/Orientation3d (fields 1..3, doubles) into ``out[offset:offset+3]``."""
    if (
        end - pos == _FULL_TRIPLE
        and data[pos] == 9
        and data[pos + 9] == 17
        and data[pos + 18] == 25
    ):
        out[offset], out[offset + 1], out[offset + 2] = _THREE_DOUBLES(data, pos)
        return
    while pos < end:
        tag = data[pos]
        pos += 1
        if tag & 0x80:
            tag, pos = _varint(data, pos - 1)
        field, wire = tag >> 3, tag & 7
        if wire == 1 and 1 <= field <= 3:
            out[offset + field - 1] = _DOUBLE(data, pos)[0]
            pos += 8
        elif wire == 5 and 1 <= field <= 3:
            out[offset + field - 1] = _FLOAT(data, pos)[0]
            pos += 4
        else:
            pos = _skip(data, pos, wire)


_BASE_OFFSETS = {1: 13, 2: 1, 3: 4, 4: 7, 5: 10}
"""BaseMoving field -> where its three values go (dimension, position, orientation, velocity,
acceleration)."""


def _moving_object(data: bytes, pos: int, end: int, values: list[float]) -> tuple[int, int]:
    """Decode one MovingObject into ``values`` (t already set); returns (id, role)."""
    object_id = -1
    role = -1
    while pos < end:
        tag = data[pos]
        if tag < 0x80:
            pos += 1
        else:
            tag, pos = _varint(data, pos)
        field, wire = tag >> 3, tag & 7
        if wire != 2:
            if field == 3 and wire == 0:
                object_type = data[pos]
                if object_type < 0x80:
                    pos += 1
                else:
                    object_type, pos = _varint(data, pos)
                values[16] = object_type
            else:
                pos = _skip(data, pos, wire)
            continue
        size = data[pos]
        if size < 0x80:
            pos += 1
        else:
            size, pos = _varint(data, pos)
        stop = pos + size
        if field == 1:
            inner = pos
            while inner < stop:
                itag = data[inner]
                if itag < 0x80:
                    inner += 1
                else:
                    itag, inner = _varint(data, inner)
                if itag == 8:
                    object_id = data[inner]
                    if object_id < 0x80:
                        inner += 1
                    else:
                        object_id, inner = _varint(data, inner)
                else:
                    inner = _skip(data, inner, itag & 7)
        elif field == 2:
            inner = pos
            while inner < stop:
                itag = data[inner]
                if itag < 0x80:
                    inner += 1
                else:
                    itag, inner = _varint(data, inner)
                ifield, iwire = itag >> 3, itag & 7
                if iwire == 2:
                    isize = data[inner]
                    if isize < 0x80:
                        inner += 1
                    else:
                        isize, inner = _varint(data, inner)
                    offset = _BASE_OFFSETS.get(ifield)
                    if offset is not None:
                        _triple(data, inner, inner + isize, values, offset)
                    inner += isize
                else:
                    inner = _skip(data, inner, iwire)
        elif field == 6:
            inner = pos
            values[17] = 0
            while inner < stop:
                itag = data[inner]
                if itag < 0x80:
                    inner += 1
                else:
                    itag, inner = _varint(data, inner)
                if itag == 8:
                    vehicle_type = data[inner]
                    if vehicle_type < 0x80:
                        inner += 1
                    else:
                        vehicle_type, inner = _varint(data, inner)
                    values[17] = vehicle_type
                elif itag == 40:
                    role = data[inner]
                    if role < 0x80:
                        inner += 1
                    else:
                        role, inner = _varint(data, inner)
                else:
                    inner = _skip(data, inner, itag & 7)
        pos = stop
    return object_id, role


def _ground_truth(
    data: bytes, fallback_t: float, objects: dict[int, ObjectRecord], refs: set[str]
) -> tuple[float, int | None]:
    """Decode one GroundTruth, appending its objects; returns (time, host id)."""
    t = fallback_t
    host: int | None = None
    spans: list[tuple[int, int]] = []
    pos, end = 0, len(data)
    while pos < end:
        tag = data[pos]
        if tag < 0x80:
            pos += 1
        else:
            tag, pos = _varint(data, pos)
        field, wire = tag >> 3, tag & 7
        if wire != 2:
            pos = _skip(data, pos, wire)
            continue
        size = data[pos]
        if size < 0x80:
            pos += 1
        else:
            size, pos = _varint(data, pos)
        stop = pos + size
        if field == 5:
            spans.append((pos, stop))
        elif field == 2:
            seconds = nanos = 0
            inner = pos
            while inner < stop:
                itag = data[inner]
                if itag < 0x80:
                    inner += 1
                else:
                    itag, inner = _varint(data, inner)
                if itag == 8:
                    seconds = data[inner]
                    if seconds < 0x80:
                        inner += 1
                    else:
                        seconds, inner = _varint(data, inner)
                elif itag == 16:
                    nanos = data[inner]
                    if nanos < 0x80:
                        inner += 1
                    else:
                        nanos, inner = _varint(data, inner)
                else:
                    inner = _skip(data, inner, itag & 7)
            t = seconds + nanos * 1e-9
        elif field == 3:
            inner = pos
            while inner < stop:
                itag = data[inner]
                if itag < 0x80:
                    inner += 1
                else:
                    itag, inner = _varint(data, inner)
                if itag == 8:
                    host = data[inner]
                    if host < 0x80:
                        inner += 1
                    else:
                        host, inner = _varint(data, inner)
                else:
                    inner = _skip(data, inner, itag & 7)
        elif field == 15:
            refs.add(data[pos:stop].decode("utf-8", "replace"))
        pos = stop
    for start, stop in spans:
        values = [0.0] * _VALUES
        values[0] = t
        values[17] = -1
        object_id, role = _moving_object(data, start, stop, values)
        if object_id < 0:
            continue
        record = objects.get(object_id)
        if record is None:
            record = objects[object_id] = ObjectRecord(object_id=object_id)
        record.t.append(t)
        record.x.append(values[1])
        record.y.append(values[2])
        record.roll.append(values[4])
        record.pitch.append(values[5])
        record.yaw.append(values[6])
        record.vx.append(values[7])
        record.vy.append(values[8])
        record.ax.append(values[10])
        record.ay.append(values[11])
        record.length.append(values[13])
        record.width.append(values[14])
        record.height.append(values[15])
        record.object_type.append(int(values[16]))
        record.vehicle_type.append(int(values[17]))
        record.role.append(role)
    return t, host


def _map_message(data: bytes) -> tuple[str | None, str | None]:
    reference = xml = None
    pos, end = 0, len(data)
    while pos < end:
        tag, pos = _varint(data, pos)
        field, wire = tag >> 3, tag & 7
        if wire != 2:
            pos = _skip(data, pos, wire)
            continue
        size, pos = _varint(data, pos)
        text = data[pos : pos + size].decode("utf-8", "replace")
        if field == 1:
            reference = text
        elif field == 2:
            xml = text
        pos += size
    return reference, xml


def read_objects(path: Path, *, with_map: bool = True) -> RecordedObjects:
    """Every frame and object of an omega-prime recording (both map topic spellings)."""
    objects: dict[int, ObjectRecord] = {}
    refs: set[str] = set()
    times: list[float] = []
    hosts: list[int | None] = []
    map_ref = map_xml = None
    map_topics = {MAP_TOPIC, "/" + MAP_TOPIC}
    try:
        with path.open("rb") as stream:
            reader = make_reader(stream)
            metadata = {record.name: dict(record.metadata) for record in reader.iter_metadata()}
            topics = [GROUND_TRUTH_TOPIC, *map_topics] if with_map else [GROUND_TRUTH_TOPIC]
            for _, channel, message in reader.iter_messages(topics=topics, log_time_order=False):
                if channel.topic in map_topics:
                    map_ref, map_xml = _map_message(message.data)
                    continue
                t, host = _ground_truth(message.data, message.log_time * 1e-9, objects, refs)
                times.append(t)
                hosts.append(host)
    except (OSError, McapError, ValueError, IndexError, struct.error) as exc:
        raise ResultsError(f"cannot read recording {path}: {exc}") from exc
    return RecordedObjects(
        frame_times=tuple(times),
        host_ids=tuple(hosts),
        objects=objects,
        map_references=frozenset(refs),
        map_xml=map_xml,
        map_channel_reference=map_ref,
        metadata=metadata,
    )
