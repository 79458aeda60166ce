"""Reading positions, orientations, routes and trajectories into the model.

Routes and trajectories (polyline, clothoid, clothoid spline, NURBS) are read here because they
hold positions and positions refer to them (RoutePosition, TrajectoryPosition).

Three conventions of files written for CARLA are read here. A file whose FileHeader description
starts with ``CARLA:`` gives positions in CARLA's left-handed frame (ScenarioRunner's
``use_carla_coordinate_system``): y, dy and headings are negated into OpenDRIVE's frame. Lateral
offsets from the road (``t``, ``dt``, ``offset``, and a LaneOffsetAction's target) are positive
to the right in every file ScenarioRunner runs (``Context.right_offsets``: the ``CARLA:`` files
and those under its rules) and are negated too. A whole-number heading beyond one turn
(``h="180"``, ``h="-90"``) is degrees, which CARLA files write; it is converted with a deviation.
Fractional ones stay radians (esmini's tests write ``h="7.853981633974483"``, 2.5 pi).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import positions as p
from simtest_operator.xmlsafe import Element


def orientation(el: Element | None, ctx: reading.Context) -> m.Orientation | None:
    """Read an optional ``<Orientation>``."""
    if el is None:
        return None
    return m.Orientation(
        type=ctx.opt_enum(el, "type", m.ReferenceContext),
        h=_heading(el, ctx, "h") or 0.0,
        p=ctx.double_or(el, "p", 0.0),
        r=ctx.double_or(el, "r", 0.0),
        line=el.sourceline,
    )


TURN = 2.0 * math.pi
"""A whole-number heading beyond one turn is read as degrees."""


def _heading(el: Element, ctx: reading.Context, name: str) -> float | None:
    value = ctx.opt_double(el, name)
    if value is None:
        return None
    if abs(value) > TURN and value.is_integer():
        ctx.deviation(el, "heading-in-degrees", f"{name}={value:g} read as degrees")
        value = math.radians(value)
    return -value if ctx.carla_frame else value


def _y(ctx: reading.Context, value: float) -> float:
    """A y or dy: CARLA's frame has y the other way."""
    return -value if ctx.carla_frame else value


def lateral(ctx: reading.Context, value: float) -> float:
    """A lateral offset from the road (also a LaneOffsetAction's target): positive to the right
    in ScenarioRunner's files."""
    return -value if ctx.right_offsets else value


def _orientation_of(el: Element, ctx: reading.Context) -> m.Orientation | None:
    return orientation(reading.child(el, "Orientation"), ctx)


def position(el: Element, ctx: reading.Context) -> p.Position:
    """Read a ``<Position>`` wrapper (its one chosen child)."""
    return position_choice(ctx.choice(el), ctx)


def position_choice(el: Element, ctx: reading.Context) -> p.Position:
    """Read the concrete position element (WorldPosition, LanePosition, ...)."""
    return ctx.by_tag(
        el,
        _POSITION_READERS,
        unknown="unknown position kind",
        reasons={"GeoPosition": "GeoPosition is not supported (needs a geo projection)"},
    )


def _world(el: Element, ctx: reading.Context) -> p.WorldPosition:
    return p.WorldPosition(
        x=ctx.double(el, "x"),
        y=_y(ctx, ctx.double(el, "y")),
        z=ctx.opt_double(el, "z"),
        h=_heading(el, ctx, "h"),
        p=ctx.opt_double(el, "p"),
        r=ctx.opt_double(el, "r"),
        line=el.sourceline,
    )


def _relative_world_or_object(
    el: Element, ctx: reading.Context
) -> p.RelativeWorldPosition | p.RelativeObjectPosition:
    relative_world = el.tag == "RelativeWorldPosition"
    kind = p.RelativeWorldPosition if relative_world else p.RelativeObjectPosition
    return kind(
        entity_ref=ctx.string(el, "entityRef"),
        dx=ctx.double(el, "dx"),
        dy=_y(ctx, ctx.double(el, "dy")),
        dz=ctx.opt_double(el, "dz"),
        orientation=_orientation_of(el, ctx),
        line=el.sourceline,
    )


def _road(el: Element, ctx: reading.Context) -> p.RoadPosition:
    return p.RoadPosition(
        road_id=ctx.string(el, "roadId"),
        s=ctx.double(el, "s"),
        t=lateral(ctx, ctx.double(el, "t")),
        orientation=_orientation_of(el, ctx),
        line=el.sourceline,
    )


def _relative_road(el: Element, ctx: reading.Context) -> p.RelativeRoadPosition:
    return p.RelativeRoadPosition(
        entity_ref=ctx.string(el, "entityRef"),
        ds=ctx.double(el, "ds"),
        dt=lateral(ctx, ctx.double(el, "dt")),
        orientation=_orientation_of(el, ctx),
        line=el.sourceline,
    )


def _lane(el: Element, ctx: reading.Context) -> p.LanePosition:
    return p.LanePosition(
        road_id=ctx.string(el, "roadId"),
        lane_id=ctx.integer(el, "laneId"),
        s=ctx.double(el, "s"),
        offset=lateral(ctx, ctx.double_or(el, "offset", 0.0)),
        orientation=_orientation_of(el, ctx),
        line=el.sourceline,
    )


def _relative_lane(el: Element, ctx: reading.Context) -> p.RelativeLanePosition:
    ds = ctx.opt_double(el, "ds")
    ds_lane = ctx.opt_double(el, "dsLane")
    if ds is None and ds_lane is None:
        # esmini reads the missing distance as 0 (no move along the road), as a 1.0 file's
        # required ds="0" would be
        ctx.deviation(
            el, "relative-lane-position-without-ds", "neither 'ds' nor 'dsLane' given: ds read as 0"
        )
        ds = 0.0
    return p.RelativeLanePosition(
        entity_ref=ctx.string(el, "entityRef"),
        d_lane=ctx.integer(el, "dLane"),
        ds=ds,
        ds_lane=ds_lane,
        offset=lateral(ctx, ctx.double_or(el, "offset", 0.0)),
        orientation=_orientation_of(el, ctx),
        line=el.sourceline,
    )


def _trajectory_position(el: Element, ctx: reading.Context) -> p.TrajectoryPosition:
    return p.TrajectoryPosition(
        trajectory=trajectory_or_ref(ctx.choice(ctx.require(el, "TrajectoryRef")), ctx),
        s=ctx.double(el, "s"),
        t=lateral(ctx, ctx.double_or(el, "t", 0.0)),
        orientation=_orientation_of(el, ctx),
        line=el.sourceline,
    )


def _route_orientation(
    el: Element, in_route: Element, ctx: reading.Context
) -> m.Orientation | None:
    """The Orientation of a RoutePosition; one written after InRoutePosition is ignored.

    The schema puts Orientation before InRoutePosition. esmini reads the children in document
    order and places the entity when it meets InRoutePosition, so a later Orientation never
    turns it: the Euro NCAP far-side obstruction vehicles (``h="3.14159"`` after the position)
    face along their lane there. Ignoring it, with a deviation, keeps the placement esmini's.
    """
    found = reading.child(el, "Orientation")
    if found is not None and list(el).index(found) > list(el).index(in_route):
        ctx.deviation(
            found,
            "route-orientation-after-position",
            "Orientation after InRoutePosition (the schema puts it before) ignored, as esmini "
            "reads it",
        )
        return None
    return orientation(found, ctx)


def _route_position(el: Element, ctx: reading.Context) -> p.RoutePosition:
    route_ref = ctx.require(el, "RouteRef")
    in_route_parent = ctx.require(el, "InRoutePosition")
    in_route_el = ctx.choice(in_route_parent)
    in_route: p.InRoutePosition
    if in_route_el.tag == "FromCurrentEntity":
        in_route = p.FromCurrentEntity(
            entity_ref=ctx.string(in_route_el, "entityRef"), line=in_route_el.sourceline
        )
    elif in_route_el.tag == "FromRoadCoordinates":
        in_route = p.FromRoadCoordinates(
            path_s=ctx.double(in_route_el, "pathS"),
            t=ctx.double(in_route_el, "t"),
            line=in_route_el.sourceline,
        )
    elif in_route_el.tag == "FromLaneCoordinates":
        in_route = p.FromLaneCoordinates(
            path_s=ctx.double(in_route_el, "pathS"),
            lane_id=ctx.integer(in_route_el, "laneId"),
            lane_offset=ctx.double_or(in_route_el, "laneOffset", 0.0),
            line=in_route_el.sourceline,
        )
    else:
        raise ctx.error(in_route_el, "unknown InRoutePosition kind")
    return p.RoutePosition(
        route=route_or_ref(route_ref, ctx),
        in_route=in_route,
        orientation=_route_orientation(el, in_route_parent, ctx),
        line=el.sourceline,
    )


def route_or_ref(el: Element, ctx: reading.Context) -> p.Route | m.Unsupported:
    """Read a route from an element holding ``<Route>`` or a ``<CatalogReference>``."""
    chosen = ctx.choice(el)
    if chosen.tag == "CatalogReference":
        entry, inner = ctx.catalogs.find(chosen, ctx, ("Route",))
        return route(entry.element, inner)
    if chosen.tag == "Route":
        return route(chosen, ctx)
    return ctx.unsupported(chosen, f"unexpected route element {chosen.tag}")


def route(el: Element, ctx: reading.Context) -> p.Route:
    """Read a ``<Route>`` (its parameters, waypoints)."""
    inner, _ = ctx.declarations(el)
    waypoints = tuple(
        p.Waypoint(
            position=position(inner.require(wp, "Position"), inner),
            route_strategy=inner.enum(wp, "routeStrategy", p.RouteStrategy),
            line=wp.sourceline,
        )
        for wp in reading.all_children(el, "Waypoint")
    )
    if len(waypoints) < 2:
        raise inner.error(el, "a route needs at least two waypoints")
    return p.Route(
        name=inner.string(el, "name"),
        closed=inner.opt_boolean(el, "closed", False) or False,
        waypoints=waypoints,
        line=el.sourceline,
    )


def trajectory_or_ref(el: Element, ctx: reading.Context) -> p.Trajectory | m.Unsupported:
    """Read ``<Trajectory>`` or a trajectory ``<CatalogReference>`` (the element itself)."""
    if el.tag == "CatalogReference":
        entry, inner = ctx.catalogs.find(el, ctx, ("Trajectory",))
        return trajectory(entry.element, inner)
    if el.tag == "Trajectory":
        return trajectory(el, ctx)
    return ctx.unsupported(el, f"unexpected trajectory element {el.tag}")


def trajectory(el: Element, ctx: reading.Context) -> p.Trajectory:
    """Read a ``<Trajectory>`` with its parameters and shape."""
    inner, _ = ctx.declarations(el)
    shape_el = inner.choice(inner.require(el, "Shape"))
    return p.Trajectory(
        name=inner.string(el, "name"),
        closed=inner.opt_boolean(el, "closed", False) or False,
        shape=_shape(shape_el, inner),
        line=el.sourceline,
    )


def _optional_position(el: Element | None, ctx: reading.Context) -> p.Position | None:
    return None if el is None else position(el, ctx)


def _shape(el: Element, ctx: reading.Context) -> p.Shape:
    tag, line = el.tag, el.sourceline
    if tag == "Polyline":
        vertices = tuple(
            p.Vertex(
                position=position(ctx.require(v, "Position"), ctx),
                time=ctx.opt_double(v, "time"),
                line=v.sourceline,
            )
            for v in reading.all_children(el, "Vertex")
        )
        if not vertices:
            raise ctx.error(el, "a polyline needs at least one vertex")
        return p.Polyline(vertices=vertices, line=line)
    if tag == "Clothoid":
        prime = ctx.opt_double(el, "curvaturePrime")
        if prime is None:
            prime = ctx.double_or(el, "curvatureDot", 0.0)
        return p.Clothoid(
            curvature=ctx.double(el, "curvature"),
            curvature_prime=prime,
            length=ctx.double(el, "length"),
            start_time=ctx.opt_double(el, "startTime"),
            stop_time=ctx.opt_double(el, "stopTime"),
            position=_optional_position(reading.child(el, "Position"), ctx),
            line=line,
        )
    if tag == "ClothoidSpline":
        segments = tuple(
            p.ClothoidSplineSegment(
                curvature_start=ctx.double(seg, "curvatureStart"),
                curvature_end=ctx.double(seg, "curvatureEnd"),
                length=ctx.double(seg, "length"),
                h_offset=ctx.double_or(seg, "hOffset", 0.0),
                time_start=ctx.opt_double(seg, "timeStart"),
                position_start=_optional_position(reading.child(seg, "PositionStart"), ctx),
                line=seg.sourceline,
            )
            for seg in reading.all_children(el, "ClothoidSplineSegment")
        )
        if not segments:
            raise ctx.error(el, "a clothoid spline needs at least one segment")
        return p.ClothoidSpline(
            segments=segments, time_end=ctx.opt_double(el, "timeEnd"), line=line
        )
    if tag == "Nurbs":
        points = tuple(
            p.ControlPoint(
                position=position(ctx.require(cp, "Position"), ctx),
                time=ctx.opt_double(cp, "time"),
                weight=ctx.opt_double(cp, "weight"),
                line=cp.sourceline,
            )
            for cp in reading.all_children(el, "ControlPoint")
        )
        knots = tuple(ctx.double(k, "value") for k in reading.all_children(el, "Knot"))
        order = ctx.integer(el, "order")
        if len(points) < 2 or len(knots) != len(points) + order:
            raise ctx.error(
                el,
                f"NURBS needs >= 2 control points and control points + order knots "
                f"(got {len(points)} points, order {order}, {len(knots)} knots)",
            )
        return p.Nurbs(order=order, control_points=points, knots=knots, line=line)
    return ctx.unsupported(el, f"unknown trajectory shape {tag}")


_POSITION_READERS: Mapping[str, Callable[[Element, reading.Context], p.Position]] = {
    "WorldPosition": _world,
    "RelativeWorldPosition": _relative_world_or_object,
    "RelativeObjectPosition": _relative_world_or_object,
    "RoadPosition": _road,
    "RelativeRoadPosition": _relative_road,
    "LanePosition": _lane,
    "RelativeLanePosition": _relative_lane,
    "RoutePosition": _route_position,
    "TrajectoryPosition": _trajectory_position,
}
"""Supported position kinds by tag (GeoPosition and unknown ones read as Unsupported)."""
