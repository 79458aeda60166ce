"""OSI 3.7.0 GroundTruth protobuf encoding, hand-rolled for the recorder's hot path.

Recording must add at most 10% to a run that is 100x faster than real time, which leaves a few
microseconds per object and frame. Building betterosi message objects costs about 20 us per object,
so the recorder writes the protobuf wire format directly: the constant parts of a frame (tags,
lengths, ids, types, classifications, dimensions, the trailing fields) are encoded once per set of
objects, and each frame packs only its 10 changing doubles per object between them with one
precompiled ``struct`` call (:class:`FrameLayout`). Every field of every sub-message is written,
including zeros, as the omega-prime specification requires (proto2 presence). Field numbers come
from ``osi_groundtruth.proto``/``osi_object.proto``/``osi_common.proto`` of OSI 3.7.0; the tests
decode the bytes with betterosi and compare them field by field.
"""

from __future__ import annotations

import dataclasses
import struct
from collections.abc import Iterator, Sequence

OSI_VERSION = (3, 7, 0)

# Wire types.
_VARINT, _FIXED64, _LENGTH = 0, 1, 2


def varint(value: int) -> bytes:
    """Unsigned LEB128 varint (protobuf uint32/uint64/enum/bool)."""
    if value < 0:
        raise ValueError(f"varint of negative value {value}")
    if value < 0x80:
        return bytes((value,))
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def key(field: int, wire_type: int) -> bytes:
    return varint((field << 3) | wire_type)


def length_delimited(field: int, payload: bytes) -> bytes:
    return key(field, _LENGTH) + varint(len(payload)) + payload


def varint_field(field: int, value: int) -> bytes:
    return key(field, _VARINT) + varint(value)


def double_field(field: int, value: float) -> bytes:
    return key(field, _FIXED64) + struct.pack("<d", value)


def triple(x: float, y: float, z: float) -> bytes:
    """Vector3d / Dimension3d / Orientation3d: three doubles in fields 1-3."""
    return double_field(1, x) + double_field(2, y) + double_field(3, z)


def identifier(value: int) -> bytes:
    return varint_field(1, value)


def map_message(map_reference: str, xml_content: str) -> bytes:
    """osi3.MapAsamOpenDrive."""
    return length_delimited(1, map_reference.encode()) + length_delimited(2, xml_content.encode())


# BaseMoving = dimension(1) position(2) orientation(3) velocity(4) acceleration(5), each a
# 27-byte triple of tagged doubles; dimension is constant per object and sits in the prefix.
_TRIPLE_LEN = 27
_BASE_LEN = 5 * (2 + _TRIPLE_LEN)
_ZERO_DOUBLE = bytes(8)
DYNAMIC_VALUES = 10
"""Doubles written per object and frame: position x/y/z, roll, pitch, yaw, velocity x/y and
acceleration x/y; vertical velocity and acceleration are written as constant zeros."""


def _dynamic_gaps() -> tuple[bytes, ...]:
    """The constant bytes around an object's ``DYNAMIC_VALUES`` doubles: one run before each
    double and one after the last (the tags, lengths and the two constant zero doubles)."""
    tags = [key(field, _FIXED64) for field in (1, 2, 3)]
    gaps: list[bytes] = []
    pending = b""
    for field, constant_z in ((2, False), (3, False), (4, True), (5, True)):
        pending += key(field, _LENGTH) + varint(_TRIPLE_LEN)
        gaps += [pending + tags[0], tags[1]]
        if constant_z:
            pending = tags[2] + _ZERO_DOUBLE
        else:
            gaps.append(tags[2])
            pending = b""
    return (*gaps, pending)


_GAPS = _dynamic_gaps()


@dataclasses.dataclass(frozen=True, slots=True)
class ObjectLayout:
    """The constant parts of one moving object's encoding; the kinematics that change every frame
    are packed between them by :class:`FrameLayout`."""

    prefix: bytes
    """GroundTruth field 5's tag and length, the id, BaseMoving's tag and length, dimension."""
    suffix: bytes
    """Object type and vehicle classification."""


def object_layout(
    *,
    object_id: int,
    object_type: int,
    dimension: tuple[float, float, float],
    classification_type: int,
    classification_role: int,
) -> ObjectLayout:
    """Layout of an osi3.MovingObject: id(1), base(2), type(3), vehicle_classification(6)."""
    classification = (
        varint_field(1, classification_type)
        + varint_field(3, 0)
        + varint_field(5, classification_role)
    )
    suffix = varint_field(3, object_type) + length_delimited(6, classification)
    head = length_delimited(1, identifier(object_id))
    base_head = key(2, _LENGTH) + varint(_BASE_LEN) + length_delimited(1, triple(*dimension))
    body_len = len(head) + len(base_head) + (_BASE_LEN - 2 - _TRIPLE_LEN) + len(suffix)
    prefix = key(5, _LENGTH) + varint(body_len) + head + base_head
    return ObjectLayout(prefix=prefix, suffix=suffix)


_VERSION_FIELD = length_delimited(
    1,
    varint_field(1, OSI_VERSION[0])
    + varint_field(2, OSI_VERSION[1])
    + varint_field(3, OSI_VERSION[2]),
)
_TIMESTAMP_KEY = key(2, _LENGTH)
_SECONDS_KEY, _NANOS_KEY = key(1, _VARINT), key(2, _VARINT)


@dataclasses.dataclass(frozen=True, slots=True)
class FrameLayout:
    """Precompiled encoding of a whole GroundTruth for one ordered set of objects.

    Constant byte runs and changing doubles alternate through the message, so one ``struct``
    packs a frame: ``template`` holds the runs at even positions, each frame fills the odd ones
    with its doubles (one slice assignment) and packs. Only the timestamp is encoded apart,
    being a variable-length varint.
    """

    packer: struct.Struct
    template: tuple[bytes | None, ...]
    host_field: bytes
    objects: int

    def encode(self, nanos: int, values: list[float]) -> bytes:
        """The GroundTruth at ``nanos``; ``values`` holds ``DYNAMIC_VALUES`` doubles per object,
        in the objects' order."""
        args: list[bytes | float | None] = list(self.template)
        args[1::2] = values
        return ground_truth_head(nanos=nanos) + self.host_field + self.packer.pack(*args)


def frame_layout(
    objects: Sequence[ObjectLayout], *, host_id: int | None, tail: bytes
) -> FrameLayout:
    """The frame layout of ``objects`` (in that order) followed by ``tail``."""
    runs: list[bytes] = []
    pending = b""
    for layout in objects:
        runs.append(pending + layout.prefix + _GAPS[0])
        runs += _GAPS[1:-1]
        pending = _GAPS[-1] + layout.suffix
    runs.append(pending + tail)
    template: list[bytes | None] = [None] * (2 * len(runs) - 1)
    template[0::2] = runs
    packer = struct.Struct("<" + "d".join(f"{len(run)}s" for run in runs))
    host_field = b"" if host_id is None else length_delimited(3, identifier(host_id))
    return FrameLayout(
        packer=packer, template=tuple(template), host_field=host_field, objects=len(objects)
    )


def ground_truth_head(*, nanos: int) -> bytes:
    """GroundTruth version(1) and timestamp(2); host_vehicle_id(3) follows from the layout."""
    seconds, nanos = divmod(nanos, 1_000_000_000)
    timestamp = _SECONDS_KEY + varint(seconds) + _NANOS_KEY + varint(nanos)
    return _VERSION_FIELD + _TIMESTAMP_KEY + varint(len(timestamp)) + timestamp


def ground_truth_tail(*, country_code: int, map_reference: str) -> bytes:
    """country_code(13), map_reference(15) and a zero proj_frame_offset(20)."""
    offset = length_delimited(1, triple(0.0, 0.0, 0.0)) + double_field(2, 0.0)
    return (
        varint_field(13, country_code)
        + length_delimited(15, map_reference.encode())
        + length_delimited(20, offset)
    )


# -- decoding (minimal, for the reader and the descriptor-set trimmer) ------------------------


def read_varint(data: bytes, position: int) -> tuple[int, int]:
    result = shift = 0
    while True:
        byte = data[position]
        position += 1
        result |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return result, position
        shift += 7


def fields(data: bytes) -> Iterator[tuple[int, int, bytes]]:
    """(field number, wire type, raw field bytes including its key) of a message."""
    position = 0
    while position < len(data):
        start = position
        tag, position = read_varint(data, position)
        field, wire_type = tag >> 3, tag & 7
        if wire_type == 0:
            _, position = read_varint(data, position)
        elif wire_type == 1:
            position += 8
        elif wire_type == 5:
            position += 4
        elif wire_type == 2:
            size, position = read_varint(data, position)
            position += size
        else:
            raise ValueError(f"unsupported wire type {wire_type}")
        yield field, wire_type, data[start:position]


def payload(raw: bytes) -> bytes:
    """The payload of a length-delimited field given with its key."""
    _, position = read_varint(raw, 0)
    size, position = read_varint(raw, position)
    return raw[position : position + size]
