"""The new edges' pcurves kept from one attempt to the next (truth: the same run without
the cache, counted projections, and geometry keys of copies and moved copies)."""

from __future__ import annotations

import pytest
from OCP.BRep import BRep_Tool
from OCP.Geom import Geom_BSplineCurve, Geom_Circle, Geom_CylindricalSurface, Geom_Plane
from OCP.GeomConvert import GeomConvert
from OCP.gp import gp_Ax2, gp_Ax3, gp_Dir, gp_Pnt, gp_Vec
from OCP.TopoDS import TopoDS

from medax.cad.simplify import geom_key as K
from medax.cad.simplify import local_measure as L
from medax.cad.simplify import parts as P
from medax.cad.simplify import pipeline, rebuild, simplify, specs_from_blend_faces
from medax.cad.simplify.occ import edges_of, faces_of
from medax.cad.simplify.search import Failure


def test_surface_and_curve_keys_are_the_geometry():
    """A copy has the key of its original; a copy moved by 1e-12, or another radius or
    kind, does not."""
    cyl = Geom_CylindricalSurface(gp_Ax3(gp_Pnt(1.0, 2.0, 3.0), gp_Dir(0.0, 0.0, 1.0)), 5.0)
    key = K.surface_key(cyl)
    assert key is not None and key == K.surface_key(cyl.Copy())
    moved = cyl.Translated(gp_Vec(1e-12, 0.0, 0.0))
    assert K.surface_key(moved) != key
    other = Geom_CylindricalSurface(gp_Ax3(gp_Pnt(1.0, 2.0, 3.0), gp_Dir(0.0, 0.0, 1.0)), 5.5)
    assert K.surface_key(other) != key
    plane = Geom_Plane(gp_Ax3(gp_Pnt(1.0, 2.0, 3.0), gp_Dir(0.0, 0.0, 1.0)))
    assert K.surface_key(plane) not in (None, key)
    part = P.box_vertical_fillets(40.0, 30.0, 20.0, 5.0)
    curves = [BRep_Tool.Curve_s(TopoDS.Edge(e), 0.0, 1.0) for e in edges_of(part.shape)]
    keys = [K.curve_key(c) for c in curves]
    assert None not in keys and keys == [K.curve_key(c.Copy()) for c in curves]
    assert any(type(c).__name__ == "Geom_TrimmedCurve" for c in curves)
    arc = Geom_Circle(gp_Ax2(gp_Pnt(1.0, 2.0, 3.0), gp_Dir(0.0, 0.0, 1.0)), 3.0)
    spline = GeomConvert.CurveToBSplineCurve_s(arc)
    assert isinstance(spline, Geom_BSplineCurve)
    skey = K.curve_key(spline)
    assert skey is not None and skey != K.curve_key(arc)
    spline.SetPole(2, spline.Pole(2).Translated(gp_Vec(0.0, 0.0, 1e-12)))
    assert K.curve_key(spline) != skey


@pytest.fixture(scope="module")
def box4():
    return P.box_vertical_fillets(40.0, 30.0, 20.0, 5.0)


def _run(part, monkeypatch, cached: bool):  # type: ignore[no-untyped-def]
    """The part simplified with its first attempt refused (a failure traced to one
    fillet: the search rebuilds the others as before); the result, the projections made,
    and the jobs seen."""
    specs = specs_from_blend_faces(part.shape, part.blends)
    real_validated, real_projected = pipeline._validated, rebuild._projected_pcurve
    jobs: list = []
    calls: list = []

    def first_refused(job, *args):  # type: ignore[no-untyped-def]
        out = real_validated(job, *args)
        jobs.append(job)
        return Failure("refused (test)", {part.blends[0]}) if len(jobs) == 1 else out

    def projected(*args):  # type: ignore[no-untyped-def]
        calls.append(len(jobs))
        return real_projected(*args)

    monkeypatch.setattr(pipeline, "_validated", first_refused)
    monkeypatch.setattr(rebuild, "_projected_pcurve", projected)
    if not cached:
        monkeypatch.setattr(L.Measures, "get", lambda self, key, compute: compute())
    r = simplify(part.shape, specs)
    monkeypatch.undo()
    return r, calls, jobs


def _pcurve_keys(shape):  # type: ignore[no-untyped-def]
    out = []
    for f in faces_of(shape):
        for e in edges_of(f):
            pc = BRep_Tool.CurveOnSurface_s(TopoDS.Edge(e), TopoDS.Face(f), 0.0, 0.0)
            out.append(None if pc is None else K.curve2d_key(pc))
    return out


def test_second_attempt_reuses_the_pcurves_with_the_same_result(box4, monkeypatch):
    """The attempt after a refusal projects no edge the first one projected (without the
    cache it projects them all again), and the solid, its numbers and every pcurve are
    the same bits as without the cache."""
    r, calls, jobs = _run(box4, monkeypatch, cached=True)
    plain, plain_calls, _ = _run(box4, monkeypatch, cached=False)
    assert len(jobs) >= 2 and r.valid and sorted(r.blends_removed) == sorted(box4.blends[1:])
    first = calls.count(0)
    again = len(plain_calls) - plain_calls.count(0)  # what the later attempts project anew
    assert first > 0 and plain_calls.count(0) == first
    assert again > 0 and len(calls) - first < again
    assert jobs[-1].pcurves.hits > 0
    assert sorted(plain.blends_removed) == sorted(r.blends_removed)
    assert (plain.faces_after, plain.volume_after, plain.max_deviation) == (
        r.faces_after,
        r.volume_after,
        r.max_deviation,
    )
    keys = _pcurve_keys(r.shape)
    assert any(k is not None for k in keys) and keys == _pcurve_keys(plain.shape)


def test_loose_boundary_key_is_the_old_face_and_its_pcurve():
    """The key of a boundary followed on an old face: the same for the face of a copy,
    another for the other face of the edge and for the face moved by 1e-9."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy, BRepBuilderAPI_Transform
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Trsf

    from medax.cad.simplify.occ import edge_curve

    def first(shape):  # type: ignore[no-untyped-def]
        face = TopoDS.Face(next(iter(faces_of(shape))))
        edge = TopoDS.Edge(next(iter(edges_of(face))))
        return face, edge

    box = BRepPrimAPI_MakeBox(2.0, 3.0, 4.0).Shape()
    face, edge = first(box)
    c = edge_curve(edge)[0]
    key = rebuild._BoundaryOnFace(edge, face, c).key()
    assert key is not None
    cface, cedge = first(BRepBuilderAPI_Copy(box).Shape())
    assert rebuild._BoundaryOnFace(cedge, cface, c).key() == key
    other = next(
        TopoDS.Face(f)
        for f in faces_of(box)
        if not f.IsSame(face) and any(e.IsSame(edge) for e in edges_of(f))
    )
    assert rebuild._BoundaryOnFace(edge, other, c).key() not in (None, key)
    t = gp_Trsf()
    t.SetTranslation(gp_Vec(1e-9, 0.0, 0.0))
    mface, medge = first(BRepBuilderAPI_Transform(box, t, False).Shape())
    assert rebuild._BoundaryOnFace(medge, mface, c).key() not in (None, key)


def _loose_square(pcurve_of_right_side):
    """A 10 x 10 square face on the plane z = 0 (a B-spline surface, as fitted faces are)
    whose right side (x = 10, y from 0 to 10) has the given pcurve and the tolerance 5e-3;
    the other sides' pcurves are exact."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeVertex
    from OCP.Geom import Geom_RectangularTrimmedSurface
    from OCP.Geom2d import Geom2d_Line
    from OCP.gp import gp_Dir2d, gp_Pnt2d
    from OCP.TopoDS import TopoDS_Face, TopoDS_Wire

    plane = GeomConvert.SurfaceToBSplineSurface_s(
        Geom_RectangularTrimmedSurface(
            Geom_Plane(gp_Ax3(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0))),
            -5.0,
            15.0,
            -5.0,
            15.0,
        )
    )
    corners = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
    builder = BRep_Builder()
    face, wire = TopoDS_Face(), TopoDS_Wire()
    builder.MakeFace(face, plane, 1e-7)
    builder.MakeWire(wire)
    edges = []
    vertices = [BRepBuilderAPI_MakeVertex(gp_Pnt(*c, 0.0)).Vertex() for c in corners]
    for i, (a, b) in enumerate(zip(corners, corners[1:] + corners[:1], strict=True)):
        edge = BRepBuilderAPI_MakeEdge(vertices[i], vertices[(i + 1) % 4]).Edge()
        d = gp_Dir2d(b[0] - a[0], b[1] - a[1])
        pc = pcurve_of_right_side if i == 1 else Geom2d_Line(gp_Pnt2d(*a), d)
        builder.UpdateEdge(edge, pc, face, 5e-3 if i == 1 else 1e-7)
        builder.Range(edge, face, 0.0, 10.0)
        builder.Add(wire, edge)
        edges.append(edge)
    wire.Closed(True)
    builder.Add(face, wire)
    return face, edges


def _area(face):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, 1e-12, False)
    return props.Mass()


@pytest.mark.parametrize("kind", ["bspline", "line"])
def test_pcurves_that_miss_each_other_are_joined(kind):
    """A pcurve that runs up to 3e-3 off its edge and misses the next one by as much
    (within its edge's tolerance, as on loose inputs) gives the face another area (by
    1.5 - 3e-2); its ends moved onto its neighbours', the face is the square again
    (truth: the square's area 100; the pcurves end where the next ones start; the
    tolerances are not tightened and the exact sides are not touched)."""
    from OCP.collections import Array1_double, Array1_gp_Pnt2d, Array1_int
    from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_Line
    from OCP.gp import gp_Dir2d, gp_Pnt2d

    if kind == "bspline":  # ends at (9.997, 10)
        poles, knots, mults = Array1_gp_Pnt2d(1, 2), Array1_double(1, 2), Array1_int(1, 2)
        poles.SetValue(1, gp_Pnt2d(10.0, 0.0))
        poles.SetValue(2, gp_Pnt2d(9.997, 10.0))
        for i, k in enumerate((0.0, 10.0)):
            knots.SetValue(i + 1, k)
            mults.SetValue(i + 1, 2)
        pc = Geom2d_BSplineCurve(poles, knots, mults, 1)
    else:  # from (10.003, 0) to (10.003, 10): misses at both ends
        pc = Geom2d_Line(gp_Pnt2d(10.003, 0.0), gp_Dir2d(0.0, 1.0))
    face, edges = _loose_square(pc)
    assert abs(_area(face) - 100.0) > 1e-2
    rebuild._close_uv_gaps(face, [edges[1]], BRep_Tool.Surface_s(face), 1e-7)
    assert _area(face) == pytest.approx(100.0, abs=1e-9)
    moved = BRep_Tool.CurveOnSurface_s(edges[1], face, 0.0, 0.0)
    assert moved.Value(0.0).Distance(gp_Pnt2d(10.0, 0.0)) < 1e-12
    assert moved.Value(10.0).Distance(gp_Pnt2d(10.0, 10.0)) < 1e-12
    assert BRep_Tool.Tolerance_s(edges[1]) >= 5e-3  # not tightened
    # the exact sides' pcurves are not touched
    for e in (edges[0], edges[2]):
        assert BRep_Tool.Tolerance_s(e) == 1e-7
