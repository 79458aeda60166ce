"""Reading controllers: Controller definitions, ObjectController, assign/activate actions."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import actions as a
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import controls as ctl
from simtest_operator.openscenario.model import entities as e
from simtest_operator.xmlsafe import Element


def properties(
    el: Element | None, ctx: reading.Context
) -> tuple[tuple[m.Property, ...], tuple[str, ...]]:
    """Read an optional ``<Properties>``: name/value pairs and File paths."""
    if el is None:
        return (), ()
    props = tuple(
        m.Property(
            name=ctx.string(prop, "name"), value=ctx.string(prop, "value"), line=prop.sourceline
        )
        for prop in reading.all_children(el, "Property")
    )
    files = tuple(ctx.string(f, "filepath") for f in reading.all_children(el, "File"))
    return props, files


def controller(el: Element, ctx: reading.Context) -> e.Controller:
    """Read a ``<Controller>`` definition (inline or catalog entry)."""
    inner, _ = ctx.declarations(el)
    props, files = properties(reading.child(el, "Properties"), inner)
    return e.Controller(
        name=inner.string(el, "name"),
        controller_type=inner.opt_string(el, "controllerType"),
        properties=props,
        files=files,
        line=el.sourceline,
    )


def controller_or_ref(el: Element, ctx: reading.Context) -> e.Controller | m.Unsupported:
    """Read ``<Controller>``, a controller ``<CatalogReference>`` or an ``<ObjectController>``."""
    if el.tag == "ObjectController":
        return controller_or_ref(ctx.choice(el), ctx)
    if el.tag == "CatalogReference":
        entry, inner = ctx.catalogs.find(el, ctx, ("Controller",))
        return controller(entry.element, inner)
    if el.tag == "Controller":
        return controller(el, ctx)
    return ctx.unsupported(el, f"unexpected controller element {el.tag}")


def object_controllers(
    scenario_object: Element, ctx: reading.Context
) -> tuple[e.ObjectController, ...]:
    """All ObjectControllers of a ScenarioObject, in file order."""
    return tuple(
        e.ObjectController(
            controller=controller_or_ref(ctx.choice(node), ctx),
            name=ctx.opt_string(node, "name"),
            line=node.sourceline,
        )
        for node in reading.all_children(scenario_object, "ObjectController")
    )


def activate(el: Element, ctx: reading.Context) -> ctl.ActivateControllerAction:
    """Read an ``<ActivateControllerAction>``."""
    return ctl.ActivateControllerAction(
        lateral=ctx.opt_boolean(el, "lateral"),
        longitudinal=ctx.opt_boolean(el, "longitudinal"),
        lighting=ctx.opt_boolean(el, "lighting"),
        animation=ctx.opt_boolean(el, "animation"),
        controller_ref=ctx.opt_string(el, "controllerRef"),
        object_controller_ref=ctx.opt_string(el, "objectControllerRef"),
        line=el.sourceline,
    )


def controller_action(el: Element, ctx: reading.Context) -> a.PrivateAction:
    """Read a ``<ControllerAction>``.

    1.0 requires AssignControllerAction plus OverrideControllerValueAction; 1.1 allows any
    combination of assign/override/activate; 1.2+ exactly one. Assign and activate are merged
    into one AssignControllerAction (activate flags filled from the ActivateControllerAction).
    An override with an active value (or alone) is listed as ignored: its values replace the
    pedal, steering and gear inputs of a controller that reads them, which no motion here does
    (esmini's default motion drives on unchanged, ``override_action.xosc``); alone it completes
    at once.
    """
    assign = reading.child(el, "AssignControllerAction")
    activate_el = reading.child(el, "ActivateControllerAction")
    override = reading.child(el, "OverrideControllerValueAction")
    if override is not None and _override_active(override, ctx):
        ctx.ignore("OverrideControllerValueAction")
    switch = activate(activate_el, ctx) if activate_el is not None else None
    if assign is not None:
        lateral = ctx.opt_boolean(assign, "activateLateral")
        longitudinal = ctx.opt_boolean(assign, "activateLongitudinal")
        lighting = ctx.opt_boolean(assign, "activateLighting")
        animation = ctx.opt_boolean(assign, "activateAnimation")
        return ctl.AssignControllerAction(
            controller=controller_or_ref(ctx.choice(assign), ctx),
            activate_lateral=lateral if switch is None or lateral is not None else switch.lateral,
            activate_longitudinal=longitudinal
            if switch is None or longitudinal is not None
            else switch.longitudinal,
            activate_lighting=lighting
            if switch is None or lighting is not None
            else switch.lighting,
            activate_animation=animation
            if switch is None or animation is not None
            else switch.animation,
            line=assign.sourceline,
        )
    if switch is not None:
        return switch
    if override is not None:
        ctx.ignore("OverrideControllerValueAction")
        return ctl.IgnoredAction(kind="OverrideControllerValueAction", line=override.sourceline)
    return ctx.unsupported(ctx.choice(el), "unknown controller action")


def _override_active(el: Element, ctx: reading.Context) -> bool:
    return any(ctx.opt_boolean(node, "active", False) for node in reading.children(el))
