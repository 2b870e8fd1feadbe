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


def test_the_default_reading_of_a_solid_is_its_faces_read_from_its_rough_centre():
    """OCCT's default mass properties read a solid from the mean of its vertices; the
    faces' readings from that point add up to it (from the world origin they do not, on
    fitted faces: the integrator's error depends on the point)."""
    import pytest

    from medax.cad.classify import classify_solid
    from medax.cad.simplify import parts as P
    from medax.cad.simplify import simplify, specs_from_classification
    from medax.cad.simplify.local_measure import default_reading, rough_centre
    from medax.cad.simplify.occ import faces_of
    from medax.cad.simplify.validate import default_volume

    c = classify_solid(P.box_all_fillets(40.0, 30.0, 20.0, 4.0).shape)
    shape = simplify(c.shape, specs_from_classification(c)).shape
    whole = default_volume(shape)
    faces = list(faces_of(shape))
    assert default_reading(faces, rough_centre(shape)) == pytest.approx(whole, rel=1e-12)
    assert abs(default_reading(faces, np.zeros(3)) / whole - 1) > 1e-9
