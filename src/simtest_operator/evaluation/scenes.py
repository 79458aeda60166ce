"""Scenes: a recorded run as numpy columns, the input of every offline evaluation.

Evaluation sits on the same layer as recording and must not import it, so the reader's objects
come in structurally (:class:`ObjectColumns`, :class:`RecordedColumns`); the CLI passes
``recording.objects.read_objects`` results straight through :func:`scene_from_columns`.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np
import numpy.typing as npt

from simtest_operator.snapshots import Discontinuity

Array = npt.NDArray[np.float64]

# OSI MovingObject.Type and VehicleClassification.Type values (osi_object.proto 3.7.0).
_OSI_VEHICLE, _OSI_PEDESTRIAN, _OSI_ANIMAL = 2, 3, 4
_OSI_BICYCLE, _OSI_MOTORBIKE = 12, 11


class ActorKind(enum.StrEnum):
    """What an object is, as far as choosing metrics goes."""

    VEHICLE = "vehicle"
    PEDESTRIAN = "pedestrian"
    CYCLIST = "cyclist"
    OTHER = "other"

    @property
    def vulnerable(self) -> bool:
        """Pedestrians and cyclists get VRU base scenarios and distance-based metrics."""
        return self in (ActorKind.PEDESTRIAN, ActorKind.CYCLIST)


class ObjectColumns(Protocol):
    """Per-sample columns of one recorded object (``recording.objects.ObjectRecord``)."""

    @property
    def object_id(self) -> int: ...
    @property
    def t(self) -> Sequence[float]: ...
    @property
    def x(self) -> Sequence[float]: ...
    @property
    def y(self) -> Sequence[float]: ...
    @property
    def yaw(self) -> Sequence[float]: ...
    @property
    def roll(self) -> Sequence[float]: ...
    @property
    def pitch(self) -> Sequence[float]: ...
    @property
    def vx(self) -> Sequence[float]: ...
    @property
    def vy(self) -> Sequence[float]: ...
    @property
    def ax(self) -> Sequence[float]: ...
    @property
    def ay(self) -> Sequence[float]: ...
    @property
    def length(self) -> Sequence[float]: ...
    @property
    def width(self) -> Sequence[float]: ...
    @property
    def height(self) -> Sequence[float]: ...
    @property
    def object_type(self) -> Sequence[int]: ...
    @property
    def vehicle_type(self) -> Sequence[int]: ...
    @property
    def role(self) -> Sequence[int]: ...


class RecordedColumns(Protocol):
    """A decoded recording (``recording.objects.RecordedObjects``)."""

    @property
    def frame_times(self) -> Sequence[float]: ...
    @property
    def host_ids(self) -> Sequence[int | None]: ...
    @property
    def objects(self) -> Mapping[int, ObjectColumns]: ...
    @property
    def map_references(self) -> frozenset[str]: ...
    @property
    def map_xml(self) -> str | None: ...
    @property
    def map_channel_reference(self) -> str | None: ...
    @property
    def discontinuities(self) -> Sequence[Discontinuity]: ...


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Track:
    """One object over time: box centre, yaw, velocity and acceleration vectors (world frame)."""

    object_id: int
    kind: ActorKind
    length: float
    width: float
    t: Array
    x: Array
    y: Array
    yaw: Array
    vx: Array
    vy: Array
    ax: Array
    ay: Array

    @property
    def speed(self) -> Array:
        return np.hypot(self.vx, self.vy)

    @property
    def longitudinal_acceleration(self) -> Array:
        """Acceleration along the heading (negative when braking)."""
        return self.ax * np.cos(self.yaw) + self.ay * np.sin(self.yaw)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Scene:
    """A recorded run: the ego (the recording's host vehicle) and every other object."""

    ego: Track
    others: tuple[Track, ...]
    frame_times: Array


def median(values: Array) -> float:
    """The median of a non-empty array (``np.median`` imports ``numpy.ma``, 30 ms, on first use)."""
    ordered = np.sort(values)
    n = len(ordered)
    return float((ordered[(n - 1) // 2] + ordered[n // 2]) / 2.0)


def kind_of(object_type: int, vehicle_type: int) -> ActorKind:
    """The actor kind of an OSI type/classification pair."""
    if object_type in (_OSI_PEDESTRIAN, _OSI_ANIMAL):
        return ActorKind.PEDESTRIAN
    if object_type == _OSI_VEHICLE:
        return ActorKind.CYCLIST if vehicle_type == _OSI_BICYCLE else ActorKind.VEHICLE
    return ActorKind.OTHER


def track_from_columns(columns: ObjectColumns) -> Track:
    """A :class:`Track` from one object's columns, sorted by time."""
    t = np.asarray(columns.t, dtype=np.float64)
    order = np.argsort(t, kind="stable")

    def col(values: Sequence[float]) -> Array:
        return np.asarray(values, dtype=np.float64)[order]

    length = median(col(columns.length)) if len(t) else 0.0
    width = median(col(columns.width)) if len(t) else 0.0
    kind = (
        kind_of(int(columns.object_type[0]), int(columns.vehicle_type[0]))
        if len(t)
        else ActorKind.OTHER
    )
    return Track(
        object_id=columns.object_id,
        kind=kind,
        length=length,
        width=width,
        t=t[order],
        x=col(columns.x),
        y=col(columns.y),
        yaw=col(columns.yaw),
        vx=col(columns.vx),
        vy=col(columns.vy),
        ax=col(columns.ax),
        ay=col(columns.ay),
    )


def host_id(recorded: RecordedColumns) -> int | None:
    """The host vehicle of the recording: the most frequent ``host_vehicle_id``, else the
    smallest object id (the recorder's convention when it was not told the ego)."""
    hosts = [h for h in recorded.host_ids if h is not None]
    if hosts:
        return max(set(hosts), key=hosts.count)
    return min(recorded.objects) if recorded.objects else None


def scene_from_columns(recorded: RecordedColumns) -> Scene | None:
    """The scene of a decoded recording; ``None`` when it has no host vehicle track."""
    ego_id = host_id(recorded)
    if ego_id is None or ego_id not in recorded.objects:
        return None
    ego = track_from_columns(recorded.objects[ego_id])
    if len(ego.t) == 0 or not math.isfinite(ego.length):
        return None
    others = tuple(
        track_from_columns(columns)
        for object_id, columns in sorted(recorded.objects.items())
        if object_id != ego_id and len(columns.t)
    )
    return Scene(
        ego=ego,
        others=others,
        frame_times=np.asarray(recorded.frame_times, dtype=np.float64),
    )
