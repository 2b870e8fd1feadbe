"""The numpy NURBS surface against closed forms: a quarter cylinder as a rational quadratic
patch (every point at the radius from the axis, derivatives against central differences)
and its heights over a plane against ``sqrt(R^2 - x^2)``. No OCP here."""

from __future__ import annotations

import numpy as np

from medax.geometry.nurbs_surface import NurbsSurface, graph_heights

R, H = 2.5, 7.0


def _quarter_cylinder() -> NurbsSurface:
    ring = np.array([[R, 0.0], [R, R], [0.0, R]])
    poles = np.array([[[x, y, 0.0], [x, y, H]] for x, y in ring])
    weights = np.array([[1.0, 1.0], [np.sqrt(0.5)] * 2, [1.0, 1.0]])
    tu = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    tv = np.array([0.0, 0.0, 1.0, 1.0])
    return NurbsSurface(poles, weights, tu, tv, 2, 1)


def test_points_on_the_cylinder_and_derivatives():
    s = _quarter_cylinder()
    rng = np.random.default_rng(3)
    u, v = rng.uniform(0.0, 1.0, 500), rng.uniform(0.0, 1.0, 500)
    p, pu, pv = s.jet(u, v)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), R, rtol=0, atol=1e-13)
    np.testing.assert_allclose(p[:, 2], H * v, atol=1e-13)
    h = 1e-6
    fd_u = (s.jet(u + h, v)[0] - s.jet(u - h, v)[0]) / (2 * h)
    fd_v = (s.jet(u, v + h)[0] - s.jet(u, v - h)[0]) / (2 * h)
    np.testing.assert_allclose(pu, fd_u, atol=1e-7)
    np.testing.assert_allclose(pv, fd_v, atol=1e-7)
    assert s.bounds == (0.0, 1.0, 0.0, 1.0)


def test_heights_over_a_plane():
    """Over the plane y = 0 (ex = x, ey = z, n = y) the cylinder's height is sqrt(R^2 - x^2)."""
    s = _quarter_cylinder()
    x = np.linspace(0.05, R - 0.05, 40)
    z = np.linspace(0.1, H - 0.1, 9)
    xy = np.array([(a, b) for a in x for b in z])
    ex, ey, n = np.eye(3)[0], np.eye(3)[2], np.eye(3)[1]
    t, ok, normal = graph_heights(s, (np.zeros(3), ex, ey, n), xy, s.bounds, 1e-12)
    assert ok.all()
    np.testing.assert_allclose(t, np.sqrt(R**2 - xy[:, 0] ** 2), atol=1e-11)
    radial = np.column_stack([xy[:, 0], t, np.zeros(len(t))]) / R  # the cylinder's normal
    np.testing.assert_allclose(np.abs(np.sum(normal * radial, axis=1)), 1.0, atol=1e-12)


def test_heights_refuse_points_off_the_surface():
    s = _quarter_cylinder()
    ex, ey, n = np.eye(3)[0], np.eye(3)[2], np.eye(3)[1]
    xy = np.array([[R + 1.0, 1.0], [1.0, H + 3.0]])  # beyond the radius, above the top
    _, ok, _ = graph_heights(s, (np.zeros(3), ex, ey, n), xy, s.bounds, 1e-12)
    assert not ok.any()
