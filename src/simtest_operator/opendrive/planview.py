"""Reference-line evaluation: planView geometries -> (x, y, heading, curvature) at a road's ``s``.

Each geometry primitive becomes a small evaluator prepared once (constants, lookup tables), so a
query costs a bisection plus a few scalar float operations; the simulator calls this for every
entity at every step. Spirals (clothoids) integrate ``cos``/``sin`` of their quadratic heading with
Gauss-Legendre quadrature on sub-intervals of at most 0.5 rad heading change, which is accurate to
machine precision (tests check it against the Fresnel-integral closed form) and avoids importing
scipy (about 0.8 s) at every simulator start. poly3 and paramPoly3 are reparameterised by arc
length, as the reference player esmini does, so ``s`` is the true distance along the curve.
"""

from __future__ import annotations

import bisect
import math
from typing import Protocol

import numpy as np

from simtest_operator.opendrive import models

RefPoint = tuple[float, float, float, float]
"""x, y, heading (rad), curvature (1/m) of the reference line at some s."""

_GL_NODES, _GL_WEIGHTS = (
    tuple(float(value) for value in array) for array in np.polynomial.legendre.leggauss(12)
)
_PARAM_TABLE_STEPS = 256
_MAX_HEADING_STEP = 0.5
_MAX_CHUNKS = 256
"""Quadrature sub-intervals per spiral query: the parser's turn limit (64 rad) needs 128; the cap
keeps a query's cost bounded even for a model that did not come through the parser."""


class _Evaluator(Protocol):
    def at(self, ds: float) -> RefPoint: ...


class _Line:
    __slots__ = ("_cos", "_heading", "_sin", "_x", "_y")

    def __init__(self, geometry: models.Geometry) -> None:
        self._x, self._y, self._heading = geometry.x, geometry.y, geometry.heading
        self._cos, self._sin = math.cos(geometry.heading), math.sin(geometry.heading)

    def at(self, ds: float) -> RefPoint:
        return (self._x + ds * self._cos, self._y + ds * self._sin, self._heading, 0.0)


class _Arc:
    __slots__ = ("_heading", "_k", "_x", "_y")

    def __init__(self, geometry: models.Geometry) -> None:
        self._x, self._y, self._heading = geometry.x, geometry.y, geometry.heading
        self._k = geometry.curvature

    def at(self, ds: float) -> RefPoint:
        k = self._k
        heading = self._heading + k * ds
        if abs(k) < 1e-12:
            return (
                self._x + ds * math.cos(self._heading),
                self._y + ds * math.sin(self._heading),
                heading,
                k,
            )
        return (
            self._x + (math.sin(heading) - math.sin(self._heading)) / k,
            self._y - (math.cos(heading) - math.cos(self._heading)) / k,
            heading,
            k,
        )


class _Spiral:
    """Clothoid: curvature changes linearly from ``curv_start`` to ``curv_end`` over the length."""

    __slots__ = ("_c", "_heading", "_k0", "_x", "_y")

    def __init__(self, geometry: models.Geometry) -> None:
        self._x, self._y, self._heading = geometry.x, geometry.y, geometry.heading
        self._k0 = geometry.curv_start
        rate = (
            (geometry.curv_end - geometry.curv_start) / geometry.length
            if geometry.length > 0
            else 0.0
        )
        self._c = rate if math.isfinite(rate) else 0.0  # sub-picometre spirals overflow

    def at(self, ds: float) -> RefPoint:
        k0, c, h0 = self._k0, self._c, self._heading
        turn = abs(k0) * ds + 0.5 * abs(c) * ds * ds
        chunks = min(max(1, math.ceil(turn / _MAX_HEADING_STEP)), _MAX_CHUNKS)
        width = ds / chunks
        half = 0.5 * width
        x = y = 0.0
        for chunk in range(chunks):
            middle = (chunk + 0.5) * width
            for node, weight in zip(_GL_NODES, _GL_WEIGHTS, strict=True):
                t = middle + half * node
                theta = h0 + t * (k0 + 0.5 * c * t)
                x += weight * math.cos(theta)
                y += weight * math.sin(theta)
        return (
            self._x + half * x,
            self._y + half * y,
            h0 + ds * (k0 + 0.5 * c * ds),
            k0 + c * ds,
        )


class _ParamPoly3:
    """paramPoly3 (and poly3 as u = p) in the geometry's local frame, arc-length parameterised."""

    __slots__ = ("_cos", "_heading", "_p", "_s", "_sin", "_u", "_v", "_x", "_y")

    def __init__(self, geometry: models.Geometry) -> None:
        self._x, self._y, self._heading = geometry.x, geometry.y, geometry.heading
        self._cos, self._sin = math.cos(geometry.heading), math.sin(geometry.heading)
        self._u, self._v = geometry.u, geometry.v
        if geometry.kind is models.GeometryKind.POLY3:
            p_end = _poly3_end(geometry.v, geometry.length)
        else:
            p_end = 1.0 if geometry.normalized else geometry.length
        p = np.linspace(0.0, p_end, _PARAM_TABLE_STEPS + 1)
        du = geometry.u[1] + p * (2 * geometry.u[2] + 3 * geometry.u[3] * p)
        dv = geometry.v[1] + p * (2 * geometry.v[2] + 3 * geometry.v[3] * p)
        speed = np.hypot(du, dv)
        # Trapezoid on a fine table; cubic speed profiles make this accurate to ~1e-6 m.
        cumulative = np.concatenate(([0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(p))))
        total = float(cumulative[-1])
        scale = geometry.length / total if total > 0 else 0.0
        scale = scale if math.isfinite(scale) else 0.0  # a (sub)normal-tiny total overflows
        self._s = [float(value) * scale for value in cumulative]
        self._p = [float(value) for value in p]

    def _param(self, ds: float) -> float:
        s_table, p_table = self._s, self._p
        index = min(max(bisect.bisect_right(s_table, ds) - 1, 0), len(s_table) - 2)
        s0, s1 = s_table[index], s_table[index + 1]
        fraction = (ds - s0) / (s1 - s0) if s1 > s0 else 0.0
        return p_table[index] + fraction * (p_table[index + 1] - p_table[index])

    def at(self, ds: float) -> RefPoint:
        p = self._param(ds)
        (au, bu, cu, du), (av, bv, cv, dv) = self._u, self._v
        u = au + p * (bu + p * (cu + p * du))
        v = av + p * (bv + p * (cv + p * dv))
        u1 = bu + p * (2 * cu + 3 * du * p)
        v1 = bv + p * (2 * cv + 3 * dv * p)
        u2 = 2 * cu + 6 * du * p
        v2 = 2 * cv + 6 * dv * p
        cube = math.hypot(u1, v1) ** 3  # may underflow to 0 for a tiny but non-zero speed
        curvature = (u1 * v2 - v1 * u2) / cube if cube > 0 else 0.0
        return (
            self._x + u * self._cos - v * self._sin,
            self._y + u * self._sin + v * self._cos,
            self._heading + math.atan2(v1, u1),
            curvature,
        )


def _poly3_end(v: tuple[float, float, float, float], length: float) -> float:
    """The local u at which a poly3 curve has arc length ``length`` (Newton on the arc length)."""

    def arc(u_end: float) -> float:
        u = np.linspace(0.0, u_end, _PARAM_TABLE_STEPS + 1)
        slope = v[1] + u * (2 * v[2] + 3 * v[3] * u)
        speed = np.sqrt(1.0 + slope * slope)
        return float(np.sum(0.5 * (speed[1:] + speed[:-1])) * (u_end / _PARAM_TABLE_STEPS))

    u_end = length
    for _ in range(20):
        slope = v[1] + u_end * (2 * v[2] + 3 * v[3] * u_end)
        step = (arc(u_end) - length) / math.sqrt(1.0 + slope * slope)
        u_end -= step
        if abs(step) < 1e-9:
            break
    return u_end


def _evaluator(geometry: models.Geometry) -> _Evaluator:
    kind = geometry.kind
    if kind is models.GeometryKind.LINE:
        return _Line(geometry)
    if kind is models.GeometryKind.ARC:
        return _Arc(geometry)
    if kind is models.GeometryKind.SPIRAL:
        if geometry.curv_start == geometry.curv_end:
            return _Arc(
                models.Geometry(
                    kind=models.GeometryKind.ARC,
                    s=geometry.s,
                    x=geometry.x,
                    y=geometry.y,
                    heading=geometry.heading,
                    length=geometry.length,
                    curvature=geometry.curv_start,
                )
            )
        return _Spiral(geometry)
    return _ParamPoly3(geometry)


class ReferenceLine:
    """A road's reference line over ``0 <= s <= length`` (queries outside are clamped)."""

    __slots__ = ("_evaluators", "_lengths", "_starts", "length")

    def __init__(self, geometries: tuple[models.Geometry, ...], length: float) -> None:
        self.length = length
        self._starts = [geometry.s for geometry in geometries]
        self._lengths = [geometry.length for geometry in geometries]
        self._evaluators = [_evaluator(geometry) for geometry in geometries]

    def at(self, s: float) -> RefPoint:
        """x, y, heading, curvature at ``s``."""
        s = min(max(s, 0.0), self.length)
        index = max(bisect.bisect_right(self._starts, s) - 1, 0)
        ds = min(s - self._starts[index], self._lengths[index])
        return self._evaluators[index].at(ds)

    def sample_s(self, step: float) -> list[float]:
        """Sample positions no further than ``step`` apart, including every geometry's ends."""
        values: list[float] = []
        for start, length in zip(self._starts, self._lengths, strict=True):
            count = max(1, math.ceil(length / step))
            values.extend(start + length * i / count for i in range(count))
        values.append(self.length)
        return sorted({min(max(value, 0.0), self.length) for value in values})


def elevation(records: tuple[models.Poly3, ...], s: float) -> float:
    """Height of the reference line at ``s`` (0 without an elevation profile)."""
    if not records:
        return 0.0
    index = max(bisect.bisect_right([record.s for record in records], s) - 1, 0)
    return records[index].value(s)
