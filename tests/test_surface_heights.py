"""Heights of a NURBS surface over a plane against closed forms: a quarter cylinder as a
rational quadratic patch, whose height over the plane y = 0 is ``sqrt(R^2 - x^2)``, inside
its domain and, continued, past it (the rational quadratic continues along the circle).
The surface's own evaluation is tested against OCCT in test_surfaces.py. No OCP here."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from medax.geometry.surface_heights import graph_heights
from medax.geometry.surfaces import NurbsSurface

R, H = 2.5, 7.0
#: the plane y = 0: ex = x, ey = z, n = y
FRAME = (np.zeros(3), np.eye(3)[0], np.eye(3)[2], np.eye(3)[1])


def _quarter_cylinder() -> NurbsSurface:
    ring = np.array([[R, 0.0], [R, R], [0.0, R]])
    poles = np.array([[[x, y, 0.0], [x, y, H]] for x, y in ring])
    weights = np.array([[1.0, 1.0], [np.sqrt(0.5)] * 2, [1.0, 1.0]])
    tu = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    tv = np.array([0.0, 0.0, 1.0, 1.0])
    return NurbsSurface(poles, 2, 1, tu, tv, weights)


def test_heights_over_a_plane():
    s = _quarter_cylinder()
    x = np.linspace(0.05, R - 0.05, 40)
    z = np.linspace(0.1, H - 0.1, 9)
    xy = np.array([(a, b) for a in x for b in z])
    t, ok, normal = graph_heights(s, FRAME, xy, s.bounds, 1e-12)
    assert ok.all()
    np.testing.assert_allclose(t, np.sqrt(R**2 - xy[:, 0] ** 2), atol=1e-11)
    radial = np.column_stack([xy[:, 0], t, np.zeros(len(t))]) / R  # the cylinder's normal
    np.testing.assert_allclose(np.abs(np.sum(normal * radial, axis=1)), 1.0, atol=1e-12)


def test_continued_past_the_domain_only_when_asked():
    """Just past u = 1 (x < 0) the continued surface is still the circle; clamped, the
    points are refused. Far off the surface they are refused either way."""
    s = _quarter_cylinder()
    xy = np.array([[-0.02, 1.0], [-0.04, 3.0]])
    _, ok, _ = graph_heights(s, FRAME, xy, s.bounds, 1e-12)
    assert not ok.any()
    t, ok, _ = graph_heights(replace(s, extrapolate=True), FRAME, xy, s.bounds, 1e-12)
    assert ok.all()
    np.testing.assert_allclose(t, np.sqrt(R**2 - xy[:, 0] ** 2), atol=1e-11)
    far = np.array([[R + 1.0, 1.0], [1.0, H + 3.0]])  # beyond the radius, above the top
    _, ok, _ = graph_heights(replace(s, extrapolate=True), FRAME, far, s.bounds, 1e-12)
    assert not ok.any()


def test_grid_rows_solved_from_their_neighbours():
    """A fine grid in row order (each point starts from the one before it): the closed-form
    heights up to the steep side, and the points past the clamped domain refused without
    spoiling the points after them."""
    s = _quarter_cylinder()
    x = np.concatenate([np.linspace(-0.04, -0.01, 4), np.linspace(0.01, R - 1e-3, 200)])
    z = np.linspace(0.1, H - 0.1, 120)
    xy = np.array([(a, b) for a in x for b in z])
    for surf, inside in ((s, xy[:, 0] > 0.0), (replace(s, extrapolate=True), xy[:, 0] > -1.0)):
        t, ok, _ = graph_heights(surf, FRAME, xy, s.bounds, 1e-12)
        assert np.array_equal(ok, inside)
        np.testing.assert_allclose(t[ok], np.sqrt(R**2 - xy[ok, 0] ** 2), atol=1e-10)
