"""Trajectories of the scenario model: polyline, clothoid, clothoid spline and NURBS, as data.

The shapes are kept as the file gives them; sampling them into paths is the engine's job.
"""

from __future__ import annotations

import dataclasses

from simtest_operator.openscenario.model.common import Unsupported
from simtest_operator.openscenario.model.positions import Position


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Vertex:
    """A polyline vertex, optionally with the time at which it should be reached."""

    position: Position
    time: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Polyline:
    """Straight segments between vertices."""

    vertices: tuple[Vertex, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Clothoid:
    """A clothoid (curvature changing linearly) from ``position`` (or the entity's position)."""

    curvature: float
    curvature_prime: float
    """Rate of curvature change (1/m^2); 1.0's ``curvatureDot`` lands here too."""
    length: float
    start_time: float | None = None
    stop_time: float | None = None
    position: Position | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClothoidSplineSegment:
    """One segment of a clothoid spline (1.3)."""

    curvature_start: float
    curvature_end: float
    length: float
    h_offset: float = 0.0
    time_start: float | None = None
    position_start: Position | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClothoidSpline:
    """A chain of clothoid segments (1.3)."""

    segments: tuple[ClothoidSplineSegment, ...]
    time_end: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ControlPoint:
    """A NURBS control point."""

    position: Position
    time: float | None = None
    weight: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Nurbs:
    """A non-uniform rational B-spline of ``order`` with control points and knot vector."""

    order: int
    control_points: tuple[ControlPoint, ...]
    knots: tuple[float, ...]
    line: int | None = None


Shape = Polyline | Clothoid | ClothoidSpline | Nurbs | Unsupported


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Trajectory:
    """A named trajectory (inline or resolved from a Trajectory catalog)."""

    name: str
    closed: bool
    shape: Shape
    line: int | None = None
