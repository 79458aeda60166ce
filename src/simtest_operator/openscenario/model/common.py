"""Shared building blocks of the scenario model: enums, parameters, orientation, unsupported nodes.

Everything the other model modules share lives here so they do not import each other in circles.
Every node carries ``line`` (the source line of the element it came from, ``None`` when synthesised)
so the engine can name the place in a verdict reason.
"""

from __future__ import annotations

import dataclasses
import enum


class ParameterType(enum.StrEnum):
    """``parameterType`` of a ParameterDeclaration/VariableDeclaration."""

    INTEGER = "integer"
    DOUBLE = "double"
    STRING = "string"
    UNSIGNED_INT = "unsignedInt"
    UNSIGNED_SHORT = "unsignedShort"
    BOOLEAN = "boolean"
    DATE_TIME = "dateTime"


ParameterValue = bool | int | float | str
"""A typed parameter value: ``bool`` (boolean), ``int`` (integer/unsignedInt/unsignedShort),
``float`` (double), ``str`` (string, and dateTime kept as its ISO text)."""


class Rule(enum.StrEnum):
    """Comparison rule of conditions."""

    GREATER_THAN = "greaterThan"
    LESS_THAN = "lessThan"
    EQUAL_TO = "equalTo"
    GREATER_OR_EQUAL = "greaterOrEqual"
    LESS_OR_EQUAL = "lessOrEqual"
    NOT_EQUAL_TO = "notEqualTo"


class ReferenceContext(enum.StrEnum):
    """Orientation type and trajectory timing domain: relative or absolute."""

    RELATIVE = "relative"
    ABSOLUTE = "absolute"


class AngleType(enum.StrEnum):
    """Which angle of an entity an angle condition checks (1.3)."""

    HEADING = "heading"
    PITCH = "pitch"
    ROLL = "roll"


class CoordinateSystem(enum.StrEnum):
    """Coordinate system in which distances are measured (1.1+)."""

    ENTITY = "entity"
    LANE = "lane"
    ROAD = "road"
    TRAJECTORY = "trajectory"
    WORLD = "world"


class RelativeDistanceType(enum.StrEnum):
    """Which component of a distance is meant; 1.0 ``cartesianDistance`` maps to EUCLIDEAN."""

    LONGITUDINAL = "longitudinal"
    LATERAL = "lateral"
    EUCLIDEAN = "euclidianDistance"


class RoutingAlgorithm(enum.StrEnum):
    """Routing algorithm for road-based distances (1.2+)."""

    ASSIGNED_ROUTE = "assignedRoute"
    FASTEST = "fastest"
    LEAST_INTERSECTIONS = "leastIntersections"
    SHORTEST = "shortest"
    UNDEFINED = "undefined"


class DirectionalDimension(enum.StrEnum):
    """Direction of a speed/acceleration condition (1.2+)."""

    LONGITUDINAL = "longitudinal"
    LATERAL = "lateral"
    VERTICAL = "vertical"


class ValueScope(enum.StrEnum):
    """Whether a set/modify action or condition targets a parameter or a variable (1.2+)."""

    PARAMETER = "parameter"
    VARIABLE = "variable"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Unsupported:
    """An element the stand-in does not implement, kept at the place where it occurs.

    The engine gives verdict ``Invalid`` naming ``element`` and ``line`` only when execution
    actually reaches or needs this node; :meth:`Scenario.unsupported` lists all of them up front.
    """

    element: str
    """XML tag of the unsupported element, e.g. ``TrafficSignalCondition``."""
    line: int | None
    reason: str
    file: str | None = None
    """Absolute path of the file holding the element (catalog entries live in other files)."""
    name: str | None = None
    """Name of the enclosing named element (entity, action, ...), when there is one."""

    def describe(self) -> str:
        """One line for verdict reasons: ``<Element> at file:line: reason``."""
        where = f"{self.file or '?'}:{self.line if self.line is not None else '?'}"
        return f"<{self.element}> at {where}: {self.reason}"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ParameterDeclaration:
    """A declared parameter (or variable) with its final, typed value after overrides."""

    name: str
    type: ParameterType
    value: ParameterValue
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Orientation:
    """Heading/pitch/roll in radians; ``type`` None means absolute per the standard's default."""

    type: ReferenceContext | None = None
    h: float = 0.0
    p: float = 0.0
    r: float = 0.0
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Property:
    """A name/value pair from ``<Properties>``."""

    name: str
    value: str
    line: int | None = None
