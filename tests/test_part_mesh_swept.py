"""Structured quads on 4-sided faces of swept surfaces (``Geom_SurfaceOfRevolution`` and
``Geom_SurfaceOfLinearExtrusion``), on parts built with OCCT: a profile with a B-spline and
an ellipse arc revolved by a quarter turn (no seam) and by a full turn (seams), and a
profile of two B-splines extruded along a slanted direction.

Truth: OCCT's own surface evaluation (``BRepAdaptor_Surface.D1``) for the numpy copies;
for the meshes, ``BRepExtrema_DistShapeShape`` from every node to its trimmed CAD face,
the mesh's own incidence (each mesh edge in exactly two quads, no two nodes within 1e-9 x
diagonal), and the outward normal OCCT gives at each node's projection
(``GeomAPI_ProjectPointOnSurf``, ``BRepLProp_SLProps``, reversed faces flipped) - none of
it from how the mesher placed the nodes.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeVertex,
    BRepBuilderAPI_MakeWire,
)
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism, BRepPrimAPI_MakeRevol
from OCP.collections import Array1_gp_Pnt
from OCP.GC import GC_MakeArcOfEllipse
from OCP.Geom import (
    Geom_Hyperbola,
    Geom_Parabola,
    Geom_SurfaceOfLinearExtrusion,
    Geom_SurfaceOfRevolution,
    Geom_TrimmedCurve,
)
from OCP.GeomAPI import GeomAPI_PointsToBSpline, GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Elips, gp_Hypr, gp_Parab, gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_REVERSED
from scipy.spatial import cKDTree

from medax.cad.face_geometry import surface_type
from medax.cad.face_region import exact_embedding
from medax.cad.part_mesh import mesh_part
from medax.cad.part_report import part_report
from medax.cad.topology import build_topology
from medax.geometry.surfaces import ExtrusionSurface, RevolutionSurface

SWEPT = ("revolution", "extrusion")


def _spline(pts):
    arr = Array1_gp_Pnt(1, len(pts))
    for k, p in enumerate(pts):
        arr.SetValue(k + 1, gp_Pnt(*p))
    return BRepBuilderAPI_MakeEdge(GeomAPI_PointsToBSpline(arr).Curve()).Edge()


def _line(a, b):
    return BRepBuilderAPI_MakeEdge(gp_Pnt(*a), gp_Pnt(*b)).Edge()


def revolved(angle: float):
    """A profile in the xz plane (a line, a B-spline, a line, an ellipse arc bulging
    towards the z axis) revolved about z by ``angle``: two revolution faces (the B-spline's
    and the ellipse's), two planar rings, and with a part turn two planar end faces."""
    w = BRepBuilderAPI_MakeWire()
    w.Add(_line((10, 0, 0), (20, 0, 0)))
    w.Add(_spline([(20, 0, 0), (23, 0, 5), (21, 0, 10), (22, 0, 15)]))
    w.Add(_line((22, 0, 15), (10, 0, 15)))
    el = gp_Elips(gp_Ax2(gp_Pnt(10, 0, 7.5), gp_Dir(0, 1, 0), gp_Dir(0, 0, 1)), 7.5, 3.0)
    arc = GC_MakeArcOfEllipse(el, gp_Pnt(10, 0, 15), gp_Pnt(10, 0, 0), True).Value()
    w.Add(BRepBuilderAPI_MakeEdge(arc).Edge())
    face = BRepBuilderAPI_MakeFace(w.Wire(), True).Face()
    return BRepPrimAPI_MakeRevol(face, gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), angle).Shape()


def extruded():
    """A profile of two B-splines and two lines in the xy plane extruded along (3, 2, 20):
    two extrusion faces, two slanted planes, two planar caps with B-spline sides."""
    w = BRepBuilderAPI_MakeWire()
    w.Add(_spline([(0, 0, 0), (10, -3, 0), (20, 2, 0), (30, 0, 0)]))
    w.Add(_line((30, 0, 0), (30, 10, 0)))
    w.Add(_spline([(30, 10, 0), (15, 14, 0), (0, 12, 0)]))
    w.Add(_line((0, 12, 0), (0, 0, 0)))
    face = BRepBuilderAPI_MakeFace(w.Wire(), True).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(3, 2, 20)).Shape()


def looped():
    """A closed periodic B-spline loop in the xy plane extruded along (2, 1, 12): one
    extrusion face with a seam (loop, seam, loop, seam), two planar caps with no corner."""
    from OCP.collections import HArray1_gp_Pnt
    from OCP.GeomAPI import GeomAPI_Interpolate

    pts = HArray1_gp_Pnt(1, 5)
    for k, p in enumerate([(0, 0, 0), (14, -3, 0), (20, 9, 0), (6, 15, 0), (-3, 6, 0)]):
        pts.SetValue(k + 1, gp_Pnt(*p))
    interp = GeomAPI_Interpolate(pts, True, 1e-9)
    interp.Perform()
    edge = BRepBuilderAPI_MakeEdge(interp.Curve()).Edge()
    face = BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakeWire(edge).Wire(), True).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(2, 1, 12)).Shape()


def _occt_d1(face, uv):
    s = BRepAdaptor_Surface(face, False)
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    out = []
    for u, v in uv:
        s.D1(float(u), float(v), p, du, dv)
        out.append([[p.X(), p.Y(), p.Z()], [du.X(), du.Y(), du.Z()], [dv.X(), dv.Y(), dv.Z()]])
    return np.array(out)


def _parameter_box(face, n=7):
    s = BRepAdaptor_Surface(face, True)  # (the face's own parameter box)
    g = np.linspace(0.0, 1.0, n)
    u = s.FirstUParameter() + g * (s.LastUParameter() - s.FirstUParameter())
    v = s.FirstVParameter() + g * (s.LastVParameter() - s.FirstVParameter())
    return np.array([(a, b) for a in u for b in v])


def _assert_same_surface(face, emb, tol):
    uv = _parameter_box(face)
    truth = _occt_d1(face, uv)
    np.testing.assert_allclose(emb.evaluate(uv), truth[:, 0], atol=tol, rtol=0)
    jac = emb.jacobian(uv)
    np.testing.assert_allclose(jac[:, :, 0], truth[:, 1], atol=tol, rtol=1e-12)
    np.testing.assert_allclose(jac[:, :, 1], truth[:, 2], atol=tol, rtol=1e-12)


@pytest.mark.parametrize("shape", [revolved(0.5 * np.pi), extruded()], ids=["revol", "prism"])
def test_swept_embeddings_keep_occt_parameters(shape):
    """The numpy copies of the built parts' revolution and extrusion surfaces (B-spline, ellipse
    and line generatrices) give OCCT's points and first derivatives at OCCT's parameters."""
    topo = build_topology(shape)
    swept = [i for i in range(topo.n_faces) if surface_type(topo.face(i)) in SWEPT]
    assert len(swept) == 2
    for i in swept:
        emb = exact_embedding(topo.face(i))
        assert isinstance(emb, (RevolutionSurface, ExtrusionSurface))
        _assert_same_surface(topo.face(i), emb, 1e-12 * 30)


def test_conic_generatrices_keep_occt_parameters():
    """Revolutions of a parabola, a hyperbola, a skew line and a circle tilted off the axis'
    planes, extrusions of a hyperbola and of a Bezier curve (faces made straight from the
    ``Geom`` surfaces, off the origin): OCCT's points and derivatives."""
    from OCP.Geom import Geom_BezierCurve, Geom_Circle, Geom_Line
    from OCP.gp import gp_Circ, gp_Lin

    frame = gp_Ax2(gp_Pnt(1, 2, 3), gp_Dir(0, 1, 0), gp_Dir(1, 0, 0))
    parab = Geom_TrimmedCurve(Geom_Parabola(gp_Parab(frame, 2.5)), -3.0, 4.0)
    hyper = Geom_TrimmedCurve(Geom_Hyperbola(gp_Hypr(frame, 4.0, 1.5)), -1.0, 1.2)
    skew = Geom_Line(gp_Lin(gp_Pnt(5, 0, 0), gp_Dir(0.2, 0.7, 0.5)))
    tilted = gp_Ax2(gp_Pnt(9, 1, 2), gp_Dir(0.3, 0.4, 0.866), gp_Dir(0.95, -0.3, 0.0))
    circle = Geom_Circle(gp_Circ(tilted, 3.0))
    poles = Array1_gp_Pnt(1, 4)
    for k, p in enumerate([(0, 0, 0), (2, 3, 1), (5, -1, 2), (7, 2, 0)]):
        poles.SetValue(k + 1, gp_Pnt(*p))
    axis = gp_Ax1(gp_Pnt(-20, 2, 0), gp_Dir(0, 0.6, 0.8))
    surfaces = [
        Geom_SurfaceOfRevolution(parab, axis),
        Geom_SurfaceOfRevolution(hyper, axis),
        Geom_SurfaceOfRevolution(skew, axis),
        Geom_SurfaceOfRevolution(circle, axis),
        Geom_SurfaceOfLinearExtrusion(hyper, gp_Dir(0.3, 0.2, 0.9)),
        Geom_SurfaceOfLinearExtrusion(Geom_BezierCurve(poles), gp_Dir(0.1, 0.2, 0.9)),
    ]
    for surf in surfaces:
        # (u: the angle of a revolution, the profile's parameter of an extrusion, within
        # the Bezier's [0, 1]; v: the profile's parameter of a revolution)
        face = BRepBuilderAPI_MakeFace(surf, 0.2, 0.9, -0.9, 1.1, 1e-9).Face()
        _assert_same_surface(face, exact_embedding(face), 1e-11)


def test_periodic_profile_across_its_period():
    """An extrusion of a periodic B-spline (a closed interpolated loop), on a face whose
    parameter box runs across the end of the loop's period: OCCT's points and
    derivatives there too."""
    from OCP.collections import HArray1_gp_Pnt
    from OCP.GeomAPI import GeomAPI_Interpolate

    pts = HArray1_gp_Pnt(1, 5)
    for k, p in enumerate([(0, 0, 0), (4, -1, 0), (6, 3, 0), (2, 5, 0), (-1, 2, 0)]):
        pts.SetValue(k + 1, gp_Pnt(*p))
    interp = GeomAPI_Interpolate(pts, True, 1e-9)
    interp.Perform()
    loop = interp.Curve()
    assert loop.IsPeriodic()
    t0, t1 = loop.FirstParameter(), loop.LastParameter()
    surf = Geom_SurfaceOfLinearExtrusion(loop, gp_Dir(0.2, 0.1, 1.0))
    a, b = t0 + 0.7 * (t1 - t0), t0 + 1.3 * (t1 - t0)
    face = BRepBuilderAPI_MakeFace(surf, a, b, 0.0, 3.0, 1e-9).Face()
    uv = _parameter_box(face)
    assert uv[:, 0].max() > t1  # (beyond the first period)
    _assert_same_surface(face, exact_embedding(face), 1e-11)


def _assert_sound(shape, m):
    """Nodes on their trimmed faces to 1e-9 x diagonal, no duplicate node, closed (each
    mesh edge in two quads), every quad corner turning along OCCT's outward normal."""
    topo = build_topology(shape)
    tol = 1e-9 * m.diagonal
    assert not cKDTree(m.points).query_pairs(tol)
    e = np.sort(np.stack([m.quads, np.roll(m.quads, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, uses = np.unique(e, axis=0, return_counts=True)
    assert np.all(uses == 2)
    for i in np.unique(m.quad_face).tolist():
        face = topo.face(i)
        q = m.quads[m.quad_face == i]
        surf = BRep_Tool.Surface_s(face)
        ad = BRepAdaptor_Surface(face)
        sign = -1.0 if face.Orientation() == TopAbs_REVERSED else 1.0
        normal = np.zeros((len(m.points), 3))
        for k in np.unique(q).tolist():
            v = BRepBuilderAPI_MakeVertex(gp_Pnt(*m.points[k])).Vertex()
            d = BRepExtrema_DistShapeShape(v, face)
            assert d.IsDone() and d.Value() <= tol, (i, k, d.Value())
            proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*m.points[k]), surf)
            u, w = proj.LowerDistanceParameters()
            n = BRepLProp_SLProps(ad, u, w, 1, 1e-9).Normal()
            normal[k] = sign * np.array([n.X(), n.Y(), n.Z()])
        p = m.points[q]
        edges = np.roll(p, -1, axis=1) - p
        turn = np.cross(np.roll(edges, 1, axis=1), edges)
        area = np.einsum("mkd,mkd->mk", turn, normal[q])
        assert np.all(area > 0.0), (i, int(np.sum(area <= 0)))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("make", "n_structured", "n_swept"),
    [
        (lambda: revolved(0.5 * np.pi), 6, 2),
        (lambda: revolved(2.0 * np.pi), 2, 2),
        (extruded, 6, 2),
        (looped, 1, 1),
    ],
    ids=["quarter turn", "full turn", "prism", "loop prism"],
)
def test_swept_faces_structured(make, n_structured, n_swept):
    """Every 4-sided face takes the medial grid, the swept ones too (the full turn's two
    revolution faces and the loop's extrusion through their seams; the full turn's planar
    rings have holes, the loop's caps no corner: gmsh), and the report says so; the mesh
    passes the part checks."""
    shape = make()
    m = mesh_part(shape, 2.0)
    topo = build_topology(shape)
    swept = {i for i in range(topo.n_faces) if surface_type(topo.face(i)) in SWEPT}
    assert len(swept) == n_swept
    assert swept <= set(m.structured_faces) and len(m.structured_faces) == n_structured
    report = part_report(m)
    kinds = {f["face"]: f["kind"] for f in report["faces"]}
    assert all(kinds[i] == "structured" for i in swept)
    assert report["n_structured_faces"] == n_structured and report["n_inverted"] == 0
    _assert_sound(shape, m)


@pytest.mark.slow
def test_simplified_shaft_revolution_faces_structured():
    """The stepped shaft after fillet simplification: its shoulders and cylinders merged
    with the fillet halves are surfaces of revolution whose seams are chains of edges (the
    old cylinder's and the half's); each run along the seam is one side, and all four take
    the medial grid (the two planar end discs have no corner and go to gmsh)."""
    from medax.cad import parts
    from medax.cad.classify import classify_solid
    from medax.cad.simplify import simplify, specs_from_classification

    cls = classify_solid(parts.stepped_shaft().shape)
    shape = simplify(cls.shape, specs_from_classification(cls)).shape
    topo = build_topology(shape)
    kinds = [surface_type(topo.face(i)) for i in range(topo.n_faces)]
    assert kinds.count("revolution") == 4
    m = mesh_part(shape, 2.0)
    revolved = {i for i, k in enumerate(kinds) if k == "revolution"}
    assert revolved <= set(m.structured_faces) and len(m.structured_faces) == 5
    _assert_sound(shape, m)
