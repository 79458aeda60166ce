"""Reading the RoadNetwork's ``TrafficSignals``: controllers and their phases."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import scenarios as s
from simtest_operator.xmlsafe import Element


def controllers(el: Element | None, ctx: reading.Context) -> tuple[s.TrafficSignalController, ...]:
    """The ``TrafficSignalController``s of ``<TrafficSignals>``; names are unique and a
    ``reference`` names another controller, without a circle of references."""
    if el is None:
        return ()
    found = tuple(
        _controller(child, ctx) for child in reading.all_children(el, "TrafficSignalController")
    )
    names = [controller.name for controller in found]
    for controller in found:
        if names.count(controller.name) > 1:
            raise ctx.error(el, f"traffic signal controller {controller.name!r} is declared twice")
        if controller.reference is not None and controller.reference not in names:
            raise ctx.error(
                el,
                f"traffic signal controller {controller.name!r} references unknown controller "
                f"{controller.reference!r}",
            )
    by_name = {controller.name: controller for controller in found}
    for controller in found:
        seen = {controller.name}
        reference = controller.reference
        while reference is not None:
            if reference in seen:
                raise ctx.error(
                    el, f"traffic signal controller {controller.name!r} references itself"
                )
            seen.add(reference)
            reference = by_name[reference].reference
    return found


def _controller(el: Element, ctx: reading.Context) -> s.TrafficSignalController:
    return s.TrafficSignalController(
        name=ctx.string(el, "name"),
        phases=tuple(_phase(phase, ctx) for phase in reading.all_children(el, "Phase")),
        delay=ctx.double_or(el, "delay", 0.0, minimum=0.0),
        reference=ctx.opt_string(el, "reference") or None,
        line=el.sourceline,
    )


def _phase(el: Element, ctx: reading.Context) -> s.Phase:
    if reading.child(el, "TrafficSignalGroupState") is not None:
        ctx.ignore("TrafficSignalGroupState")
    return s.Phase(
        name=ctx.string(el, "name"),
        duration=ctx.double(el, "duration", minimum=0.0),
        states=tuple(
            (ctx.string(state, "trafficSignalId"), ctx.string(state, "state"))
            for state in reading.all_children(el, "TrafficSignalState")
        ),
    )
