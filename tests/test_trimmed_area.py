"""Area of trimmed B-spline surfaces by Green's theorem (``medax.geometry.trimmed_area``)
and of OCCT faces on them (``medax.cad.face_area``).

Truth: the paraboloid ``z = (u^2 + v^2) / 2``, which a cubic B-spline holds exactly, has
the area ``2 pi / 3 ((1 + R^2)^(3/2) - 1)`` over the disk of radius ``R`` about the origin;
other regions by scipy's adaptive double quadrature of the area element; OCCT faces also
by OCCT's own adaptive area integrator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from medax.geometry.bspline import BSpline
from medax.geometry.line import Line
from medax.geometry.surfaces import NurbsSurface
from medax.geometry.tensor_fit import greville
from medax.geometry.trimmed_area import boundary_rule, trimmed_area

HALF = 2.0  # the surfaces cover [-HALF, HALF]^2


def paraboloid(n: int = 40, degree: int = 3) -> NurbsSurface:
    """``z = (u^2 + v^2) / 2`` on [-2, 2]^2 with ``n`` poles each way, exactly (the
    coefficients of ``x^2`` in the B-spline basis are the symmetric products of each
    function's inner knots, averaged: its blossom)."""
    inner = np.linspace(-HALF, HALF, n - degree + 1)[1:-1]
    t = np.r_[[-HALF] * (degree + 1), inner, [HALF] * (degree + 1)]
    g = greville(t, degree)
    win = np.lib.stride_tricks.sliding_window_view(t[1:-1], degree)[:n]
    pairs = [(a, b) for a in range(degree) for b in range(a + 1, degree)]
    sq = np.mean([win[:, a] * win[:, b] for a, b in pairs], axis=0)
    u, v = np.meshgrid(g, g, indexing="ij")
    poles = np.stack([u, v, 0.5 * (sq[:, None] + sq[None, :])], axis=2)
    return NurbsSurface(poles, degree, degree, t, t)


def circle(r: float, centre=(0.0, 0.0), ccw: bool = True) -> BSpline:  # type: ignore[no-untyped-def]
    """The circle of radius ``r`` as a rational quadratic B-spline (counter-clockwise)."""
    s = math.sqrt(0.5)
    square = [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]]
    pts = np.array(square, float) * r + np.asarray(centre)
    w = np.array([1, s, 1, s, 1, s, 1, s, 1])
    c = BSpline(pts, 2, np.array([0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4], float), w)
    return c if ccw else c.reversed()


def disk_area(r: float) -> float:
    return 2.0 * math.pi / 3.0 * ((1.0 + r * r) ** 1.5 - 1.0)


def _area(s: NurbsSurface, curves: list) -> float:  # type: ignore[type-arg]
    uv, w = boundary_rule(curves, s.uknots, s.vknots, max(s.udeg, s.vdeg))
    return trimmed_area(s, uv, w)


def test_surface_is_the_paraboloid():
    s = paraboloid()
    p = np.random.default_rng(1).uniform(-HALF, HALF, (50, 2))
    assert np.abs(s.evaluate(p)[:, 2] - 0.5 * (p**2).sum(axis=1)).max() <= 1e-13


@pytest.mark.parametrize("r", [0.3, 1.0, 1.9])
def test_disk_on_the_paraboloid(r):
    assert _area(paraboloid(), [circle(r)]) == pytest.approx(disk_area(r), rel=1e-12)


def test_clockwise_boundary_gives_the_negative_area():
    assert _area(paraboloid(), [circle(1.3, ccw=False)]) == pytest.approx(
        -disk_area(1.3), rel=1e-12
    )


def test_hole_off_the_knot_lines():
    """A disk of radius 1.8 with a hole of radius 0.55 about (0.13, -0.21), whose circle
    crosses knot lines at arbitrary points: against the hole's area by scipy."""
    c, r = (0.13, -0.21), 0.55

    def element(rho: float, th: float) -> float:
        u, v = c[0] + rho * math.cos(th), c[1] + rho * math.sin(th)
        return rho * math.sqrt(1.0 + u * u + v * v)

    hole, _ = integrate.dblquad(element, 0.0, 2 * math.pi, 0.0, r, epsabs=1e-13, epsrel=1e-13)
    got = _area(paraboloid(37), [circle(1.8), circle(r, c, ccw=False)])
    assert got == pytest.approx(disk_area(1.8) - hole, rel=1e-11)


def test_polygon_region_with_a_side_on_a_knot_line():
    """A triangle of straight lines (one of them along the knot line v = 0), on a surface
    of degree 5: against scipy's quadrature of the area element over the triangle."""
    s = paraboloid(30, degree=5)
    a, b, c = np.array([-1.5, 0.0]), np.array([1.7, 0.0]), np.array([0.2, 1.6])
    sides = [Line(a, b), Line(b, c), Line(c, a)]

    def element(v: float, u: float) -> float:
        return math.sqrt(1.0 + u * u + v * v)

    # u from a to c (lower v = 0, upper the line a-c), then from c to b (upper c-b)
    left, _ = integrate.dblquad(
        element, a[0], c[0], 0.0, lambda u: (u - a[0]) / (c[0] - a[0]) * c[1], epsrel=1e-13
    )
    right, _ = integrate.dblquad(
        element, c[0], b[0], 0.0, lambda u: (b[0] - u) / (b[0] - c[0]) * c[1], epsrel=1e-13
    )
    assert _area(s, sides) == pytest.approx(left + right, rel=1e-11)


def test_a_rational_surface_is_refused():
    s = paraboloid(8)
    w = np.ones(s.poles.shape[:2])
    w[3, 3] = 2.0
    rational = NurbsSurface(s.poles, 3, 3, s.uknots, s.vknots, w)
    uv, wt = boundary_rule([circle(1.0)], s.uknots, s.vknots)
    with pytest.raises(ValueError, match="polynomial"):
        trimmed_area(rational, uv, wt)


# ---- OCCT faces -------------------------------------------------------------------------
def _occt_surface(s: NurbsSurface):  # type: ignore[no-untyped-def]
    from medax.cad.simplify.occ import bspline_surface

    return bspline_surface(s.poles, s.uknots, s.vknots, s.udeg, s.vdeg)


def _occt_area(face) -> float:  # type: ignore[no-untyped-def]
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, 1e-12, False)
    return float(props.Mass())


def _disk_face(surf, r: float, hole: float | None = None, reverse: bool = False):  # type: ignore[no-untyped-def]
    """A face of ``surf`` bounded by the circle of radius ``r`` in its parameters (and a
    hole of radius ``hole``), its 3-D curves built from the pcurves."""
    from OCP.BRepBuilderAPI import (
        BRepBuilderAPI_MakeEdge,
        BRepBuilderAPI_MakeFace,
        BRepBuilderAPI_MakeWire,
    )
    from OCP.BRepLib import BRepLib
    from OCP.Geom2d import Geom2d_Circle
    from OCP.gp import gp_Ax2d, gp_Dir2d, gp_Pnt2d
    from OCP.TopoDS import TopoDS

    def wire(radius: float, ccw: bool):  # type: ignore[no-untyped-def]
        c = Geom2d_Circle(gp_Ax2d(gp_Pnt2d(0.1, -0.05), gp_Dir2d(1.0, 0.0)), radius, ccw)
        edge = BRepBuilderAPI_MakeEdge(c, surf).Edge()
        return BRepBuilderAPI_MakeWire(edge).Wire()

    mk = BRepBuilderAPI_MakeFace(surf, wire(r, True))
    if hole is not None:
        mk.Add(wire(hole, False))
    face = mk.Face()
    BRepLib.BuildCurves3d_s(face)
    return TopoDS.Face(face.Reversed()) if reverse else face


@pytest.mark.parametrize("reverse", [False, True])
def test_occt_face_with_a_hole(reverse):
    """The same face area by medax's rule, by the paraboloid's closed form (outer disk
    minus the hole, both about one centre: the closed form is about the origin, so the
    circles are centred off it and scipy gives the truth) and by OCCT's integrator."""
    from medax.cad.face_area import bspline_face_area

    s = paraboloid(30)
    face = _disk_face(_occt_surface(s), 1.7, 0.4, reverse)
    got = bspline_face_area(face)
    assert got is not None

    def ring(rho: float, th: float) -> float:
        u, v = 0.1 + rho * math.cos(th), -0.05 + rho * math.sin(th)
        return rho * math.sqrt(1.0 + u * u + v * v)

    truth, _ = integrate.dblquad(ring, 0.0, 2 * math.pi, 0.4, 1.7, epsabs=1e-12, epsrel=1e-13)
    assert got == pytest.approx(truth, rel=1e-10)
    assert got == pytest.approx(_occt_area(face), rel=1e-10)


def test_occt_faces_it_does_not_take():
    """A plane face and a rational B-spline face: None (the caller measures them)."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    from medax.cad.face_area import bspline_face_area
    from medax.cad.simplify.occ import faces_of

    box = BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()
    assert all(bspline_face_area(f) is None for f in faces_of(box))
    s = paraboloid(8)
    surf = _occt_surface(s)
    surf.SetWeight(4, 4, 2.0)
    assert bspline_face_area(_disk_face(surf, 1.0)) is None


def test_pcurves_of_a_built_face_meet_and_a_gap_is_closed():
    """A face built by OCCT has pcurves meeting end to end (no gap); a loop with a gap
    closed by a straight piece (as ``face_area`` closes a loose face's) encloses the
    region of the closed polygon: two half circles shrunk apart by 1e-3 in v, whose
    straight closing pieces add the strip between them, checked against the disk's area
    plus the strip's by scipy."""
    from medax.cad.face_area import pcurve_gap

    s = paraboloid(30)
    assert pcurve_gap(_disk_face(_occt_surface(s), 1.2)) <= 1e-12
    r, d = 1.2, 1e-3
    top = _arc(r, 0.0, math.pi, d)  # the upper half moved up by d
    bottom = _arc(r, math.pi, 2 * math.pi, -d)
    ends = [top.evaluate(np.array([1.0]))[0], bottom.evaluate(np.array([0.0]))[0]]
    starts = [bottom.evaluate(np.array([1.0]))[0], top.evaluate(np.array([0.0]))[0]]
    loop = [top, Line(ends[0], ends[1]), bottom, Line(starts[0], starts[1])]

    def element(v: float, u: float) -> float:
        return math.sqrt(1.0 + u * u + v * v)

    strip, _ = integrate.dblquad(element, -r, r, -d, d, epsrel=1e-13)
    half, _ = integrate.dblquad(
        lambda rho, th: rho * math.sqrt(1 + rho * rho + 2 * d * rho * math.sin(th) + d * d),
        0.0, math.pi, 0.0, r, epsabs=1e-13, epsrel=1e-13,
    )  # fmt: skip
    assert _area(s, loop) == pytest.approx(2 * half + strip, rel=1e-11)


def _arc(r: float, a0: float, a1: float, dv: float) -> BSpline:
    """The arc of radius ``r`` about (0, dv) from angle ``a0`` to ``a1`` (< pi apart plus
    a bit: two rational quadratic pieces)."""
    mid = 0.5 * (a0 + a1)
    pts, w = [], []
    for lo, hi in ((a0, mid), (mid, a1)):
        half = 0.5 * (hi - lo)
        c = np.array([math.cos(lo + half), math.sin(lo + half)]) * r / math.cos(half)
        p0 = np.array([math.cos(lo), math.sin(lo)]) * r
        pts += [p0, c]
        w += [1.0, math.cos(half)]
    pts.append(np.array([math.cos(a1), math.sin(a1)]) * r)
    w.append(1.0)
    ctrl = np.array(pts) + np.array([0.0, dv])
    return BSpline(ctrl, 2, np.array([0, 0, 0, 1, 1, 2, 2, 2], float), np.array(w))


def test_a_surface_read_twice_is_copied_once():
    """``bspline_embedding`` keeps the copy of a surface it read, and reads a changed one
    again (a pole moved: the stamp's middle pole)."""
    from OCP.gp import gp_Pnt

    from medax.cad.face_region import bspline_embedding

    surf = _occt_surface(paraboloid(12))
    first = bspline_embedding(surf)
    assert bspline_embedding(surf) is first
    surf.SetPole(7, 7, gp_Pnt(0.0, 0.0, 5.0))
    again = bspline_embedding(surf)
    assert again is not first
    assert np.allclose(again.poles[6, 6], [0.0, 0.0, 5.0])
