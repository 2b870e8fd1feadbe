"""The traced medial curve of a B-spline blend whose mid iso-line is not equidistant (the
catalogue's slanted boss: a rolling ball between a plate and a slanted cylinder), checked
against OCCT's own distances, and the simplification of that part (the fillet is kept, with
the reason naming what is missing: a fitted surface over the cylinder)."""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS

from medax.cad import parts
from medax.cad.classify import classify_solid
from medax.cad.simplify import simplify, specs_from_classification
from medax.cad.simplify.medial import TRACED, medial_curve
from medax.cad.simplify.occ import shape_map
from medax.cad.simplify.split import split_along
from medax.cad.simplify.validate import check


def _occt_distance(point: np.ndarray, shape) -> float:
    """BRepExtrema distance, polished on edges by GeomAPI_ProjectPointOnCurve (BRepExtrema
    stops near 1e-7 on B-spline edges)."""
    p = gp_Pnt(*map(float, point))
    d = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(p).Vertex(), shape)
    assert d.IsDone()
    best = d.Value()
    if shape.ShapeType() == TopAbs_EDGE:
        ad = BRepAdaptor_Curve(TopoDS.Edge(shape))
        a, b = ad.FirstParameter(), ad.LastParameter()
        proj = GeomAPI_ProjectPointOnCurve(p, BRep_Tool.Curve_s(TopoDS.Edge(shape), a, b), a, b)
        if proj.NbPoints() > 0:
            best = min(best, proj.LowerDistance())
    return float(best)


@pytest.fixture(scope="module")
def slanted():
    built = parts.slanted_boss()
    cls = classify_solid(built.shape)
    (spec,) = specs_from_classification(cls).fillets
    fmap = shape_map(cls.shape, TopAbs_FACE)
    emap = shape_map(cls.shape, TopAbs_EDGE)
    face = TopoDS.Face(fmap.FindKey(spec.face + 1))
    edges = [TopoDS.Edge(emap.FindKey(i + 1)) for i in spec.smooth_edges]
    return cls, spec, face, edges, medial_curve(face, *edges)


def test_traced_medial_edge_equidistant_by_occt(slanted):
    _, _, face, edges, m = slanted
    assert not isinstance(m, str), m
    assert m.iso == TRACED
    ad = BRepAdaptor_Curve(m.edge)
    ts = np.linspace(ad.FirstParameter(), ad.LastParameter(), 61)
    pts = np.array(
        [[ad.Value(float(t)).X(), ad.Value(float(t)).Y(), ad.Value(float(t)).Z()] for t in ts]
    )
    d0 = np.array([_occt_distance(p, edges[0]) for p in pts])
    d1 = np.array([_occt_distance(p, edges[1]) for p in pts])
    assert np.max(np.abs(d0 - d1)) < 1e-9 * m.radius
    # and the error the tracer measured is an upper bound of what OCCT sees here
    assert np.max(np.abs(d0 - d1)) <= m.error * (1 + 1e-3) + 1e-13
    # on the fillet face (OCCT distance to the trimmed face)
    assert max(_occt_distance(p, face) for p in pts[::4]) < 1e-9 * m.radius
    # closed like the fillet (one vertex), and its pcurve on the face follows the 3-D curve
    assert np.linalg.norm(pts[0] - pts[-1]) < 1e-12
    c2 = BRep_Tool.CurveOnSurface_s(m.edge, face, 0.0, 0.0)
    surf = BRep_Tool.Surface_s(face)
    for t, p in zip(ts, pts, strict=True):
        uv = c2.Value(float(t))
        q = surf.Value(uv.X(), uv.Y())
        assert np.linalg.norm([q.X() - p[0], q.Y() - p[1], q.Z() - p[2]]) < 1e-9 * m.radius


def test_traced_medial_edge_splits_the_fillet_in_two(slanted):
    cls, spec, _, _, m = slanted
    split = split_along(cls.shape, [m.edge])
    assert len(split.pieces(spec.face)) == 2
    assert check(split.shape, with_volume=False).valid


def test_slanted_boss_keeps_its_fillet_with_the_missing_route(slanted):
    cls, spec, *_ = slanted
    r = simplify(cls.shape, specs_from_classification(cls))
    assert r.faces_after == r.faces_before == 11 and r.valid and not r.blends_removed
    ((face, why),) = r.blends_kept
    assert face == spec.face
    assert "not equidistant" not in why  # the medial curve is there now
    assert "cylinder" in why and "planar supporting faces only" in why
    assert r.volume_rel_change == 0.0
