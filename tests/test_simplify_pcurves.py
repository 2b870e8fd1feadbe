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
