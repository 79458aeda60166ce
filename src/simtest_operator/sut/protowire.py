"""A strict protobuf wire reader for the few small OSI messages the SUT protocol decodes.

SUT answers are untrusted input: every read is bounds-checked and a truncated or malformed
message raises :class:`ValueError` with what was wrong, instead of an IndexError or a silent
truncation. Encoding reuses the recorder's helpers (:mod:`simtest_operator.recording.osiwire`).
"""

from __future__ import annotations

import struct
from collections.abc import Iterator

VARINT, FIXED64, LENGTH, FIXED32 = 0, 1, 2, 5
_DOUBLE = struct.Struct("<d")
_TRIPLE = struct.Struct("<xdxdxd")
_MAX_VARINT_BYTES = 10


def read_varint(data: bytes, position: int) -> tuple[int, int]:
    """(value, next position) of the varint at ``position``."""
    result = shift = 0
    for _ in range(_MAX_VARINT_BYTES):
        if position >= len(data):
            raise ValueError("truncated varint")
        byte = data[position]
        position += 1
        result |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return result, position
        shift += 7
    raise ValueError("varint longer than 10 bytes")


def fields(data: bytes) -> Iterator[tuple[int, int, int | float | bytes]]:
    """(field number, wire type, value) of each field: an int for varints and fixed32, a float
    for fixed64 (every fixed64 field the protocol reads is a double), bytes for length-delimited
    fields."""
    position, end = 0, len(data)
    while position < end:
        tag, position = read_varint(data, position)
        number, wire_type = tag >> 3, tag & 7
        if number == 0:
            raise ValueError("field number 0")
        if wire_type == VARINT:
            value, position = read_varint(data, position)
            yield number, wire_type, value
        elif wire_type == FIXED64:
            if position + 8 > end:
                raise ValueError(f"truncated double in field {number}")
            yield number, wire_type, _DOUBLE.unpack_from(data, position)[0]
            position += 8
        elif wire_type == LENGTH:
            size, position = read_varint(data, position)
            if position + size > end:
                raise ValueError(f"field {number} claims {size} bytes, {end - position} left")
            yield number, wire_type, data[position : position + size]
            position += size
        elif wire_type == FIXED32:
            if position + 4 > end:
                raise ValueError(f"truncated fixed32 in field {number}")
            yield number, wire_type, int.from_bytes(data[position : position + 4], "little")
            position += 4
        else:
            raise ValueError(f"unsupported wire type {wire_type} in field {number}")


def message_fields(data: bytes) -> dict[int, list[int | float | bytes]]:
    """Every field's values by number (repeated fields keep their order).

    The common case -- one-byte tags and lengths, doubles -- is read inline (a SUT parses a few
    hundred sub-messages per step); anything else goes through :func:`fields`' general path.
    """
    out: dict[int, list[int | float | bytes]] = {}
    position, end = 0, len(data)
    unpack = _DOUBLE.unpack_from
    while position < end:
        tag = data[position]
        if tag & 0x80 or tag < 8:
            break  # multi-byte tag (or field 0): general path from here
        wire_type = tag & 7
        if wire_type == FIXED64 and position + 9 <= end:
            value: int | float | bytes = unpack(data, position + 1)[0]
            position += 9
        elif wire_type == LENGTH:
            size, start = read_varint(data, position + 1)
            if start + size > end:
                break
            value = data[start : start + size]
            position = start + size
        elif wire_type == VARINT and position + 1 < end and not data[position + 1] & 0x80:
            value = data[position + 1]
            position += 2
        else:
            break
        found = out.get(tag >> 3)
        if found is None:
            out[tag >> 3] = [value]
        else:
            found.append(value)
    if position < end:
        for number, _, value in fields(data[position:]):
            out.setdefault(number, []).append(value)
    return out


def sub_message(values: dict[int, list[int | float | bytes]], number: int) -> bytes | None:
    """The last occurrence of a length-delimited field (protobuf: last one wins)."""
    found = values.get(number)
    if not found:
        return None
    value = found[-1]
    if not isinstance(value, bytes):
        raise ValueError(f"field {number} should be a message")
    return value


def number(values: dict[int, list[int | float | bytes]], field: int, default: float) -> float:
    """A double field (0-valued default when absent)."""
    found = values.get(field)
    if not found:
        return default
    value = found[-1]
    if not isinstance(value, float):
        raise ValueError(f"field {field} should be a double")
    return value


def integer(values: dict[int, list[int | float | bytes]], field: int, default: int) -> int:
    """A varint field."""
    found = values.get(field)
    if not found:
        return default
    value = found[-1]
    if not isinstance(value, int) or isinstance(value, bool):
        raise ValueError(f"field {field} should be a varint")
    return value


def vector(data: bytes | None) -> tuple[float, float, float] | None:
    """A Vector3d/Orientation3d (three doubles in fields 1-3); None when absent."""
    if data is None:
        return None
    if len(data) == _TRIPLE.size and data[0] == 0x09 and data[9] == 0x11 and data[18] == 0x19:
        x, y, z = _TRIPLE.unpack(data)  # the usual encoding: x, y, z in order, all present
        return x, y, z
    values = message_fields(data)
    return number(values, 1, 0.0), number(values, 2, 0.0), number(values, 3, 0.0)


def timestamp_nanos(data: bytes | None) -> int | None:
    """An osi3.Timestamp (seconds 1, nanos 2) in nanoseconds; None when absent."""
    if data is None:
        return None
    values = message_fields(data)
    return integer(values, 1, 0) * 1_000_000_000 + integer(values, 2, 0)
