"""DDS transport for ROS 2 messages: Cyclone DDS carries them, ``rosbags`` encodes them.

Cyclone DDS (the ``cyclonedds`` binding) does discovery, matching and delivery. A topic needs a
DDS type, so :func:`idl_type` builds one from the ``rosbags`` definition of the ROS 2 message
(same members, same ROS 2 DDS name, final extensibility like ``rosidl``'s): what the participant
advertises therefore describes the real message. The payload itself never goes through the
binding's own codec: :class:`Writer` sends the bytes ``rosbags`` serialised and :class:`Reader`
hands back the bytes that arrived, through the same C-layer calls the binding's
``DataWriter.write``/``DataReader.take`` make after their own (de)serialisation.

Only this module imports ``cyclonedds``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from cyclonedds import idl
from cyclonedds._clayer import ddspy_take, ddspy_write  # the raw sample calls of the binding
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import types as idl_types
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from rosbags.typesys.store import Typestore

from simtest_operator.sut.ros2 import interfaces
from simtest_operator.sut.ros2.interfaces import Durability, QosProfile, Reliability

_BASE: dict[str, Any] = {
    "bool": bool,
    "byte": idl_types.byte,
    "char": idl_types.uint8,
    "int8": idl_types.int8,
    "uint8": idl_types.uint8,
    "int16": idl_types.int16,
    "uint16": idl_types.uint16,
    "int32": idl_types.int32,
    "uint32": idl_types.uint32,
    "int64": idl_types.int64,
    "uint64": idl_types.uint64,
    "float32": idl_types.float32,
    "float64": idl_types.float64,
}
_BASE_NODE, _NAME_NODE, _ARRAY_NODE, _SEQUENCE_NODE = 1, 2, 3, 4  # rosbags' Nodetype values


def idl_type(store: Typestore, ros_type: str, cache: dict[str, Any] | None = None) -> Any:
    """The Cyclone DDS IDL struct of ``ros_type`` (named ``pkg::msg::dds_::Type_``)."""
    cache = {} if cache is None else cache
    found = cache.get(ros_type)
    if found is not None:
        return found
    _, fields = store.fielddefs[ros_type]
    members = {name: _member(store, node, cache) for name, node in fields}
    if not members:  # an empty ROS message has one uint8 member in DDS (rosidl's rule)
        members = {"structure_needs_at_least_one_member": idl_types.uint8}
    package, kind, name = ros_type.split("/")
    struct = idl.make_idl_struct(
        f"{package}_{kind}_{name}", interfaces.dds_type(ros_type).replace("::", "."), members
    )
    cache[ros_type] = struct
    return struct


def _member(store: Typestore, node: tuple[Any, Any], cache: dict[str, Any]) -> Any:
    kind, detail = int(node[0]), node[1]
    if kind == _BASE_NODE:
        base, bound = detail
        if base == "string":
            # The binding's IDL types are subscripted at run time (typing.Annotated forms).
            return idl_types.bounded_str[bound] if bound else str  # type: ignore[misc]
        if base == "wstring":
            raise ValueError("wstring members are not supported")
        return _BASE[base]
    if kind == _NAME_NODE:
        return idl_type(store, detail, cache)
    inner, size = detail
    element = _member(store, inner, cache)
    if kind == _ARRAY_NODE:
        return idl_types.array[element, size]  # type: ignore[misc]
    if kind == _SEQUENCE_NODE:
        bounded = (element, size) if size else element
        return idl_types.sequence[bounded]  # type: ignore[misc]
    raise ValueError(f"unknown rosbags node type {kind}")


def qos(profile: QosProfile) -> Qos:
    """The DDS QoS of a ROS 2 profile."""
    return Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100))
        if profile.reliability is Reliability.RELIABLE
        else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal
        if profile.durability is Durability.TRANSIENT_LOCAL
        else Policy.Durability.Volatile,
        Policy.History.KeepLast(profile.depth),
    )


def pad(payload: bytes) -> bytes:
    """A serialised sample padded to 4 bytes, as the binding (and Cyclone DDS) sends it."""
    return payload + b"\0" * (-len(payload) % 4)


class Participant:
    """One DDS participant with ROS 2-named topics (``rt/...``) for ``rosbags`` types."""

    def __init__(self, domain_id: int, store: Typestore | None = None) -> None:
        self.store = store if store is not None else interfaces.typestore()
        self.participant = DomainParticipant(domain_id)
        self._types: dict[str, Any] = {}

    def topic(self, name: str, ros_type: str) -> Topic[Any]:
        return Topic(
            self.participant,
            interfaces.dds_topic(name),
            idl_type(self.store, ros_type, self._types),
        )

    def writer(self, name: str, ros_type: str, profile: QosProfile) -> Writer:
        return Writer(
            DataWriter(self.participant, self.topic(name, ros_type), qos=qos(profile)),
            self.store,
            ros_type,
        )

    def reader(self, name: str, ros_type: str, profile: QosProfile) -> Reader:
        return Reader(
            DataReader(self.participant, self.topic(name, ros_type), qos=qos(profile)),
            self.participant,
            self.store,
            ros_type,
        )


class Writer:
    """Publishes ``rosbags`` messages of one type on one topic."""

    def __init__(self, writer: DataWriter[Any], store: Typestore, ros_type: str) -> None:
        self.writer = writer
        self._store = store
        self.ros_type = ros_type

    def serialise(self, message: object) -> bytes:
        """The sample as it goes on the wire: ``rosbags``' CDR, padded to 4 bytes."""
        return pad(bytes(self._store.serialize_cdr(message, self.ros_type)))

    def publish(self, message: object) -> None:
        self.publish_raw(self.serialise(message))

    def publish_raw(self, payload: bytes) -> None:
        result = ddspy_write(self.writer._ref, payload)
        if result < 0:
            raise OSError(f"DDS write on {self.writer.topic.name} failed ({result})")

    def matched(self) -> int:
        """Subscriptions matched right now (a stack's reader of this topic)."""
        return len(self.writer.get_matched_subscriptions())


class Reader:
    """Takes ``rosbags`` messages of one type from one topic."""

    _ANY = SampleState.Any | ViewState.Any | InstanceState.Any

    def __init__(
        self,
        reader: DataReader[Any],
        participant: DomainParticipant,
        store: Typestore,
        ros_type: str,
    ) -> None:
        self.reader = reader
        self._store = store
        self.ros_type = ros_type
        self._waitset = WaitSet(participant)
        self._waitset.attach(ReadCondition(reader, self._ANY))

    def take_raw(self, limit: int = 64) -> list[bytes]:
        """The samples that arrived, as their bytes (oldest first; empty when none)."""
        taken = ddspy_take(self.reader._ref, self._ANY, limit)
        if isinstance(taken, int):
            raise OSError(f"DDS take on {self.reader.topic.name} failed ({taken})")
        return [bytes(data) for data, info in taken if info.valid_data]

    def drain(self) -> None:
        """Drop every sample that arrived so far."""
        while self.take_raw():
            pass

    def take(self, limit: int = 64) -> list[Any]:
        return [self.decode(raw) for raw in self.take_raw(limit)]

    def decode(self, raw: bytes) -> Any:
        return self._store.deserialize_cdr(raw, self.ros_type)

    def wait(self, timeout: float) -> bool:
        """Block until a sample is there or ``timeout`` seconds passed (True: data)."""
        return self._waitset.wait(max(int(timeout * 1e9), 0)) > 0

    def matched(self) -> int:
        """Publications matched right now (a stack's writer of this topic)."""
        return len(self.reader.get_matched_publications())


def wait_matched(
    endpoints: Sequence[Writer | Reader], *, timeout: float, poll: float = 0.01
) -> list[Writer | Reader]:
    """The endpoints still without a match after at most ``timeout`` s (empty: all matched)."""
    deadline = time.monotonic() + timeout
    while True:
        missing = [e for e in endpoints if e.matched() == 0]
        if not missing or time.monotonic() >= deadline:
            return missing
        time.sleep(poll)
