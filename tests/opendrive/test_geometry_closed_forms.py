"""Reference-line and lane geometry against closed forms: line, arc (radius, heading, curvature),
clothoid end points against the Fresnel-integral closed form and brute-force integration,
paramPoly3 (arcLength and normalized) and poly3 against direct evaluation, lane centres with
lane offset and width polynomials, lane heading where the width changes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, special

from simtest_operator.opendrive import RoadNetwork
from tests.opendrive.conftest import single_road


def test_line_pose_and_lane_centres() -> None:
    net = RoadNetwork.from_bytes(
        single_road(
            '<geometry s="0" x="10" y="-5" hdg="0.5" length="100"><line/></geometry>', length=100
        )
    )
    pose = net.reference_pose("r", 40.0)
    assert pose.x == pytest.approx(10 + 40 * math.cos(0.5))
    assert pose.y == pytest.approx(-5 + 40 * math.sin(0.5))
    assert pose.heading == pytest.approx(0.5)
    right = net.lane_pose("r", 40.0, -1)
    assert right.x == pytest.approx(pose.x + 1.75 * math.sin(0.5))
    assert right.y == pytest.approx(pose.y - 1.75 * math.cos(0.5))
    sidewalk = net.lane_pose("r", 40.0, -2, offset=0.5)
    assert math.hypot(sidewalk.x - pose.x, sidewalk.y - pose.y) == pytest.approx(3.5 + 1.0 - 0.5)
    assert net.lane_width("r", 40.0, -2) == pytest.approx(2.0)
    assert net.driving_direction("r", -1) == 1
    assert net.driving_direction("r", 1) == -1


@pytest.mark.parametrize("curvature", [0.01, -0.05, 0.2])
def test_arc_has_constant_radius(curvature: float) -> None:
    length = 0.9 * 2 * math.pi / abs(curvature)
    net = RoadNetwork.from_bytes(
        single_road(
            f'<geometry s="0" x="0" y="0" hdg="0" length="{length}">'
            f'<arc curvature="{curvature}"/></geometry>',
            length=length,
        )
    )
    radius = 1 / curvature
    centre = (0.0, radius)
    for s in np.linspace(0, length, 9):
        pose = net.reference_pose("r", float(s))
        assert math.hypot(pose.x - centre[0], pose.y - centre[1]) == pytest.approx(
            abs(radius), abs=1e-9
        )
        assert pose.heading == pytest.approx(curvature * s)
        # A lane centre on an arc lies on a concentric circle.
        lane = net.lane_pose("r", float(s), 1)
        assert math.hypot(lane.x - centre[0], lane.y - centre[1]) == pytest.approx(
            abs(radius - 1.75)
        )
        assert lane.heading == pytest.approx(curvature * s)


def fresnel_clothoid(k0: float, k1: float, length: float, h0: float) -> tuple[float, float]:
    """End point of a clothoid from the origin via scipy's Fresnel integrals (closed form)."""
    c = (k1 - k0) / length
    sigma = math.copysign(1.0, c)
    scale = math.sqrt(abs(c) / math.pi)
    u0, u1 = k0 / c, k0 / c + length
    s0, c0 = special.fresnel(scale * u0)
    s1, c1 = special.fresnel(scale * u1)
    b = h0 - k0 * k0 / (2 * c)
    dc, ds = c1 - c0, s1 - s0
    return (
        (dc * math.cos(b) - sigma * ds * math.sin(b)) / scale,
        (sigma * ds * math.cos(b) + dc * math.sin(b)) / scale,
    )


@pytest.mark.parametrize(
    ("k0", "k1", "length", "h0"),
    [
        (0.0, 0.02, 80.0, 0.0),
        (0.01, -0.03, 150.0, 1.0),
        (-0.1, 0.0, 30.0, -2.0),
        (0.0, 0.5, 25.0, 0.3),
    ],
)
def test_spiral_matches_fresnel_closed_form(k0: float, k1: float, length: float, h0: float) -> None:
    geometry = (
        f'<geometry s="0" x="0" y="0" hdg="{h0}" length="{length}">'
        f'<spiral curvStart="{k0}" curvEnd="{k1}"/></geometry>'
    )
    net = RoadNetwork.from_bytes(single_road(geometry, length=length))
    end = net.reference_pose("r", length)
    x, y = fresnel_clothoid(k0, k1, length, h0)
    assert end.x == pytest.approx(x, abs=1e-8)
    assert end.y == pytest.approx(y, abs=1e-8)
    assert end.heading == pytest.approx(h0 + k0 * length + 0.5 * (k1 - k0) * length)
    # And against brute-force adaptive quadrature at an inner point.
    c = (k1 - k0) / length
    s = 0.37 * length
    xq = integrate.quad(lambda u: math.cos(h0 + k0 * u + 0.5 * c * u * u), 0, s, epsabs=1e-12)[0]
    yq = integrate.quad(lambda u: math.sin(h0 + k0 * u + 0.5 * c * u * u), 0, s, epsabs=1e-12)[0]
    inner = net.reference_pose("r", s)
    assert (inner.x, inner.y) == pytest.approx((xq, yq), abs=1e-9)


def arc_length(fu, fv, p_end: float) -> float:  # type: ignore[no-untyped-def]
    return float(integrate.quad(lambda p: math.hypot(fu(p), fv(p)), 0, p_end, epsabs=1e-12)[0])


@pytest.mark.parametrize("normalized", [False, True])
def test_param_poly3_points_and_arc_length(normalized: bool) -> None:
    u = (0.0, 40.0, 0.0, 0.0) if normalized else (0.0, 1.0, 0.0, 0.0)
    v = (0.0, 0.0, 6.0, -2.5) if normalized else (0.0, 0.0, 0.004, -0.00006)
    p_end = 1.0 if normalized else 40.0

    def du(p: float) -> float:
        return u[1] + 2 * u[2] * p + 3 * u[3] * p * p

    def dv(p: float) -> float:
        return v[1] + 2 * v[2] * p + 3 * v[3] * p * p

    # arcLength: p runs over [0, length]; the declared length is then the curve's own parameter
    # range, and s maps to p through the arc length scaled to the declared length.
    length = p_end if not normalized else arc_length(du, dv, p_end)
    true_length = arc_length(du, dv, p_end)
    p_range = "normalized" if normalized else "arcLength"
    geometry = (
        f'<geometry s="0" x="5" y="7" hdg="0.25" length="{length}"><paramPoly3 aU="{u[0]}" '
        f'bU="{u[1]}" cU="{u[2]}" dU="{u[3]}" aV="{v[0]}" bV="{v[1]}" cV="{v[2]}" dV="{v[3]}" '
        f'pRange="{p_range}"/></geometry>'
    )
    net = RoadNetwork.from_bytes(single_road(geometry, length=length))
    for p in (0.0, 0.3 * p_end, p_end):
        s = arc_length(du, dv, p) * length / true_length
        lu = u[0] + u[1] * p + u[2] * p * p + u[3] * p**3
        lv = v[0] + v[1] * p + v[2] * p * p + v[3] * p**3
        pose = net.reference_pose("r", s)
        assert pose.x == pytest.approx(5 + lu * math.cos(0.25) - lv * math.sin(0.25), abs=2e-4)
        assert pose.y == pytest.approx(7 + lu * math.sin(0.25) + lv * math.cos(0.25), abs=2e-4)
        assert pose.heading == pytest.approx(0.25 + math.atan2(dv(p), du(p)), abs=1e-5)


def test_poly3_end_point() -> None:
    a, b, c, d = 0.0, 0.0, 0.01, -0.0002
    u_end = 30.0
    length = arc_length(lambda _: 1.0, lambda p: b + 2 * c * p + 3 * d * p * p, u_end)
    geometry = (
        f'<geometry s="0" x="0" y="0" hdg="0" length="{length}">'
        f'<poly3 a="{a}" b="{b}" c="{c}" d="{d}"/></geometry>'
    )
    net = RoadNetwork.from_bytes(single_road(geometry, length=length))
    end = net.reference_pose("r", length)
    assert end.x == pytest.approx(u_end, abs=1e-4)
    assert end.y == pytest.approx(a + b * u_end + c * u_end**2 + d * u_end**3, abs=1e-4)


def test_lane_offset_and_width_change_follow_polynomials() -> None:
    lanes = (
        '<laneSection s="0"><center><lane id="0" type="none"/></center><right>'
        '<lane id="-1" type="driving"><width sOffset="0" a="3.0" b="0.01"/></lane>'
        '<lane id="-2" type="driving"><width sOffset="0" a="3.0"/>'
        '<width sOffset="50" a="3.0" b="0.02"/></lane></right></laneSection>'
    )
    offset = '<laneOffset s="0" a="0.5" b="0.0" c="0.0001" d="0"/>'
    net = RoadNetwork.from_bytes(
        single_road(
            '<geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry>',
            length=100,
            lanes=lanes,
            extra=offset,
        )
    )
    s = 80.0
    centre = 0.5 + 0.0001 * s * s
    w1 = 3.0 + 0.01 * s
    w2 = 3.0 + 0.02 * (s - 50)
    pose = net.lane_pose("r", s, -2)
    assert pose.y == pytest.approx(centre - w1 - w2 / 2)
    slope = 2 * 0.0001 * s - 0.01 - 0.02 / 2
    assert pose.heading == pytest.approx(math.atan(slope))
    assert net.lane_pose("r", s, 0).y == pytest.approx(centre)


def test_lane_stretch_on_arcs_and_width_changes() -> None:
    curvature = 0.02
    net = RoadNetwork.from_bytes(
        single_road(
            f'<geometry s="0" x="0" y="0" hdg="0" length="100"><arc curvature="{curvature}"/>'
            "</geometry>",
            length=100,
        )
    )
    assert net.lane_stretch("r", 50.0, -1) == pytest.approx(1 + curvature * 1.75)
    assert net.lane_stretch("r", 50.0, 1) == pytest.approx(1 - curvature * 1.75)
    assert net.lane_stretch("r", 50.0, 1, offset=0.25) == pytest.approx(1 - curvature * 2.0)
    lanes = (
        '<laneSection s="0"><center><lane id="0" type="none"/></center><right>'
        '<lane id="-1" type="driving"><width sOffset="0" a="3.0" b="0.1"/></lane>'
        "</right></laneSection>"
    )
    straight = RoadNetwork.from_bytes(
        single_road(
            '<geometry s="0" x="0" y="0" hdg="0" length="10"><line/></geometry>',
            length=10,
            lanes=lanes,
        )
    )
    assert straight.lane_stretch("r", 5.0, -1) == pytest.approx(math.hypot(1.0, 0.05))
