"""World snapshots: what the simulator emits at every step.

The simulator produces them; evaluation, recording and the runner consume them. They are plain
frozen values so those consumers never depend on the simulator backend.

Conventions (OpenDRIVE/OpenSCENARIO, right-handed): ``x``/``y``/``z`` in metres are the entity's
*reference point* (for vehicles the rear-axle centre projected to the ground); ``heading`` in
radians counter-clockwise from +x; ``speed`` in m/s along the heading; ``acceleration`` in m/s^2
along the heading. ``box`` gives the bounding box relative to the reference point, so consumers can
derive the box centre (:meth:`EntityState.box_center`).
"""

from __future__ import annotations

import dataclasses
import enum
import math


class EntityKind(enum.StrEnum):
    """OpenSCENARIO entity families."""

    VEHICLE = "vehicle"
    PEDESTRIAN = "pedestrian"
    MISC_OBJECT = "miscObject"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BoundingBox:
    """An entity's box: centre offset from the reference point (entity frame) and dimensions."""

    center_x: float = 0.0
    center_y: float = 0.0
    center_z: float = 0.0
    length: float = 4.5
    width: float = 1.8
    height: float = 1.5


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EntityState:
    """One entity at one instant."""

    id: int
    """Stable integer id >= 0, unique within a run (OSI object ids need integers)."""
    name: str
    kind: EntityKind
    category: str
    """OpenSCENARIO category, e.g. ``car``, ``truck``, ``pedestrian``, ``obstacle``."""
    x: float
    y: float
    z: float = 0.0
    heading: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0
    speed: float = 0.0
    acceleration: float = 0.0
    lateral_speed: float = 0.0
    box: BoundingBox = dataclasses.field(default_factory=BoundingBox)
    road_id: str | None = None
    lane_id: int | None = None
    s: float | None = None
    t: float | None = None

    def box_center(self) -> tuple[float, float, float]:
        """World coordinates of the bounding-box centre."""
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        return (
            self.x + self.box.center_x * cos_h - self.box.center_y * sin_h,
            self.y + self.box.center_x * sin_h + self.box.center_y * cos_h,
            self.z + self.box.center_z,
        )

    def velocity(self) -> tuple[float, float]:
        """World-frame velocity vector (vx, vy)."""
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        return (
            self.speed * cos_h - self.lateral_speed * sin_h,
            self.speed * sin_h + self.lateral_speed * cos_h,
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class WorldSnapshot:
    """All entities at one simulated instant, ``time`` seconds after the scenario start."""

    time: float
    entities: tuple[EntityState, ...]

    def entity(self, name: str) -> EntityState | None:
        """The entity called ``name``, or None when it is not (yet) in the world."""
        for state in self.entities:
            if state.name == name:
                return state
        return None
