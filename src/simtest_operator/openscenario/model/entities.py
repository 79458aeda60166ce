"""Entities of the scenario model: scenario objects (vehicles, pedestrians, misc objects) and
controllers.

A ScenarioObject is flattened from Vehicle/Pedestrian/MiscObject (inline or from a catalog) into
one shape the engine can place and drive without looking at which XML element it came from.
"""

from __future__ import annotations

import dataclasses

from simtest_operator.openscenario.model.common import Property, Unsupported
from simtest_operator.snapshots import BoundingBox, EntityKind


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Performance:
    """Vehicle limits in m/s, m/s^2 and m/s^3 (rates only from 1.2)."""

    max_speed: float
    max_acceleration: float
    max_deceleration: float
    max_acceleration_rate: float | None = None
    max_deceleration_rate: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Axle:
    """One axle: steering limit (rad), wheel diameter, track width, position in the entity frame."""

    max_steering: float
    wheel_diameter: float
    track_width: float
    position_x: float
    position_z: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Axles:
    """Front (optional since 1.1), rear and additional axles."""

    rear: Axle
    front: Axle | None = None
    additional: tuple[Axle, ...] = ()
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Controller:
    """A controller definition (inline or from a Controller catalog) with its properties.

    Controllers are simulator-specific (esmini uses property ``esminiController``); the engine
    decides what to make of them, typically by name or properties.
    """

    name: str
    controller_type: str | None = None
    """1.2 ``controllerType`` (lateral, longitudinal, lighting, animation, movement, appearance,
    all), when given."""
    properties: tuple[Property, ...] = ()
    files: tuple[str, ...] = ()
    """``<File filepath>`` entries of the properties, as written."""
    line: int | None = None

    def property(self, name: str) -> str | None:
        """Value of the property called ``name``, or None."""
        for prop in self.properties:
            if prop.name == name:
                return prop.value
        return None

    def number(self, name: str, default: float) -> float:
        """Property ``name`` as a number; ``default`` when absent or not a number (as esmini's
        controllers read their properties)."""
        text = self.property(name)
        try:
            return float(text) if text is not None else default
        except ValueError:
            return default

    def flag(self, name: str, default: bool) -> bool:
        """Property ``name`` as a boolean (``true`` in any case); ``default`` when absent."""
        text = self.property(name)
        return default if text is None else text.strip().lower() == "true"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ObjectController:
    """One ``<ObjectController>`` of an entity (1.3 allows several, selected by name)."""

    controller: Controller | Unsupported
    name: str | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioObject:
    """One entity of the scenario."""

    name: str
    kind: EntityKind
    category: str
    """vehicleCategory (car, truck, bicycle, ...), pedestrianCategory (pedestrian, wheelchair,
    animal) or miscObjectCategory (obstacle, pole, ...)."""
    bounding_box: BoundingBox
    model_name: str | None = None
    """Vehicle/Pedestrian/MiscObject ``name`` attribute (for catalog objects the entry name)."""
    catalog_entry: str | None = None
    """Catalog entry name when the object came from a catalog."""
    role: str | None = None
    """1.2 vehicle role (none, ambulance, police, ...)."""
    mass: float | None = None
    performance: Performance | None = None
    axles: Axles | None = None
    properties: tuple[Property, ...] = ()
    controller: Controller | Unsupported | None = None
    """ObjectController's controller; None when the object has no controller (default driver)."""
    object_controller_name: str | None = None
    """1.3 ``ObjectController name`` of ``controller``, if named."""
    object_controllers: tuple[ObjectController, ...] = ()
    """All ObjectControllers in file order (``controller`` is the first one's controller); 1.3
    ActivateControllerAction ``objectControllerRef`` selects among them by name."""
    unsupported: Unsupported | None = None
    """Set when the object itself cannot be simulated (e.g. ExternalObjectReference); the other
    fields then hold defaults."""
    trailer_hitch: float | None = None
    """``TrailerHitch dx``: where a trailer is pulled, metres ahead of the reference point."""
    trailer_coupler: float | None = None
    """``TrailerCoupler dx``: where this (trailer) vehicle is pulled, metres ahead of its
    reference point."""
    trailer: str | None = None
    """Entity towed at the start (``TrailerRef``, or the inline ``Trailer`` that loading adds as
    the entity ``<name>+``, esmini's name for it)."""
    inline_trailer: ScenarioObject | None = None
    """An inline ``Trailer`` as read, before loading adds it to the entities."""
    line: int | None = None

    def property(self, name: str) -> str | None:
        """Value of the property called ``name``, or None."""
        for prop in self.properties:
            if prop.name == name:
                return prop.value
        return None
