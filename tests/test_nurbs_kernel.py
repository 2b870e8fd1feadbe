"""The compiled NURBS jet (medax.geometry.nurbs_kernel) against OCCT's Geom_BSplineSurface.D1
on random rational surfaces (the power basis up to POWER_BASIS_MAX_DEGREE, Cox-de Boor
above it), and graph_heights on a random rational graph against its forward evaluation."""

from __future__ import annotations

import numpy as np
import pytest

from medax.geometry.bspline import POWER_BASIS_MAX_DEGREE
from medax.geometry.surface_heights import graph_heights
from medax.geometry.surfaces import NurbsSurface


def knot_vector(n: int, p: int, rng: np.random.Generator, double: bool) -> np.ndarray:
    inner = np.sort(rng.uniform(0.05, 0.95, n - p - 1))
    if double and p > 1 and inner.size >= 2:
        inner[1] = inner[0]  # a double knot
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)]) * 3.0 - 1.0


def _random_surface(pu: int, pv: int, seed: int, graph: bool = False) -> NurbsSurface:
    rng = np.random.default_rng(seed)
    nu, nv = pu + 4, pv + 3
    if graph:  # z over a regular (x, y) grid of poles: a graph over z = 0
        g = np.stack(np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij"), axis=2)
        poles = np.concatenate((g.astype(float), 0.3 * rng.normal(size=(nu, nv, 1))), axis=2)
        weights = rng.uniform(0.8, 1.25, size=(nu, nv))
    else:
        poles = rng.normal(size=(nu, nv, 3)) * 5.0
        weights = rng.uniform(0.3, 3.0, size=(nu, nv))
    uk, vk = knot_vector(nu, pu, rng, True), knot_vector(nv, pv, rng, False)
    return NurbsSurface(poles, pu, pv, uk, vk, weights)


@pytest.mark.parametrize(
    ("pu", "pv"), [(1, 2), (3, 3), (POWER_BASIS_MAX_DEGREE, 4), (7, 2), (13, 9)]
)
def test_jet_equals_occt_d1(pu, pv):
    pytest.importorskip("OCP")
    from OCP.gp import gp_Pnt, gp_Vec

    from test_surfaces import _occt_nurbs

    s = _random_surface(pu, pv, seed=10 * pu + pv)
    g = _occt_nurbs(s)
    rng = np.random.default_rng(pu)
    knots_u = np.unique(s.uknots)
    p = np.column_stack([rng.uniform(-1.0, 2.0, 300), rng.uniform(-1.0, 2.0, 300)])
    p = np.vstack([p, np.column_stack([knots_u, np.full(knots_u.size, 0.3)])])
    x, du, dv = s.jet(p)
    ref = np.empty((3, len(p), 3))
    for i, (u, v) in enumerate(p):
        q, a, b = gp_Pnt(), gp_Vec(), gp_Vec()
        g.D1(float(u), float(v), q, a, b)
        ref[:, i] = [q.X(), q.Y(), q.Z()], [a.X(), a.Y(), a.Z()], [b.X(), b.Y(), b.Z()]
    rel = 1e-12 if max(pu, pv) <= POWER_BASIS_MAX_DEGREE else 2e-11  # degree 13: 5e-12
    for ours, theirs in zip((x, du, dv), ref, strict=True):
        assert np.max(np.abs(ours - theirs)) < rel * np.max(np.abs(theirs))
    assert np.array_equal(s.evaluate(p), x)


@pytest.mark.parametrize(("pu", "pv"), [(3, 2), (7, 3)])
def test_heights_of_a_random_rational_graph(pu, pv):
    """Points of the surface projected onto z = 0 give back their heights: many points
    (the seeded solve), converged to the tolerance, with the surface's normals."""
    s = _random_surface(pu, pv, seed=pu + 5 * pv, graph=True)
    rng = np.random.default_rng(7)
    b0, b1, c0, c1 = s.bounds
    uv = np.column_stack([rng.uniform(b0, b1, 4000), rng.uniform(c0, c1, 4000)])
    x, du, dv = s.jet(uv)
    frame = (np.array([0.1, -0.2, 0.5]), np.eye(3)[0], np.eye(3)[1], np.eye(3)[2])
    xy = x[:, :2] - frame[0][:2]
    t, ok, normal = graph_heights(s, frame, xy, s.bounds, 1e-12)
    assert ok.all()
    np.testing.assert_allclose(t, x[:, 2] - frame[0][2], atol=1e-10)
    nref = np.cross(du, dv)
    nref /= np.linalg.norm(nref, axis=1)[:, None]
    np.testing.assert_allclose(normal, nref, atol=1e-8)
