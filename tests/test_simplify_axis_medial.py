"""A fillet whose smooth edges are no iso-lines: its medial curve is the paper's axis.

The face is a piece of a cylinder (radius R, axis z) between two helices ``theta = a z`` and
``theta = a z + PHI``, cut by the planes ``z = 0`` and ``z = L``. The half-turn about the line
through the axis and a point P of the middle helix ``theta = a z + PHI / 2`` maps the
cylinder onto itself, one helix onto the other, and fixes P: P is equidistant from the two
(where their nearest points lie inside them, away from the cross edges). So the medial
curve must be that helix.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeWire,
)
from OCP.BRepLib import BRepLib
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.Geom import Geom_CylindricalSurface
from OCP.Geom2d import Geom2d_Line
from OCP.gp import gp_Ax3, gp_Dir2d, gp_Pnt2d

from medax.cad.simplify.medial import AXIS, medial_curve
from medax.cad.simplify.occ import edge_points

R, A, PHI, L = 5.0, 0.02, 0.8, 20.0


def _helix_face():
    surf = Geom_CylindricalSurface(gp_Ax3(), R)

    def edge(p, q):
        p2 = gp_Pnt2d(*p)
        d = np.subtract(q, p)
        line = Geom2d_Line(p2, gp_Dir2d(*d))
        e = BRepBuilderAPI_MakeEdge(line, surf, 0.0, float(np.hypot(*d))).Edge()
        BRepLib.BuildCurves3d_s(e, 1e-9)
        return e

    # corners in (theta, z): the helices are the lines theta = A z (+ PHI)
    c = [(0.0, 0.0), (A * L, L), (A * L + PHI, L), (PHI, 0.0)]
    s0, top, s1, bottom = (edge(c[i], c[(i + 1) % 4]) for i in range(4))
    wire = BRepBuilderAPI_MakeWire(s0, top, s1, bottom).Wire()
    face = BRepBuilderAPI_MakeFace(surf, wire).Face()
    BRepLib.BuildCurves3d_s(face, 1e-9)
    edges = []  # the face's own edges (making the wire may copy them), in wire order
    exp = BRepTools_WireExplorer(BRepTools.OuterWire_s(face), face)
    while exp.More():
        edges.append(exp.Current())
        exp.Next()
    return face, edges[0], edges[2]


@pytest.fixture(scope="module")
def medial():
    face, s0, s1 = _helix_face()
    return medial_curve(face, s0, s1, tol=1e-7 * L)


def test_smooth_edges_off_the_iso_lines_get_the_traced_axis(medial):
    assert not isinstance(medial, str), medial
    assert medial.iso == AXIS
    assert medial.error <= 1e-7 * L  # OCCT's distances to the two helices, on the edge


def test_the_axis_is_the_middle_helix(medial):
    pts = edge_points(medial.edge, 41)
    z = pts[:, 2]
    theta = np.arctan2(pts[:, 1], pts[:, 0])
    assert np.allclose(np.hypot(pts[:, 0], pts[:, 1]), R, atol=1e-8 * L)  # on the cylinder
    # from one cross edge to the other
    assert z.min() <= 1e-7 * L and z.max() >= L - 1e-7 * L
    # away from the cross edges (where a helix's nearest point may be its end), on the
    # middle helix: the symmetry's truth
    inner = (z > 0.25 * L) & (z < 0.75 * L)
    assert inner.sum() >= 15
    off = R * np.abs(theta[inner] - (A * z[inner] + 0.5 * PHI))
    assert off.max() <= 1e-7 * L


def test_the_radius_is_the_cylinders(medial):
    assert math.isclose(medial.radius, R, rel_tol=1e-12)


def test_a_fillet_on_the_axis_route_goes_only_where_it_meets_no_other_blend():
    """Fillets 1 and 2: a chain (1's supporting face is fillet 2); fillet 3 rides on
    nothing and carries nothing; fillet 4 meets corner blend 9. Every one has an axis medial
    curve except 2 (an iso-line): 1 and 4 are kept, 3 keeps its medial curve, 2 is not
    touched."""
    from medax.cad.simplify.job import Job
    from medax.cad.simplify.medial import Medial
    from medax.cad.simplify.pipeline import _unlinked_axes
    from medax.cad.simplify.specs import BlendInput, CornerSpec, FilletSpec

    fillets = (
        FilletSpec(1, (10, 11), (2, 20)),
        FilletSpec(2, (11, 12), (1, 21)),
        FilletSpec(3, (13, 14), (22, 23)),
        FilletSpec(4, (15, 16), (24, 25)),
    )
    blends = BlendInput(fillets, (), (CornerSpec(9, (4,), (24, 25)),))
    job = Job(None, None, None, 1.0, 1e-5, print, {})
    iso = {1: AXIS, 2: "u", 3: AXIS, 4: AXIS}
    job.medials = {f: Medial(None, m, float("nan"), 0.0, 1.0) for f, m in iso.items()}
    _unlinked_axes(job, blends)
    assert sorted(job.medials) == [2, 3]
    assert sorted(job.kept) == [1, 4]
    assert all("not iso-lines" in why for why in job.kept.values())


def test_no_exact_surface_is_swept_from_a_half_whose_medial_curve_is_the_axis(medial):
    """The exact routes sweep a half's section between its smooth edge and its mid
    iso-line; a cylinder half whose medial curve is the traced axis has none (a nan
    parameter reached OCCT and crashed it): it is refused with the reason, the fitted
    routes take it."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    from medax.cad.simplify.occ import faces_of
    from medax.cad.simplify.surfaces import Half, merged_surface

    face, s0, _ = _helix_face()
    plane = next(iter(faces_of(BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape())))
    why = merged_surface(plane, [Half(face, medial, s0)], 1e-7 * L)
    assert isinstance(why, str) and "no iso-line" in why
