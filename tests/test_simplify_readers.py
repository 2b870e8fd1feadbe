"""Knots inserted for OCCT's default mass properties change no geometry."""

from __future__ import annotations

import numpy as np
from OCP.collections import Array1_double, Array1_int, Array2_gp_Pnt
from OCP.Geom import Geom_BSplineSurface, Geom_Plane
from OCP.gp import gp_Pln, gp_Pnt

from medax.cad.simplify.occ import READER_POINTS, reader_spans


def _surface(v_knots: list[float], v_mults: list[int]) -> Geom_BSplineSurface:
    """A bicubic over [0, 1] x [v0, v1] with bumpy poles (4 x n)."""
    rng = np.random.default_rng(7)
    n = sum(v_mults) - 4
    poles = Array2_gp_Pnt(1, 4, 1, n)
    for i in range(4):
        for j in range(n):
            poles.SetValue(i + 1, j + 1, gp_Pnt(i / 3, j / (n - 1), float(rng.normal())))

    def arr(vals, kind):
        a = kind(1, len(vals))
        for k, x in enumerate(vals):
            a.SetValue(k + 1, x)
        return a

    return Geom_BSplineSurface(
        poles,
        arr([0.0, 1.0], Array1_double),
        arr(v_knots, Array1_double),
        arr([4, 4], Array1_int),
        arr(v_mults, Array1_int),
        3,
        3,
    )


def test_reader_spans_inserts_knots_without_moving_the_surface():
    s = _surface([0.0, 0.3, 1.0], [4, 2, 4])  # a C1 knot, as at a fit's curvature jump
    r = reader_spans(s)
    assert s.NbVKnots() == 3  # the input is not touched
    assert 2 * (r.VDegree() + 1) * (r.NbVKnots() - 1) >= READER_POINTS
    assert r.VMultiplicity(2) >= 1 and 0.3 in [r.VKnot(j) for j in range(1, r.NbVKnots() + 1)]
    uv = np.random.default_rng(1).random((200, 2))
    a = np.array([s.Value(u, v).Coord() for u, v in uv])
    b = np.array([r.Value(u, v).Coord() for u, v in uv])
    assert np.abs(a - b).max() <= 1e-14
    assert r.IsCNv(1) and not r.IsCNv(2)  # the C1 knot stays C1


def test_reader_spans_leaves_enough_spans_and_other_surfaces_alone():
    knots = list(np.linspace(0.0, 1.0, 9))
    s = _surface(knots, [4] + [1] * 7 + [4])
    assert reader_spans(s) is s
    plane = Geom_Plane(gp_Pln())
    assert reader_spans(plane) is plane
