"""The traced medial curve of a B-spline blend whose mid iso-line is not equidistant (the
catalogue's slanted boss: a rolling ball between a plate and a slanted cylinder), checked
against OCCT's own distances (the simplification of that part, which now removes the
fillet by the ring route: tests/test_simplify_ring.py)."""

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
from medax.cad.simplify import specs_from_classification
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


def test_traced_medial_edge_taken_to_the_iso_line_tolerance(slanted, monkeypatch):
    """A traced medial curve that misses ``rel_tol x radius`` with the most nodes is taken
    when it is within ``accept`` (the tolerance an iso-line is accepted with: twice the
    build tolerance or the input's own), and refused when it is not; its measured error
    bounds OCCT's."""
    import medax.cad.simplify.medial as medial
    import medax.cad.simplify.traced as traced

    _, _, face, edges, _ = slanted
    monkeypatch.setattr(traced, "MAX_NODES", traced.NODES)  # one round: 24 nodes per span
    calls = []

    def spy(*args):  # type: ignore[no-untyped-def]
        calls.append(args)
        return traced.traced_medial_edge(*args)

    monkeypatch.setattr(medial, "traced_medial_edge", spy)
    m = medial_curve(face, *edges, rel_tol=1e-11)
    (args,) = calls
    accept = args[6]  # (face, edges, k, cross, along, tol, accept, early)
    assert not isinstance(m, str), m
    assert m.iso == TRACED and 1e-11 * m.radius < m.error <= accept
    refused = traced.traced_medial_edge(*args[:6], 0.5 * m.error)
    assert isinstance(refused, str) and refused.startswith("traced medial curve error")
    ad = BRepAdaptor_Curve(m.edge)
    ts = np.linspace(ad.FirstParameter(), ad.LastParameter(), 41)
    pts = [ad.Value(float(t)) for t in ts]
    gap = [
        abs(_occt_distance(np.array([p.X(), p.Y(), p.Z()]), edges[0])
            - _occt_distance(np.array([p.X(), p.Y(), p.Z()]), edges[1]))
        for p in pts
    ]  # fmt: skip
    assert max(gap) <= m.error * (1 + 1e-3) + 1e-13


def test_traced_medial_edge_stops_at_the_pole_budget(slanted, monkeypatch):
    """Once the error is within ``accept``, the nodes are not doubled past ``MAX_POLES``
    (OCCT's splitter slows down steeply with the tool's poles); with no ``accept`` they are
    doubled until ``tol`` (here out of reach) and the curve is refused with the most."""
    import medax.cad.simplify.traced as traced

    _, _, face, edges, m = slanted
    calls = []
    real = traced.traced_medial_edge

    def spy(*args):  # type: ignore[no-untyped-def]
        calls.append(args)
        return real(*args)

    import medax.cad.simplify.medial as medial

    monkeypatch.setattr(medial, "traced_medial_edge", spy)
    medial_curve(face, *edges)
    (args,) = calls
    rounds = []
    measure = traced._measure

    def count(*a):  # type: ignore[no-untyped-def]
        rounds.append(a[-1])
        return measure(*a)

    monkeypatch.setattr(traced, "_measure", count)
    monkeypatch.setattr(traced, "MAX_POLES", 0)  # every doubling is past the budget
    tol = 1e-11 * m.radius  # out of reach with 24 or 48 nodes per span
    got = real(*args[:5], tol, 1e-3 * m.radius, 1e-3 * m.radius)  # accept, early loose
    assert not isinstance(got, str), got
    assert rounds == [traced.NODES] and got[1] <= 1e-3 * m.radius
    poles = BRep_Tool.Curve_s(got[0], 0.0, 0.0).NbPoles()
    spans = traced._spans(BRep_Tool.Surface_s(face), args[2], *args[4])
    assert poles <= len(spans) * traced.NODES + traced.DEGREE  # one round's nodes
    rounds.clear()
    monkeypatch.setattr(traced, "MAX_NODES", 2 * traced.NODES)
    refused = real(*args[:5], tol, 0.0, 1e-3 * m.radius)
    assert isinstance(refused, str), refused  # doubled to MAX_NODES, then refused
    assert rounds == [traced.NODES, 2 * traced.NODES]


def test_traced_medial_edge_splits_the_fillet_in_two(slanted):
    cls, spec, _, _, m = slanted
    split = split_along(cls.shape, [m.edge])
    assert len(split.pieces(spec.face)) == 2
    assert check(split.shape, with_volume=False).valid


def test_degree_13_blend_evaluated_to_occt_precision(slanted):
    """The blend is of degree 13 along the boss: the power basis lost ~1e-9 there (the plate
    half's heights then failed to converge); Cox-de Boor matches OCCT to ~1e-13."""
    from OCP.gp import gp_Vec

    from medax.cad.face_region import surface_embedding

    _, _, face, _, _ = slanted
    emb = surface_embedding(face)
    surf = BRep_Tool.Surface_s(face)
    u0, u1, v0, v1 = surf.Bounds()
    rng = np.random.default_rng(3)
    uv = np.column_stack([rng.uniform(u0, u1, 200), rng.uniform(v0, v1, 200)])
    x, du, dv = emb.jet(uv)
    worst = 0.0
    for (u, v), p, a, b in zip(uv, x, du, dv, strict=True):
        q, qu, qv = gp_Pnt(), gp_Vec(), gp_Vec()
        surf.D1(float(u), float(v), q, qu, qv)
        worst = max(worst, np.linalg.norm(p - [q.X(), q.Y(), q.Z()]))
        assert np.allclose(a, [qu.X(), qu.Y(), qu.Z()], rtol=1e-9, atol=1e-9)
        assert np.allclose(b, [qv.X(), qv.Y(), qv.Z()], rtol=1e-9, atol=1e-9)
    assert worst < 1e-12


def test_plate_half_is_a_height_field(slanted):
    """Split along the traced medial curve, the plate and its half blend are a height field
    over the plate (the probe fit: defined everywhere on the face)."""
    from medax.cad.simplify.fitted import FittedSurface, graph_surface
    from medax.cad.simplify.groups import build_groups
    from medax.cad.simplify.occ import diagonal

    cls, spec, _, _, m = slanted
    split = split_along(cls.shape, [m.edge])
    groups = build_groups(split, {spec.face: spec.supporting}, {})
    (g,) = [g for g in groups if g.support == spec.supporting[0]]
    plate = TopoDS.Face(shape_map(cls.shape, TopAbs_FACE).FindKey(g.support + 1))
    members = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
    diag = diagonal(cls.shape)
    r = graph_surface(plate, members, 1e-6 * diag, 1e-7 * diag, probe=True)
    assert isinstance(r, FittedSurface), r
    assert np.isfinite(r.error)
