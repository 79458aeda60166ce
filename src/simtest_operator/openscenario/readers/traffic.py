"""Reading ``<TrafficAction>`` (swarms, sources, sinks, stop) into the model.

Across versions: 1.0 ``velocity``, 1.2 ``SpeedRange``, 1.3 ``InitialSpeedRange`` and the source's
``speed``; all are read. The ControllerDistribution is kept by name only and recorded as ignored
(SUMO's driver models drive the traffic). The 1.3 TrafficDistribution (entity templates) and
TrafficAreaAction are Unsupported.
"""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import traffic as t
from simtest_operator.openscenario.readers import positions
from simtest_operator.xmlsafe import Element


def traffic_action(el: Element, ctx: reading.Context) -> t.TrafficAction | m.Unsupported:
    """Read a ``<TrafficAction>`` (its ``trafficName`` names the traffic for a stop action)."""
    name = ctx.opt_string(el, "trafficName")
    chosen = ctx.choice(el)
    tag, line = chosen.tag, chosen.sourceline
    if tag == "TrafficStopAction":
        return t.TrafficStopAction(traffic_name=name, line=line)
    if tag == "TrafficAreaAction":
        return ctx.unsupported(chosen, "traffic areas are not supported")
    if reading.child(chosen, "TrafficDistribution") is not None and (
        reading.child(chosen, "TrafficDefinition") is None
    ):
        return ctx.unsupported(
            chosen, "TrafficDistribution (entity templates) is not supported; use TrafficDefinition"
        )
    definition = _definition(reading.child(chosen, "TrafficDefinition"), ctx)
    if tag == "TrafficSwarmAction":
        central = ctx.require(chosen, "CentralObject")
        return t.TrafficSwarmAction(
            central_entity=ctx.string(central, "entityRef"),
            inner_radius=_non_negative(chosen, "innerRadius", ctx),
            semi_major_axis=_non_negative(chosen, "semiMajorAxis", ctx),
            semi_minor_axis=_non_negative(chosen, "semiMinorAxis", ctx),
            offset=ctx.double(chosen, "offset"),
            number_of_vehicles=ctx.integer(chosen, "numberOfVehicles"),
            velocity=ctx.opt_double(chosen, "velocity"),
            speed_range=_speed_range(chosen, ctx),
            direction=_direction(reading.child(chosen, "DirectionOfTravelDistribution"), ctx),
            definition=definition,
            traffic_name=name,
            line=line,
        )
    if tag == "TrafficSourceAction":
        speed = ctx.opt_double(chosen, "speed")
        return t.TrafficSourceAction(
            position=positions.position(ctx.require(chosen, "Position"), ctx),
            radius=_non_negative(chosen, "radius", ctx),
            rate=_non_negative(chosen, "rate", ctx),
            speed=speed if speed is not None else ctx.opt_double(chosen, "velocity"),
            definition=definition,
            traffic_name=name,
            line=line,
        )
    if tag == "TrafficSinkAction":
        rate = ctx.opt_double(chosen, "rate")
        if rate is not None and rate < 0.0:
            raise ctx.error(chosen, "attribute 'rate' must not be negative")
        return t.TrafficSinkAction(
            position=positions.position(ctx.require(chosen, "Position"), ctx),
            radius=_non_negative(chosen, "radius", ctx),
            rate=rate,
            definition=definition,
            traffic_name=name,
            line=line,
        )
    return ctx.unsupported(chosen, f"unknown traffic action {tag}")


def _non_negative(el: Element, name: str, ctx: reading.Context) -> float:
    value = ctx.double(el, name)
    if value < 0.0:
        raise ctx.error(el, f"attribute {name!r} must not be negative")
    return value


def _speed_range(el: Element, ctx: reading.Context) -> t.SpeedRange | None:
    node = reading.child(el, "InitialSpeedRange")
    if node is None:
        node = reading.child(el, "SpeedRange")
    if node is None:
        return None
    lower, upper = ctx.double(node, "lowerLimit"), ctx.double(node, "upperLimit")
    if lower < 0.0 or upper < lower:
        raise ctx.error(node, "speed range needs 0 <= lowerLimit <= upperLimit")
    return t.SpeedRange(lower=lower, upper=upper, line=node.sourceline)


def _direction(el: Element | None, ctx: reading.Context) -> t.DirectionOfTravel | None:
    if el is None:
        return None
    same, opposite = ctx.double(el, "same"), ctx.double(el, "opposite")
    if same < 0.0 or opposite < 0.0 or same + opposite <= 0.0:
        raise ctx.error(el, "direction weights must be non-negative and not both zero")
    return t.DirectionOfTravel(same=same, opposite=opposite, line=el.sourceline)


def _definition(el: Element | None, ctx: reading.Context) -> t.TrafficDefinition | None:
    if el is None:
        return None
    categories = tuple(
        t.CategoryWeight(
            category=ctx.string(entry, "category"),
            weight=_non_negative(entry, "weight", ctx),
            line=entry.sourceline,
        )
        for entry in reading.all_children(
            ctx.require(el, "VehicleCategoryDistribution"), "VehicleCategoryDistributionEntry"
        )
    )
    if not categories or sum(c.weight for c in categories) <= 0.0:
        raise ctx.error(el, "a VehicleCategoryDistribution needs an entry with positive weight")
    controllers: list[t.ControllerWeight] = []
    holder = reading.child(el, "ControllerDistribution")
    entries = (
        reading.all_children(holder, "ControllerDistributionEntry") if holder is not None else []
    )
    for entry in entries:
        chosen = ctx.choice(entry)
        attribute = "entryName" if chosen.tag == "CatalogReference" else "name"
        controllers.append(
            t.ControllerWeight(
                controller=ctx.string(chosen, attribute),
                weight=_non_negative(entry, "weight", ctx),
                line=entry.sourceline,
            )
        )
    if controllers:
        ctx.ignore("ControllerDistribution")
    return t.TrafficDefinition(
        name=ctx.string(el, "name"),
        categories=categories,
        controllers=tuple(controllers),
        line=el.sourceline,
    )
