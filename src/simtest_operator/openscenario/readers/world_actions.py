"""Reading the global actions that change what is in the world: entities and environment."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import controls as ctl
from simtest_operator.openscenario.readers import positions
from simtest_operator.xmlsafe import Element

_SETTINGS: dict[str, tuple[str, ...]] = {
    "TimeOfDay": ("animation", "dateTime"),
    "Weather": ("cloudState", "fractionalCloudCover", "atmosphericPressure", "temperature"),
    "Weather.Sun": ("intensity", "illuminance", "azimuth", "elevation"),
    "Weather.Fog": ("visualRange",),
    "Weather.Precipitation": ("precipitationType", "intensity", "precipitationIntensity"),
    "Weather.Wind": ("direction", "speed"),
    "RoadCondition": ("frictionScaleFactor", "wetness"),
}
"""The Environment's settings by element path (OpenSCENARIO 1.0 names and the 1.1+ additions)."""


def entity_action(
    el: Element, ctx: reading.Context
) -> ctl.AddEntityAction | ctl.DeleteEntityAction:
    """Read ``<EntityAction entityRef=...>`` with AddEntityAction or DeleteEntityAction."""
    ref = ctx.string(el, "entityRef")
    chosen = ctx.choice(el)
    if chosen.tag == "AddEntityAction":
        return ctl.AddEntityAction(
            entity_ref=ref,
            position=positions.position(ctx.require(chosen, "Position"), ctx),
            line=el.sourceline,
        )
    if chosen.tag == "DeleteEntityAction":
        return ctl.DeleteEntityAction(entity_ref=ref, line=el.sourceline)
    raise ctx.error(chosen, "expected AddEntityAction or DeleteEntityAction")


def environment_action(el: Element, ctx: reading.Context) -> ctl.EnvironmentAction | m.Unsupported:
    """Read ``<EnvironmentAction>``: an inline Environment or an environment catalog entry (its
    entry name may be a parameter, which is how one scenario is run under several weathers).
    Still listed as ignored: the stand-in records the environment but renders none."""
    ctx.ignore("EnvironmentAction")
    chosen = ctx.choice(el)
    if chosen.tag == "CatalogReference":
        entry, inner = ctx.catalogs.find(chosen, ctx, ("Environment",))
        return ctl.EnvironmentAction(
            environment=environment(entry.element, inner), line=el.sourceline
        )
    if chosen.tag == "Environment":
        return ctl.EnvironmentAction(environment=environment(chosen, ctx), line=el.sourceline)
    return ctx.unsupported(chosen, f"unexpected environment element {chosen.tag}")


def environment(el: Element, ctx: reading.Context) -> ctl.Environment:
    """Read an ``<Environment>`` into flat ``Element.attribute`` settings (parameters resolved)."""
    inner, _ = ctx.declarations(el)
    settings: list[tuple[str, str]] = []
    for path, names in _SETTINGS.items():
        node: Element | None = el
        for tag in path.split("."):
            node = reading.child(node, tag) if node is not None else None
        if node is None:
            continue
        for name in names:
            value = inner.opt_string(node, name)
            if value is not None:
                settings.append((f"{path}.{name}", value))
    return ctl.Environment(
        name=inner.string(el, "name"), settings=tuple(settings), line=el.sourceline
    )
