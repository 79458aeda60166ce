"""Frames of the SUT protocol: a 16-byte header, then the payload.

Header (network byte order): magic ``b"OSUT"``, protocol version (u16), frame kind (u16),
sequence (u32: the step number; an answer repeats the step it answers), payload length (u32).
Payloads are OSI protobuf bytes, or UTF-8 JSON for the handshake, or UTF-8 text for errors.
The format is deliberately trivial so a SUT in any language needs a socket and protobuf only.
"""

from __future__ import annotations

import dataclasses
import enum
import socket
import struct

from simtest_operator.sut.errors import SutError, SutProtocolError

MAGIC = b"OSUT"
PROTOCOL_VERSION = 1
HEADER = struct.Struct("!4sHHII")
MAX_PAYLOAD = 64 * 1024 * 1024
"""Largest payload either side accepts (a ground truth of thousands of objects fits)."""


class Kind(enum.IntEnum):
    """What a frame carries."""

    HELLO = 1
    """Simulator -> SUT, JSON: protocol, OSI version, ego id, step, run and SUT configuration."""
    READY = 2
    """SUT -> simulator, JSON: protocol, the SUT's name/version/digest and its answer kind."""
    TRAFFIC_COMMAND = 3
    """Simulator -> SUT, osi3.TrafficCommand: scenario instructions to the ego (before the
    SENSOR_VIEW of the same step, only on steps that have any)."""
    SENSOR_VIEW = 4
    """Simulator -> SUT, osi3.SensorView: what the SUT perceives at t; it must answer."""
    MOTION_REQUEST = 5
    """SUT -> simulator, osi3.MotionRequest for t + dt."""
    TRAFFIC_UPDATE = 6
    """SUT -> simulator, osi3.TrafficUpdate: the ego's state at t + dt."""
    GOODBYE = 7
    """Simulator -> SUT, empty: the run ended; the SUT may wait for the next HELLO."""
    ERROR = 8
    """Either side, UTF-8 text: the sender gives up on this run, with the reason."""


@dataclasses.dataclass(frozen=True, slots=True)
class Frame:
    kind: Kind
    sequence: int
    payload: bytes


def encode(kind: Kind, sequence: int, payload: bytes = b"") -> bytes:
    """Header and payload of one frame."""
    return HEADER.pack(MAGIC, PROTOCOL_VERSION, kind, sequence, len(payload)) + payload


def send(sock: socket.socket, kind: Kind, sequence: int, payload: bytes = b"") -> None:
    try:
        sock.sendall(encode(kind, sequence, payload))
    except OSError as exc:
        raise SutError(f"cannot send {kind.name} to the SUT: {_describe(exc)}") from exc


def _read_exact(sock: socket.socket, size: int, buffer: bytearray) -> None:
    view = memoryview(buffer)
    got = 0
    while got < size:
        count = sock.recv_into(view[got:size], size - got)
        if count == 0:
            raise ConnectionResetError("connection closed by the peer")
        got += count


def receive(sock: socket.socket) -> Frame:
    """The next frame (socket timeouts propagate as TimeoutError; closed -> SutError)."""
    header = bytearray(HEADER.size)
    try:
        _read_exact(sock, HEADER.size, header)
    except TimeoutError:
        raise
    except OSError as exc:
        raise SutError(f"the SUT closed the connection ({_describe(exc)})") from exc
    magic, version, kind, sequence, length = HEADER.unpack(header)
    if magic != MAGIC:
        raise SutProtocolError(f"frame does not start with {MAGIC!r} (got {bytes(magic)!r})")
    if version != PROTOCOL_VERSION:
        raise SutProtocolError(
            f"protocol version {version} in a frame, this simulator speaks {PROTOCOL_VERSION}"
        )
    if length > MAX_PAYLOAD:
        raise SutProtocolError(f"frame payload of {length} bytes exceeds {MAX_PAYLOAD}")
    try:
        frame_kind = Kind(kind)
    except ValueError:
        raise SutProtocolError(f"unknown frame kind {kind}") from None
    payload = bytearray(length)
    try:
        _read_exact(sock, length, payload)
    except TimeoutError:
        raise
    except OSError as exc:
        raise SutError(f"the SUT closed the connection mid-frame ({_describe(exc)})") from exc
    return Frame(frame_kind, sequence, bytes(payload))


def _describe(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__
