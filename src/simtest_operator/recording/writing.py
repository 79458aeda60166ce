"""The run recorder: world snapshots -> one omega-prime (OSI GroundTruth 3.7.0) MCAP file.

Layout of a recording, as omega-prime and the OSI MCAP trace convention expect:
- file metadata ``net.asam.osi.trace`` (OSI/protobuf versions, description, zero time),
  ``simtest.run`` (scenario id, seed, tool versions), one ``simtest.environment`` per environment
  the scenario set and one ``simtest.discontinuity`` per jump it commanded (the evidence checks
  excuse those);
- topic ``ground_truth``: one ``osi3.GroundTruth`` per recorded frame, timestamps being offsets
  from the scenario start, log time equal to the timestamp;
- topic ``ground_truth_map``: one ``osi3.MapAsamOpenDrive`` with the road file, whose
  ``map_reference`` matches every GroundTruth's.
Every entity is an ``osi3.MovingObject`` at its bounding-box centre; the map's traffic lights
(bulb by bulb, with their current modes) and stop signs are ``traffic_light``/``traffic_sign``
messages (:mod:`~simtest_operator.recording.signalwire`). Misc objects are written as
moving objects of type OTHER, because omega-prime ignores ``stationary_object`` when reading and
obstacles would otherwise vanish from every consumer. An entity that reappears after missing from
a frame gets a fresh id, since omega-prime forbids gaps in an object's frames.
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import operator
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, BinaryIO

from mcap.writer import CompressionType, Writer

from simtest_operator.errors import ResultsError
from simtest_operator.recording import descriptors, osiwire
from simtest_operator.snapshots import (
    BoundingBox,
    Discontinuity,
    EntityKind,
    EntityState,
    WorldSnapshot,
)

if TYPE_CHECKING:  # the SUT processes read recordings without the road network (numpy)
    from simtest_operator.opendrive import TrafficControl
    from simtest_operator.recording import signalwire

GROUND_TRUTH_TOPIC = "ground_truth"
MAP_TOPIC = "ground_truth_map"
OSI_TRACE_METADATA = "net.asam.osi.trace"
RUN_METADATA = "simtest.run"
ENVIRONMENT_METADATA = "simtest.environment"
"""One metadata record per environment the scenario set (time, name, Element.attribute settings)."""
DISCONTINUITY_METADATA = "simtest.discontinuity"
"""One metadata record per jump the scenario commanded (time, entity, OSI object id, cause): the
evidence checks excuse these, in the run and when the recording is judged again."""
_OSI_VERSION = ".".join(str(part) for part in osiwire.OSI_VERSION)
_PROTOBUF_VERSION = "7.0.0"  # what betterosi declares for the OSI protobuf files
_REISSUED_ID_BASE = 1_000_000_000
_MIN_DIMENSION = 0.01

# OSI MovingObject.Type and VehicleClassification.Type / Role values (osi_object.proto 3.7.0).
_TYPE_OTHER, _TYPE_VEHICLE, _TYPE_PEDESTRIAN, _TYPE_ANIMAL = 1, 2, 3, 4
_CLASS_OTHER = 1
_VEHICLE_CLASSES = {
    "car": 4, "van": 6, "truck": 7, "semitrailer": 9, "trailer": 10, "motorbike": 11,
    "bicycle": 12, "bus": 13, "tram": 14, "train": 15, "wheelchair": 16,
}  # fmt: skip
_ROLE_UNKNOWN, _ROLE_CIVIL = 0, 2
_SIGNATURE = operator.attrgetter("id", "box", "kind", "category")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RecordingInfo:
    """What a recording says about its run."""

    scenario_id: str
    seed: int
    versions: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Tool versions, e.g. ``{"simtest-operator": "0.1.0", "sumo": "1.28.0"}``."""
    description: str = ""
    zero_time: datetime.datetime | None = None
    """Wall-clock time of simulated t = 0, if meaningful (omitted from the file otherwise)."""


def _classify(state: EntityState) -> tuple[int, int, int]:
    """(OSI object type, classification type, classification role) of an entity."""
    category = state.category.lower()
    if state.kind is EntityKind.VEHICLE:
        return _TYPE_VEHICLE, _VEHICLE_CLASSES.get(category, _CLASS_OTHER), _ROLE_CIVIL
    if state.kind is EntityKind.PEDESTRIAN:
        kind = _TYPE_ANIMAL if category == "animal" else _TYPE_PEDESTRIAN
        return kind, _CLASS_OTHER, _ROLE_UNKNOWN
    return _TYPE_OTHER, _CLASS_OTHER, _ROLE_UNKNOWN


class Recorder:
    """Writes world snapshots to an omega-prime MCAP file; use as a context manager.

    ``period`` (seconds) thins the snapshots: a frame is written when its time reaches the next
    multiple of the period (0 writes every snapshot; pass 0.1 for 10 Hz from a 20 Hz loop).
    ``host_id`` is the ego's entity id (OSI ``host_vehicle_id``); without it the smallest id of
    the first frame is used.
    """

    def __init__(
        self,
        path: Path,
        *,
        info: RecordingInfo,
        opendrive: str | bytes | None = None,
        map_reference: str = "map",
        host_id: int | None = None,
        period: float = 0.0,
        country_code: int = 276,
        signals: Sequence[TrafficControl] = (),
    ) -> None:
        self.path = path
        self._signals: signalwire.SignalWire | None = None
        """The map's traffic lights and stop signs, written into every frame."""
        if signals:
            from simtest_operator.recording import signalwire

            self._signals = signalwire.SignalWire(signals)
        self._map = (
            opendrive.decode("utf-8", "replace") if isinstance(opendrive, bytes) else opendrive
        )
        self._map_reference = map_reference
        self._host_id = host_id
        self._period_ns = round(period * 1e9)
        self._due_ns = 0
        self._last_ns: int | None = None
        self._frames = 0
        self._tail = osiwire.ground_truth_tail(
            country_code=country_code, map_reference=map_reference
        )
        self._ids: dict[int, int] = {}
        self._id_history: dict[int, list[tuple[int, int]]] = {}
        """Per entity, the OSI ids it had and the time (ns) from which it had each."""
        self._previous: set[int] = set()
        self._seen: set[int] = set()
        self._reissued = 0
        self._signature: tuple[tuple[object, ...], ...] | None = None
        self._frame = osiwire.frame_layout((), host_id=None, tail=self._tail)
        self._layouts: dict[int, tuple[EntityKind, str, BoundingBox, osiwire.ObjectLayout]] = {}
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file: BinaryIO | None = path.open("wb")
        except OSError as exc:
            raise ResultsError(f"cannot create recording {path}: {exc}") from exc
        self._writer = Writer(self._file, compression=CompressionType.ZSTD)
        self._writer.start(profile="", library="simtest-operator")
        self._writer.add_metadata(OSI_TRACE_METADATA, self._trace_metadata(info))
        run = {"scenario_id": info.scenario_id, "seed": str(info.seed)}
        run.update({f"version.{name}": value for name, value in sorted(info.versions.items())})
        self._writer.add_metadata(RUN_METADATA, run)
        descriptor_set = descriptors.osi_descriptor_set()
        channel_meta = {
            "net.asam.osi.trace.channel.osi_version": _OSI_VERSION,
            "net.asam.osi.trace.channel.protobuf_version": _PROTOBUF_VERSION,
        }
        gt_schema = self._writer.register_schema("osi3.GroundTruth", "protobuf", descriptor_set)
        self._gt_channel = self._writer.register_channel(
            GROUND_TRUTH_TOPIC, "protobuf", gt_schema,
            {**channel_meta, "net.asam.osi.trace.channel.description": "simulated ground truth"},
        )  # fmt: skip
        self._map_channel: int | None = None
        if self._map is not None:
            map_schema = self._writer.register_schema(
                "osi3.MapAsamOpenDrive", "protobuf", descriptor_set
            )
            self._map_channel = self._writer.register_channel(
                MAP_TOPIC, "protobuf", map_schema,
                {**channel_meta, "net.asam.osi.trace.channel.description": "OpenDRIVE road map"},
            )  # fmt: skip

    @staticmethod
    def _trace_metadata(info: RecordingInfo) -> dict[str, str]:
        metadata = {
            "version": _OSI_VERSION,
            "min_osi_version": _OSI_VERSION,
            "max_osi_version": _OSI_VERSION,
            "min_protobuf_version": _PROTOBUF_VERSION,
            "max_protobuf_version": _PROTOBUF_VERSION,
            "description": info.description or f"simtest-operator run of {info.scenario_id}",
            "authors": "simtest-operator",
            "data_sources": "simulation",
        }
        if info.zero_time is not None:
            stamp = info.zero_time.astimezone(datetime.UTC)
            metadata["zero_time"] = stamp.strftime("%Y-%m-%dT%H:%M:%S.%fZ")
        return metadata

    @property
    def frames(self) -> int:
        """Number of GroundTruth frames written so far."""
        return self._frames

    def __enter__(self) -> Recorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def _osi_id(self, entity_id: int, nanos: int) -> int:
        if entity_id in self._previous or entity_id not in self._seen:
            if entity_id not in self._seen:
                self._seen.add(entity_id)
                self._id_history[entity_id] = [(nanos, entity_id)]
            return self._ids.setdefault(entity_id, entity_id)
        # Back after a gap: omega-prime forbids gaps, so this is a new object.
        self._reissued += 1
        self._ids[entity_id] = _REISSUED_ID_BASE + self._reissued
        self._id_history[entity_id].append((nanos, self._ids[entity_id]))
        return self._ids[entity_id]

    def _layout(self, osi_id: int, state: EntityState) -> osiwire.ObjectLayout:
        cached = self._layouts.get(osi_id)
        box = state.box
        if (
            cached is not None
            and (cached[2] is box or cached[2] == box)
            and cached[0] is state.kind
            and cached[1] == state.category
        ):
            return cached[3]
        kind, class_type, role = _classify(state)
        layout = osiwire.object_layout(
            object_id=osi_id,
            object_type=kind,
            dimension=(
                max(box.length, _MIN_DIMENSION),
                max(box.width, _MIN_DIMENSION),
                max(box.height, 0.0),
            ),
            classification_type=class_type,
            classification_role=role,
        )
        self._layouts[osi_id] = (state.kind, state.category, box, layout)
        return layout

    def _relayout(self, entities: tuple[EntityState, ...], nanos: int) -> osiwire.FrameLayout:
        """The frame layout for a new set of entities (or changed boxes or categories); keeps
        OSI ids stable and reissues the id of an entity that is back after a gap."""
        layouts = [self._layout(self._osi_id(state.id, nanos), state) for state in entities]
        self._previous = {state.id for state in entities}
        if self._host_id is None and entities:
            self._host_id = min(state.id for state in entities)
        host = self._ids.get(self._host_id) if self._host_id is not None else None
        return osiwire.frame_layout(layouts, host_id=host, tail=self._tail)

    def write(self, snapshot: WorldSnapshot, *, force: bool = False) -> bool:
        """Record the snapshot if it is due (always with ``force``); returns whether it was.

        Snapshots at or before the last recorded time are ignored.
        """
        if self._file is None:
            raise ResultsError(f"recording {self.path} is already closed")
        nanos = round(snapshot.time * 1e9)
        if nanos < 0:
            raise ValueError(f"snapshot time {snapshot.time} is before the scenario start")
        if self._last_ns is not None and nanos <= self._last_ns:
            return False
        if not force and nanos < self._due_ns - 1000:
            return False
        if self._period_ns > 0:
            self._due_ns = (nanos // self._period_ns + 1) * self._period_ns
        if self._frames == 0:
            self._write_map(nanos)
        entities = snapshot.entities
        # The frame layout stays valid while the same entities come in the same order with the
        # same boxes and categories: then neither ids nor constant bytes change.
        signature = tuple(map(_SIGNATURE, entities))
        if signature != self._signature:
            self._frame = self._relayout(entities, nanos)
            self._signature = signature
        # Per object: bounding-box centre, roll/pitch/yaw in [-pi, pi] (math.remainder is exact,
        # so angles already in range are kept as they are), world-frame velocity of the box
        # centre (EntityState.box_velocity, inlined: the recorder's hot path) and acceleration.
        cos, sin, remainder, pi, two_pi = math.cos, math.sin, math.remainder, math.pi, 2 * math.pi
        values: list[float] = []
        extend = values.extend
        for state in entities:
            heading, pitch, roll = state.heading, state.pitch, state.roll
            c, s = cos(heading), sin(heading)
            box = state.box
            bx, by = box.center_x, box.center_y
            acceleration, rate = state.acceleration, state.yaw_rate
            travel = state.travel
            vx, vy = (state.speed * c, state.speed * s) if travel is None else travel
            extend((
                state.x + bx * c - by * s,
                state.y + bx * s + by * c,
                state.z + box.center_z,
                roll if -pi <= roll <= pi else remainder(roll, two_pi),
                pitch if -pi <= pitch <= pi else remainder(pitch, two_pi),
                heading if -pi <= heading <= pi else remainder(heading, two_pi),
                vx - rate * (bx * s + by * c),
                vy + rate * (bx * c - by * s),
                acceleration * c,
                acceleration * s,
            ))  # fmt: skip
        self._writer.add_message(
            self._gt_channel,
            log_time=nanos,
            data=self._frame.encode(nanos, values)
            + (self._signals.encode(snapshot.signals) if self._signals is not None else b""),
            publish_time=nanos,
            sequence=self._frames,
        )
        self._last_ns = nanos
        self._frames += 1
        return True

    def _write_map(self, nanos: int) -> None:
        if self._map_channel is None or self._map is None:
            return
        data = osiwire.map_message(self._map_reference, self._map)
        self._writer.add_message(self._map_channel, log_time=nanos, data=data, publish_time=nanos)

    def add_environment(self, time: float, name: str, settings: Sequence[tuple[str, str]]) -> None:
        """Record an environment the scenario set at ``time`` (weather, time of day) as an MCAP
        metadata record: the stand-in renders none, the recording says what was asked."""
        if self._file is None:
            return
        data = {"time": f"{time:g}", "name": name, **dict(settings)}
        self._writer.add_metadata(ENVIRONMENT_METADATA, data)

    def add_discontinuity(self, jump: Discontinuity) -> None:
        """Record a jump the scenario commanded (after the frames it concerns, so the OSI id the
        entity had then is known) as an MCAP metadata record."""
        if self._file is None:
            return
        nanos = round(jump.time * 1e9)
        history = self._id_history.get(jump.entity, [(0, jump.entity)])
        object_id = history[0][1]
        for since, osi_id in history:
            if since <= nanos:
                object_id = osi_id
        data = {
            "time": repr(jump.time),
            "entity": str(jump.entity),
            "object": str(object_id),
            "cause": jump.cause.value,
        }
        self._writer.add_metadata(DISCONTINUITY_METADATA, data)

    def close(self) -> None:
        """Finish the file (summary and index); safe to call twice."""
        if self._file is None:
            return
        try:
            if self._frames == 0:
                self._write_map(0)
            self._writer.finish()  # type: ignore[no-untyped-call]
        finally:
            self._file.close()
            self._file = None
