"""The new edges' pcurves kept from one attempt to the next (truth: the same run without
the cache, counted projections, and geometry keys of copies and moved copies)."""

from __future__ import annotations

import pytest
from OCP.BRep import BRep_Tool
from OCP.Geom import (
    Geom_BSplineCurve,
    Geom_Circle,
    Geom_CylindricalSurface,
    Geom_Plane,
    Geom_RectangularTrimmedSurface,
)
from OCP.Geom2d import Geom2d_Circle
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
    real_validated, real_projected = pipeline.validated, rebuild._projected_pcurve
    jobs: list = []
    calls: list = []

    def first_refused(job, *args):  # type: ignore[no-untyped-def]
        out = real_validated(job, *args)
        jobs.append(job)
        return Failure("refused (test)", {part.blends[0]}) if len(jobs) == 1 else out

    def projected(*args):  # type: ignore[no-untyped-def]
        calls.append(len(jobs))
        return real_projected(*args)

    monkeypatch.setattr(pipeline, "validated", first_refused)
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


def test_new_pcurves_follow_the_edges_not_an_old_loose_boundary():
    """An old square face whose right side's pcurve runs 3e-3 off its edge (within the
    edge's tolerance 5e-3, as on loose inputs); a new face on another surface through the
    same edges gets pcurves of the 3-D curves: they meet at the vertices and the face is
    the square (truth: its area 100, its corners)."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeVertex
    from OCP.BRepGProp import BRepGProp
    from OCP.Geom import Geom_RectangularTrimmedSurface
    from OCP.Geom2d import Geom2d_Line
    from OCP.gp import gp_Dir2d, gp_Pnt2d
    from OCP.GProp import GProp_GProps
    from OCP.TopoDS import TopoDS_Face, TopoDS_Wire

    plane = Geom_Plane(gp_Ax3(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)))
    corners = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
    vertices = [BRepBuilderAPI_MakeVertex(gp_Pnt(*c, 0.0)).Vertex() for c in corners]
    builder = BRep_Builder()
    old, new = TopoDS_Face(), TopoDS_Face()
    builder.MakeFace(old, plane, 1e-7)
    # the new surface: the same plane as a B-spline (no pcurves of the edges on it yet)
    bspline = GeomConvert.SurfaceToBSplineSurface_s(
        Geom_RectangularTrimmedSurface(plane, -5.0, 15.0, -5.0, 15.0)
    )
    builder.MakeFace(new, bspline, 1e-7)
    wires = [TopoDS_Wire(), TopoDS_Wire()]
    for w in wires:
        builder.MakeWire(w)
    for i, (a, b) in enumerate(zip(corners, corners[1:] + corners[:1], strict=True)):
        edge = BRepBuilderAPI_MakeEdge(vertices[i], vertices[(i + 1) % 4]).Edge()
        start = (a[0] + 3e-3, a[1]) if i == 1 else a  # the right side, 3e-3 off in x
        pc = Geom2d_Line(gp_Pnt2d(*start), gp_Dir2d(b[0] - a[0], b[1] - a[1]))
        builder.UpdateEdge(edge, pc, old, 5e-3 if i == 1 else 1e-7)
        builder.Range(edge, old, 0.0, 10.0)
        for w in wires:
            builder.Add(w, edge)
    for face, w in zip((old, new), wires, strict=True):
        w.Closed(True)
        builder.Add(face, w)

    rebuild._add_pcurves(new, 1e-7)
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(new, props, 1e-12, False)
    assert props.Mass() == pytest.approx(100.0, abs=1e-9)
    for e in edges_of(new):
        pc = BRep_Tool.CurveOnSurface_s(TopoDS.Edge(e), new, 0.0, 0.0)
        f, l = BRep_Tool.Range_s(TopoDS.Edge(e), new)
        ends = [pc.Value(f).Coord(), pc.Value(l).Coord()]
        assert all(min(abs(x - c[0]) + abs(y - c[1]) for c in corners) < 1e-9 for x, y in ends)


def _graph_surface(heights):  # type: ignore[no-untyped-def]
    """A cubic B-spline graph ``o + u ex + v ey + c(u, v) n`` in a tilted frame: poles at
    the Greville abscissae of non-uniform knots, heights ``heights(gu, gv)``."""
    import numpy as np
    from OCP.collections import Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface

    from medax.cad.simplify.occ import knot_arrays
    from medax.geometry.tensor_fit import greville

    o = np.array([1.0, -2.0, 0.5])
    ex = np.array([np.cos(0.3), np.sin(0.3), 0.0])
    n = np.array([0.0, -np.sin(0.2), np.cos(0.2)])
    n -= (n @ ex) * ex
    n /= np.linalg.norm(n)
    ey = np.cross(n, ex)
    tu = np.r_[[0.0] * 4, 1.0, 2.5, 3.0, [5.0] * 4]
    tv = np.r_[[-1.0] * 4, 0.5, 2.0, [4.0] * 4]
    gu, gv = greville(tu), greville(tv)
    c = heights(*np.meshgrid(gu, gv, indexing="ij"))
    poles = Array2_gp_Pnt(1, len(gu), 1, len(gv))
    for i, a in enumerate(gu):
        for j, b in enumerate(gv):
            poles.SetValue(i + 1, j + 1, gp_Pnt(*map(float, o + a * ex + b * ey + c[i, j] * n)))

    (uk, um), (vk, vm) = knot_arrays(tu), knot_arrays(tv)
    return Geom_BSplineSurface(poles, uk, vk, um, vm, 3, 3), (o, ex, ey, n)


def test_a_curve_on_a_graph_surface_has_its_affine_image_as_pcurve():
    """On a fitted (graph) surface the pcurve of a curve on it is its image along the
    normal, on the curve's own parameter: an iso-curve's pcurve is the iso-line (to
    1e-12), a circle's in a plane parallel to the frame a circle; an oblique circle (an
    ellipse in the plane) has none. Not graphs: a rational surface, perturbed poles."""
    import numpy as np
    from OCP.Geom import Geom_BSplineSurface

    from medax.cad.simplify.occ import xyz
    from medax.cad.simplify.projection import graph_frame

    surf, (o, ex, ey, n) = _graph_surface(lambda u, v: 0.3 * u * u - 0.2 * u * v + np.sin(v))
    frame = graph_frame(surf)
    assert frame is not None
    for iso, fixed in ((surf.UIso(2.2), "u"), (surf.VIso(0.7), "v")):
        pc = rebuild._affine_pcurve(iso, iso.FirstParameter(), iso.LastParameter(), *frame)
        for t in np.linspace(iso.FirstParameter(), iso.LastParameter(), 13):
            uv = pc.Value(float(t))
            want = (2.2, t) if fixed == "u" else (t, 0.7)
            assert abs(uv.X() - want[0]) < 1e-12 and abs(uv.Y() - want[1]) < 1e-12
        assert (
            rebuild._pcurve_error(pc, iso, surf, iso.FirstParameter(), iso.LastParameter()) < 1e-12
        )
    flat, (o, ex, ey, n) = _graph_surface(lambda u, v: 0.25 + 0 * u)
    frame = graph_frame(flat)
    assert frame is not None
    centre = o + 2.0 * ex + 1.5 * ey + 0.25 * n
    circle = Geom_Circle(gp_Ax2(gp_Pnt(*centre), gp_Dir(*n), gp_Dir(*ey)), 0.8)
    pc = rebuild._affine_pcurve(circle, 0.3, 2.9, *frame)
    assert isinstance(pc, Geom2d_Circle) and abs(pc.Radius() - 0.8) < 1e-12
    for t in np.linspace(0.3, 2.9, 9):
        uv = pc.Value(float(t))
        assert np.linalg.norm(xyz(flat.Value(uv.X(), uv.Y())) - xyz(circle.Value(float(t)))) < 1e-12
    tilted = Geom_Circle(gp_Ax2(gp_Pnt(*centre), gp_Dir(*(n + 0.3 * ex))), 0.8)
    assert rebuild._affine_pcurve(tilted, 0.0, 1.0, *frame) is None
    cylinder = Geom_CylindricalSurface(gp_Ax3(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), 2.0)
    rational = GeomConvert.SurfaceToBSplineSurface_s(
        Geom_RectangularTrimmedSurface(cylinder, 0.0, 1.5, 0.0, 3.0)
    )
    assert isinstance(rational, Geom_BSplineSurface) and graph_frame(rational) is None
    bent = surf.Copy()
    bent.SetPole(3, 2, bent.Pole(3, 2).Translated(gp_Vec(*(1e-6 * ex))))
    assert graph_frame(bent) is None


def test_an_oblique_circle_near_a_fitted_surface_needs_no_occt_projection(monkeypatch):
    """A circle oblique to a fitted (graph) surface, lying 2e-6 off it along the normal
    (as a fitted face's edges lie off its surface within the fit's error): its pcurve comes
    from the grid's feet, OCCT's projection is never called (it fails here if it is), and
    the pcurve's error is within NEAR_FLOOR of the circle's own distance from the surface
    (no pcurve is nearer), measured independently by OCCT's point projection."""
    import numpy as np
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf

    from medax.cad.simplify.projection import GridProjection, graph_frame

    flat, (o, ex, ey, n) = _graph_surface(lambda u, v: 0.25 + 0 * u)
    frame = graph_frame(flat)
    assert frame is not None
    centre = o + 2.0 * ex + 1.5 * ey + (0.25 + 2e-6) * n
    tilted = Geom_Circle(gp_Ax2(gp_Pnt(*centre), gp_Dir(*(n + 1e-5 * ex))), 0.8)

    def no_projection(*args):  # type: ignore[no-untyped-def]
        raise AssertionError("OCCT's projection was called")

    monkeypatch.setattr(rebuild.GeomProjLib, "Curve2d_s", no_projection)
    u0, u1, v0, v1 = (float(x) for x in flat.Bounds())
    grid = GridProjection.of(flat, (u0, u1, v0, v1))
    pc, err = rebuild._edge_pcurve(tilted, 0.3, 2.9, flat, 1e-7, lambda: grid, lambda: frame)
    assert pc is not None
    gaps = []
    for t in np.linspace(0.3, 2.9, 41):
        p = tilted.Value(float(t))
        gaps.append(GeomAPI_ProjectPointOnSurf(p, flat).LowerDistance())
    assert 1e-6 < max(gaps) < 1e-5
    assert err <= rebuild.NEAR_FLOOR * max(gaps) * (1 + 1e-6)
    for t in np.linspace(0.3, 2.9, 7):  # on the circle's own parameter
        uv = pc.Value(float(t))
        q = np.array(flat.Value(uv.X(), uv.Y()).Coord())
        assert np.linalg.norm(q - np.array(tilted.Value(float(t)).Coord())) <= err * 1.01
