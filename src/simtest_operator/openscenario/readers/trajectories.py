"""Reading trajectories (polyline, clothoid, clothoid spline, NURBS) into the model."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import positions as p
from simtest_operator.openscenario.model import trajectories as t
from simtest_operator.openscenario.readers import positions
from simtest_operator.xmlsafe import Element


def trajectory_or_ref(el: Element, ctx: reading.Context) -> t.Trajectory | m.Unsupported:
    """Read ``<Trajectory>`` or a trajectory ``<CatalogReference>`` (the element itself)."""
    if el.tag == "CatalogReference":
        entry, inner = ctx.catalogs.find(el, ctx, ("Trajectory",))
        return trajectory(entry.element, inner)
    if el.tag == "Trajectory":
        return trajectory(el, ctx)
    return ctx.unsupported(el, f"unexpected trajectory element {el.tag}")


def trajectory(el: Element, ctx: reading.Context) -> t.Trajectory:
    """Read a ``<Trajectory>`` with its parameters and shape."""
    inner, _ = ctx.declarations(el)
    shape_el = inner.choice(inner.require(el, "Shape"))
    return t.Trajectory(
        name=inner.string(el, "name"),
        closed=inner.opt_boolean(el, "closed", False) or False,
        shape=_shape(shape_el, inner),
        line=el.sourceline,
    )


def _optional_position(el: Element | None, ctx: reading.Context) -> p.Position | None:
    return None if el is None else positions.position(el, ctx)


def _shape(el: Element, ctx: reading.Context) -> t.Shape:
    tag, line = el.tag, el.sourceline
    if tag == "Polyline":
        vertices = tuple(
            t.Vertex(
                position=positions.position(ctx.require(v, "Position"), ctx),
                time=ctx.opt_double(v, "time"),
                line=v.sourceline,
            )
            for v in reading.all_children(el, "Vertex")
        )
        if not vertices:
            raise ctx.error(el, "a polyline needs at least one vertex")
        return t.Polyline(vertices=vertices, line=line)
    if tag == "Clothoid":
        prime = ctx.opt_double(el, "curvaturePrime")
        if prime is None:
            prime = ctx.double_or(el, "curvatureDot", 0.0)
        return t.Clothoid(
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
            t.ClothoidSplineSegment(
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
        return t.ClothoidSpline(
            segments=segments, time_end=ctx.opt_double(el, "timeEnd"), line=line
        )
    if tag == "Nurbs":
        points = tuple(
            t.ControlPoint(
                position=positions.position(ctx.require(cp, "Position"), ctx),
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
        return t.Nurbs(order=order, control_points=points, knots=knots, line=line)
    return ctx.unsupported(el, f"unknown trajectory shape {tag}")
