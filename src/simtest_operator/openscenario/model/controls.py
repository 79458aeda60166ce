"""Controller, parameter/variable, traffic signal, entity, environment and ignored actions of the
scenario model.

Split from :mod:`.actions` to keep modules small; import them through ``model``.
"""

from __future__ import annotations

import dataclasses
import enum

from simtest_operator.openscenario.model.common import Unsupported, ValueScope
from simtest_operator.openscenario.model.entities import Controller
from simtest_operator.openscenario.model.positions import Position


class ModifyRule(enum.StrEnum):
    """Parameter/variable modify operation."""

    ADD = "addValue"
    MULTIPLY = "multiplyByValue"


# --- controllers ------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ActivateControllerAction:
    """Switch the entity's controller on/off per domain (None: leave unchanged)."""

    lateral: bool | None = None
    longitudinal: bool | None = None
    lighting: bool | None = None
    animation: bool | None = None
    controller_ref: str | None = None
    object_controller_ref: str | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AssignControllerAction:
    """Assign a controller to the entity, optionally activating domains (1.2)."""

    controller: Controller | Unsupported
    activate_lateral: bool | None = None
    activate_longitudinal: bool | None = None
    activate_lighting: bool | None = None
    activate_animation: bool | None = None
    line: int | None = None


# --- parameters and variables -----------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SetValueAction:
    """Set a parameter or variable to ``value`` (text, typed by the declaration)."""

    scope: ValueScope
    ref: str
    value: str
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ModifyValueAction:
    """Add to or multiply a numeric parameter or variable."""

    scope: ValueScope
    ref: str
    rule: ModifyRule
    value: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSignalStateAction:
    """Set the state of the traffic signal ``name`` (OpenDRIVE signal id) to ``state``."""

    name: str
    state: str
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSignalControllerAction:
    """Switch the RoadNetwork's controller ``controller_ref`` to its phase ``phase`` now (it
    cycles on from there)."""

    controller_ref: str
    phase: str
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class IgnoredAction:
    """An action accepted but not simulated (environment, lights, visibility, appearance)."""

    kind: str
    """XML tag, e.g. ``EnvironmentAction`` or ``LightStateAction``."""
    line: int | None = None


# --- entities and environment -----------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AddEntityAction:
    """Put the declared entity ``entity_ref`` into the world at ``position`` (it was absent)."""

    entity_ref: str
    position: Position
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class DeleteEntityAction:
    """Take ``entity_ref`` out of the world: no pose, no conditions, no collisions until added."""

    entity_ref: str
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Environment:
    """An environment (time of day, weather, road condition) as written.

    The stand-in renders no weather, so the settings are kept as flat ``Element.attribute`` ->
    value pairs (``Weather.cloudState``, ``Sun.elevation``, ``Precipitation.intensity``, ...)
    with parameters resolved: enough to record exactly what the run was asked to show.
    """

    name: str
    settings: tuple[tuple[str, str], ...] = ()
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EnvironmentAction:
    """Set the environment (Init or story); recorded, not rendered."""

    environment: Environment
    line: int | None = None
