"""Fitted merges take pieces on any surface OCCT converts to a B-spline (revolutions,
extrusions, cones, Bezier), not only the analytic kinds.

Truth: a horizontal round edge of a box stored as a surface of revolution (what CAD
exporters often write for a cylinder); its height above the plane under it is the closed form
``zc + sqrt(r^2 - (y - yc)^2)``.
"""

from __future__ import annotations

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
from OCP.GeomAbs import GeomAbs_SurfaceOfRevolution
from OCP.ShapeCustom import ShapeCustom

from medax.cad.simplify import parts as P
from medax.cad.simplify.fitted import _heights, _member
from medax.cad.simplify.occ import faces_of

A, B, H, R = 40.0, 30.0, 20.0, 5.0


def _top_back_round():
    """The box with its top edge at y = B, z = H rounded, every elementary surface
    converted to a surface of revolution; the round's face."""
    box = BRepPrimAPI_MakeBox(A, B, H).Shape()
    edges = [e for e in P._edges_where(box, lambda p: np.allclose(p[:, 1:], [B, H]))]
    part = P.fillet(box, edges, R, "round")
    shape = ShapeCustom.ConvertToRevolution_s(part.shape)
    faces = list(faces_of(shape))
    (k,) = part.blends
    return faces[k]


def test_revolution_piece_heights_match_the_cylinder():
    face = _top_back_round()
    assert BRepAdaptor_Surface(face).GetType() == GeomAbs_SurfaceOfRevolution
    ex, ey, n = np.eye(3)
    m = _member(face, (np.zeros(3), ex, ey))  # the plane z = 0, seen from above
    assert not isinstance(m, str), m
    x, y = np.meshgrid(np.linspace(1.0, A - 1.0, 9), np.linspace(B - R, B, 41))
    q = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    t, ok = _heights(m, q, n)
    yc, zc = B - R, H - R
    exact = zc + np.sqrt(np.maximum(R**2 - (q[:, 1] - yc) ** 2, 0.0))
    # defined where the slope is within 70 degrees: |y - yc| <= R sin(70 deg)
    steep = np.abs(q[:, 1] - yc) > R * np.sin(np.radians(70.0)) + 1e-9
    assert ok[~steep].all()
    assert np.abs(t[ok] - exact[ok]).max() <= 1e-9 * A
    # its projected boundary is the round's: y from B - R to B
    ys = np.vstack(m.edges)[:, 1]
    assert abs(ys.min() - (B - R)) <= 1e-9 * A and abs(ys.max() - B) <= 1e-9 * A
