"""Reading ScenarioObjects (vehicles, pedestrians, misc objects) into the model."""

from __future__ import annotations

import re

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import entities as e
from simtest_operator.openscenario.readers import controllers
from simtest_operator.snapshots import BoundingBox, EntityKind
from simtest_operator.xmlsafe import Element

VEHICLE_CATEGORIES = frozenset(
    {
        "bicycle",
        "bus",
        "car",
        "motorbike",
        "semitrailer",
        "trailer",
        "train",
        "tram",
        "truck",
        "van",
    }
)
"""The schema's VehicleCategory values."""

MIN_BOX_SIZE = 0.01
"""Shortest bounding-box length or width (m): a smaller box cannot collide, and a collision with
it became a pass (issue 29)."""
CARLA_BLUEPRINT = re.compile(r"(vehicle|walker|static)\.")
"""A model name that is a CARLA blueprint id: CARLA spawns the blueprint and ignores the box."""
CARLA_SIZES = {
    EntityKind.VEHICLE: (4.9, 2.1, 1.5),
    EntityKind.PEDESTRIAN: (0.5, 0.5, 1.8),
    EntityKind.MISC_OBJECT: (1.0, 1.0, 1.0),
}
"""Length, width, height (m) a zero box in a CARLA file is read as: typical of CARLA's car and
walker blueprints (a walker is a capsule about 0.5 m across; the simulator gives every walker of
a ScenarioRunner file this size, ``sim.carla.WALKER_BOX``); 1 m for a prop (a cone is smaller, a
container larger)."""
CARLA_TWO_WHEELERS = (1.8, 0.8, 1.6)
"""The same for ``bicycle`` and ``motorbike`` vehicles."""

_KINDS = {
    "Vehicle": (EntityKind.VEHICLE, "vehicleCategory"),
    "Pedestrian": (EntityKind.PEDESTRIAN, "pedestrianCategory"),
    "MiscObject": (EntityKind.MISC_OBJECT, "miscObjectCategory"),
}


def scenario_object(el: Element, ctx: reading.Context) -> e.ScenarioObject:
    """Read one ``<ScenarioObject>`` (resolving its catalog reference and controller)."""
    name = ctx.string(el, "name")
    chosen = ctx.choice(el)
    catalog_entry: str | None = None
    body, body_ctx = chosen, ctx
    if chosen.tag == "CatalogReference":
        entry, body_ctx = ctx.catalogs.find(chosen, ctx, tuple(_KINDS))
        body, catalog_entry = entry.element, entry.entry_name
    owned = controllers.object_controllers(el, ctx)
    if body.tag not in _KINDS:
        return e.ScenarioObject(
            name=name,
            kind=EntityKind.VEHICLE,
            category="unknown",
            bounding_box=BoundingBox(),
            controller=owned[0].controller if owned else None,
            object_controller_name=owned[0].name if owned else None,
            object_controllers=owned,
            unsupported=ctx.unsupported(body, f"{body.tag} entities are not supported", name=name),
            line=el.sourceline,
        )
    return _object(
        body,
        body_ctx,
        name=name,
        catalog_entry=catalog_entry,
        owned=owned,
        line=el.sourceline,
    )


def _object(
    el: Element,
    ctx: reading.Context,
    *,
    name: str,
    catalog_entry: str | None,
    owned: tuple[e.ObjectController, ...],
    line: int | None,
) -> e.ScenarioObject:
    inner, _ = ctx.declarations(el)
    kind, category_attr = _KINDS[str(el.tag)]
    category = inner.opt_string(el, category_attr)
    if category is None:
        # 1.0 pedestrians may omit the category; vehicles and misc objects may not.
        if kind is not EntityKind.PEDESTRIAN:
            raise inner.error(el, f"missing required attribute {category_attr!r}")
        category = "pedestrian"
    if kind is EntityKind.VEHICLE and category not in VEHICLE_CATEGORIES:
        inner.deviation(
            el,
            "vehicle-category-unknown",
            f"vehicleCategory {category!r} is not one of the schema's; kept as written",
        )
    props, _ = controllers.properties(reading.child(el, "Properties"), inner)
    trailer_ref, inline_trailer = _trailer(reading.child(el, "Trailer"), inner)
    return e.ScenarioObject(
        name=name,
        kind=kind,
        category=category,
        bounding_box=_bounding_box(
            inner.require(el, "BoundingBox"), inner, kind, category, inner.opt_string(el, "name")
        ),
        model_name=inner.opt_string(el, "name"),
        catalog_entry=catalog_entry,
        role=inner.opt_string(el, "role"),
        mass=inner.opt_double(el, "mass"),
        performance=_performance(reading.child(el, "Performance"), inner),
        axles=_axles(reading.child(el, "Axles"), inner),
        properties=props,
        controller=owned[0].controller if owned else None,
        object_controller_name=owned[0].name if owned else None,
        object_controllers=owned,
        trailer_hitch=_dx(reading.child(el, "TrailerHitch"), inner),
        trailer_coupler=_dx(reading.child(el, "TrailerCoupler"), inner),
        trailer=trailer_ref,
        inline_trailer=inline_trailer,
        line=line,
    )


def _dx(el: Element | None, ctx: reading.Context) -> float | None:
    return ctx.double(el, "dx") if el is not None else None


def _trailer(
    el: Element | None, ctx: reading.Context
) -> tuple[str | None, e.ScenarioObject | None]:
    """The towed entity of a ``<Trailer>``: a ``TrailerRef`` name, or an inline trailer (that
    loading names and adds to the entities)."""
    if el is None:
        return None, None
    ref = reading.child(el, "TrailerRef")
    if ref is not None:
        # Catalog vehicles declare <TrailerRef entityRef="$TrailerRef"/> with an empty default,
        # meaning "no trailer".
        name = ctx.string(ref, "entityRef").strip()
        return (name or None), None
    return None, scenario_object(ctx.require(el, "Trailer"), ctx)


def _bounding_box(
    el: Element, ctx: reading.Context, kind: EntityKind, category: str, model: str | None
) -> BoundingBox:
    center = ctx.require(el, "Center")
    dims = ctx.require(el, "Dimensions")
    box = BoundingBox(
        center_x=ctx.double(center, "x"),
        center_y=ctx.double(center, "y"),
        center_z=ctx.double(center, "z"),
        length=ctx.double(dims, "length", minimum=0.0),
        width=ctx.double(dims, "width", minimum=0.0),
        height=ctx.double(dims, "height", minimum=0.0),
    )
    if min(box.length, box.width) >= MIN_BOX_SIZE:
        return box
    written = f"bounding box {box.length:g} x {box.width:g} m"
    if not (ctx.carla_frame or (model is not None and CARLA_BLUEPRINT.match(model))):
        raise ctx.error(
            dims,
            f"{written} cannot collide: length and width must be at least {MIN_BOX_SIZE:g} m",
        )
    # CARLA files give props and walkers no size: CARLA spawns the named blueprint instead.
    two_wheeler = kind is EntityKind.VEHICLE and category in ("bicycle", "motorbike")
    length, width, height = CARLA_TWO_WHEELERS if two_wheeler else CARLA_SIZES[kind]
    ctx.deviation(
        dims,
        "bounding-box-zero-size",
        f"{written} of CARLA blueprint {model or '(CARLA: file)'} read as {length:g} x {width:g} "
        f"x {height:g} m, the blueprint's typical size",
    )
    return BoundingBox(
        center_x=box.center_x,
        center_y=box.center_y,
        center_z=box.center_z,
        length=length,
        width=width,
        height=height,
    )


def _performance(el: Element | None, ctx: reading.Context) -> e.Performance | None:
    if el is None:
        return None
    return e.Performance(
        max_speed=ctx.double(el, "maxSpeed", minimum=0.0),
        max_acceleration=ctx.double(el, "maxAcceleration", minimum=0.0),
        max_deceleration=ctx.double(el, "maxDeceleration", minimum=0.0),
        max_acceleration_rate=ctx.opt_double(el, "maxAccelerationRate", minimum=0.0),
        max_deceleration_rate=ctx.opt_double(el, "maxDecelerationRate", minimum=0.0),
        line=el.sourceline,
    )


def _axle(el: Element, ctx: reading.Context) -> e.Axle:
    return e.Axle(
        max_steering=ctx.double(el, "maxSteering"),
        wheel_diameter=ctx.double(el, "wheelDiameter"),
        track_width=ctx.double(el, "trackWidth"),
        position_x=ctx.double(el, "positionX"),
        position_z=ctx.double(el, "positionZ"),
        line=el.sourceline,
    )


def _axles(el: Element | None, ctx: reading.Context) -> e.Axles | None:
    if el is None:
        return None
    front = reading.child(el, "FrontAxle")
    return e.Axles(
        rear=_axle(ctx.require(el, "RearAxle"), ctx),
        front=_axle(front, ctx) if front is not None else None,
        additional=tuple(_axle(x, ctx) for x in reading.all_children(el, "AdditionalAxle")),
        line=el.sourceline,
    )
