"""Parametric surface embeddings: exact jacobians, OCCT's parametrisation, NURBS exactness."""

from __future__ import annotations

import numpy as np
import pytest

from medax.geometry.embedding import Embedding
from medax.geometry.surfaces import (
    ConeSurface,
    CylinderSurface,
    Frame,
    NurbsSurface,
    PlaneSurface,
    SphereSurface,
    TorusSurface,
    basis_and_derivative,
)

FRAME = Frame.make([1.0, -2.0, 0.5], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.3])


def quarter_cylinder_nurbs(r: float, h: float) -> NurbsSurface:
    """A rational quadratic x linear patch: exactly a quarter of a cylinder of radius r."""
    w = np.sqrt(0.5)
    arc = np.array([[r, 0.0], [r, r], [0.0, r]])
    poles = np.zeros((3, 2, 3))
    for a in range(3):
        for b, z in enumerate((0.0, h)):
            poles[a, b] = (arc[a, 0], arc[a, 1], z)
    weights = np.array([[1.0, 1.0], [w, w], [1.0, 1.0]])
    return NurbsSurface(
        poles, 2, 1, np.array([0, 0, 0, 1, 1, 1.0]), np.array([0, 0, 1, 1.0]), weights
    )


def wavy_nurbs() -> NurbsSurface:
    rng = np.random.default_rng(3)
    nu, nv = 6, 5
    g = np.stack(np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij"), axis=2).astype(float)
    poles = np.concatenate((g, rng.normal(size=(nu, nv, 1))), axis=2)
    uk = np.array([0, 0, 0, 0, 0.3, 0.7, 1, 1, 1, 1.0]) * 2.0 + 1.0
    vk = np.array([0, 0, 0, 0.3, 0.6, 1, 1, 1.0])
    weights = rng.uniform(0.5, 2.0, size=(nu, nv))
    return NurbsSurface(poles, 3, 2, uk, vk, weights)


SURFACES = {
    "plane": (PlaneSurface(FRAME), ((-3, 3), (-2, 2))),
    "cylinder": (CylinderSurface(FRAME, 2.5), ((0, 6.28), (-3, 3))),
    "cone": (ConeSurface(FRAME, 2.0, 0.4), ((0, 6.28), (-2, 2))),
    "sphere": (SphereSurface(FRAME, 3.0), ((0, 6.28), (-1.5, 1.5))),
    "torus": (TorusSurface(FRAME, 5.0, 1.5), ((0, 6.28), (0, 6.28))),
    "nurbs": (wavy_nurbs(), ((1.0, 3.0), (0.0, 1.0))),
    "nurbs_cyl": (quarter_cylinder_nurbs(2.0, 3.0), ((0.0, 1.0), (0.0, 1.0))),
}


def sample(bounds, n=200, seed=0):
    rng = np.random.default_rng(seed)
    (u0, u1), (v0, v1) = bounds
    return np.column_stack((rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)))


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_jacobian_matches_central_differences(name):
    surf, bounds = SURFACES[name]
    assert isinstance(surf, Embedding) and surf.dim == 3 and not surf.is_identity
    p = sample(bounds)
    jac = surf.jacobian(p)
    assert jac.shape == (len(p), 3, 2)
    h = 1e-6
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        fd = (surf.evaluate(p + e) - surf.evaluate(p - e)) / (2 * h)
        scale = np.max(np.abs(jac[:, :, k])) + 1.0
        assert np.max(np.abs(fd - jac[:, :, k])) < 1e-7 * scale, name


def test_nurbs_quarter_cylinder_is_exact():
    surf = quarter_cylinder_nurbs(2.0, 3.0)
    p = sample(((0, 1), (0, 1)), 500)
    x = surf.evaluate(p)
    assert np.max(np.abs(np.hypot(x[:, 0], x[:, 1]) - 2.0)) < 1e-14
    assert np.allclose(x[:, 2], 3.0 * p[:, 1], atol=1e-14)
    n = surf.normal(p)
    radial = x[:, :2] / np.hypot(x[:, 0], x[:, 1])[:, None]
    assert np.allclose(np.abs(np.sum(n[:, :2] * radial, axis=1)), 1.0, atol=1e-12)


def test_basis_is_a_partition_of_unity_and_derivatives_sum_to_zero():
    kn = np.array([0, 0, 0, 0, 0.2, 0.2, 0.6, 1, 1, 1, 1.0])
    t = np.linspace(0, 1, 101)
    _, vals, ders = basis_and_derivative(kn, 3, t)
    assert np.allclose(vals.sum(axis=1), 1.0, atol=1e-14)
    assert np.allclose(ders.sum(axis=1), 0.0, atol=1e-10)
    assert np.all(vals >= -1e-15)


@pytest.mark.parametrize("extrapolate", [False, True])
def test_span_polynomials_match_the_recursion(extrapolate):
    """The per-span polynomials give the Cox-de Boor values and derivatives (a double
    knot, unequal spans, points past both ends), and finite differences of the values."""
    from medax.geometry.surfaces import SpanBasis

    kn = np.array([0, 0, 0, 0, 0.2, 0.2, 0.6, 0.65, 1, 1, 1, 1.0]) * 7.0 + 2.0
    t = np.concatenate([np.linspace(1.5, 9.5, 401), kn])
    basis = SpanBasis.of(kn, 3, extrapolate)
    span, vals, ders = basis(t)
    span0, vals0, ders0 = basis_and_derivative(kn, 3, t, extrapolate)
    assert np.array_equal(span, span0)
    assert np.max(np.abs(vals - vals0)) < 1e-13 and np.max(np.abs(ders - ders0)) < 1e-12
    h = 1e-6
    inside = (t > 2.0 + h) & (t < 9.0 - h) & np.all(np.abs(t[:, None] - kn) > h, axis=1)
    fd = (basis(t[inside] + h)[1] - basis(t[inside] - h)[1]) / (2 * h)
    assert np.max(np.abs(fd - ders[inside])) < 1e-6


@pytest.mark.parametrize("name", ["plane", "cylinder", "cone", "sphere", "torus", "nurbs"])
def test_same_parametrisation_as_occt(name):
    """Each embedding reproduces OCCT's ``Geom_*`` surface point for point."""
    pytest.importorskip("OCP")
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    surf, bounds = SURFACES[name]
    f = FRAME
    ax = gp_Ax3(gp_Pnt(*f.origin), gp_Dir(*f.z), gp_Dir(*f.x))
    if name == "plane":
        from OCP.Geom import Geom_Plane

        g = Geom_Plane(ax)
    elif name == "cylinder":
        from OCP.Geom import Geom_CylindricalSurface

        g = Geom_CylindricalSurface(ax, 2.5)
    elif name == "cone":
        from OCP.Geom import Geom_ConicalSurface

        g = Geom_ConicalSurface(ax, 0.4, 2.0)
    elif name == "sphere":
        from OCP.Geom import Geom_SphericalSurface

        g = Geom_SphericalSurface(ax, 3.0)
    elif name == "torus":
        from OCP.Geom import Geom_ToroidalSurface

        g = Geom_ToroidalSurface(ax, 5.0, 1.5)
    else:
        g = _occt_nurbs(surf)
    p = sample(bounds, 50, seed=1)
    ours = surf.evaluate(p)
    theirs = np.array([[q.X(), q.Y(), q.Z()] for q in (g.Value(float(u), float(v)) for u, v in p)])
    assert np.max(np.abs(ours - theirs)) < 1e-12 * (1.0 + np.max(np.abs(theirs)))


def _occt_nurbs(s: NurbsSurface):
    from OCP.collections import Array1_double as TColStd_Array1OfReal
    from OCP.collections import Array1_int as TColStd_Array1OfInteger
    from OCP.collections import Array2_double as TColStd_Array2OfReal
    from OCP.collections import Array2_gp_Pnt as TColgp_Array2OfPnt
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    nu, nv = s.poles.shape[:2]
    poles = TColgp_Array2OfPnt(1, nu, 1, nv)
    weights = TColStd_Array2OfReal(1, nu, 1, nv)
    for a in range(nu):
        for b in range(nv):
            poles.SetValue(a + 1, b + 1, gp_Pnt(*s.poles[a, b]))
            weights.SetValue(a + 1, b + 1, float(s.weights[a, b]))

    def knots(kv):
        vals, mults = np.unique(kv, return_counts=True)
        k = TColStd_Array1OfReal(1, len(vals))
        m = TColStd_Array1OfInteger(1, len(vals))
        for i, (x, c) in enumerate(zip(vals, mults, strict=True)):
            k.SetValue(i + 1, float(x))
            m.SetValue(i + 1, int(c))
        return k, m

    uk, um = knots(s.uknots)
    vk, vm = knots(s.vknots)
    return Geom_BSplineSurface(poles, weights, uk, vk, um, vm, s.udeg, s.vdeg)


def test_nurbs_evaluation_in_chunks_is_the_same(monkeypatch):
    """Many points are evaluated in chunks (see PARTS_CHUNK): the same points, derivatives
    and order as one pass."""
    from medax.geometry import surfaces

    surf = wavy_nurbs()
    p = sample(((1.0, 3.0), (0.0, 1.0)), 1000, seed=4)
    whole = surf.jet(p)
    monkeypatch.setattr(surfaces, "PARTS_CHUNK", 64)
    for a, b in zip(whole, surf.jet(p), strict=True):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("degree", [1, 2, 3, 5, 9, 13])
def test_basis_and_derivative_equal_scipy(degree):
    """The compiled Cox-de Boor values and first derivatives equal scipy's B-spline basis
    (each function evaluated as a B-spline with one unit coefficient), double knots and the
    knots themselves included."""
    from scipy.interpolate import BSpline as SciBSpline

    rng = np.random.default_rng(degree)
    inner = np.sort(rng.uniform(0.0, 1.0, 6))
    if degree > 1:  # a double knot (scipy has no derivative of a C-1 linear spline)
        inner[2] = inner[1]
    kn = np.concatenate([np.zeros(degree + 1), inner, np.ones(degree + 1)]) * 3.0 - 1.0
    t = np.concatenate([rng.uniform(-1.0, 2.0, 200), kn])
    span, vals, ders = basis_and_derivative(kn, degree, t)
    n_ctrl = kn.size - degree - 1
    for r in range(degree + 1):
        k = span - degree + r  # the index of the r-th non-zero function at each point
        for i in np.unique(k):
            c = np.zeros(n_ctrl)
            c[i] = 1.0
            f = SciBSpline(kn, c, degree)
            at = k == i
            x = t[at]
            assert np.max(np.abs(vals[at, r] - f(x))) < 1e-12
            scale = max(1.0, float(np.max(np.abs(f.derivative()(x)))))
            assert np.max(np.abs(ders[at, r] - f.derivative()(x))) < 1e-11 * scale
