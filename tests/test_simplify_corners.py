"""Corner blends and fitted merged faces: a box with all 12 edges filleted (8 sphere corners),
simplified by the exact rounded-box surface (:mod:`medax.cad.simplify.rounded`) and, with
that route switched off, by the height-field fit (as on faces whose corners are no spheres).

Truth: the closed-form volume of a rounded box (Steiner's formula), OCCT's own validity check,
distances between old and new boundaries measured with BRepExtrema on the whole solids, and
the crease angle across the new edges (the original boundary is smooth there).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS

from medax.cad.simplify import merging, simplify, specs_from_blend_faces
from medax.cad.simplify import parts as P
from medax.cad.simplify.occ import edge_points, max_normal_angle, shape_map
from medax.cad.simplify.specs import edge_face_map
from medax.cad.simplify.validate import check
from truth import boundary_distances, face_neighbours

pytestmark = pytest.mark.slow  # OCCT-heavy: module fixtures build and simplify parts

A, B, H, R = 40.0, 30.0, 20.0, 4.0


@pytest.fixture(scope="module", params=["exact", "fitted"])
def box12(request):
    """(part, result, route): ``exact`` the rounded-box surface, ``fitted`` the height field."""
    part = P.box_all_fillets(A, B, H, R)
    with pytest.MonkeyPatch.context() as mp:
        if request.param == "fitted":
            mp.setattr(merging, "rounded_surface", lambda *args: "switched off")
        r = simplify(part.shape, specs_from_blend_faces(part.shape, part.blends))
    return part, r, request.param


def test_box12_every_blend_absorbed(box12):
    part, r, _ = box12
    assert (r.faces_before, r.faces_after) == (26, 6)
    assert sorted(r.blends_removed) == sorted(part.blends) and not r.blends_kept
    c = check(r.shape)
    assert c.valid and c.shells == 1 and c.closed
    # a box's faces again: each meets four others, the opposite one not at all
    assert [len(n) for n in face_neighbours(r.shape)] == [4] * 6


def test_box12_volume_matches_closed_form(box12):
    _, r, _ = box12
    exact = _rounded_box_volume(A, B, H, R)
    assert abs(r.volume_before - exact) <= 1e-9 * exact
    assert abs(r.volume_after - exact) <= 1e-6 * exact
    assert abs(r.volume_rel_change) <= 1e-6


def test_box12_shape_unchanged_both_ways(box12):
    """Old and new boundaries within 1e-5 x diagonal of each other (the issue's fitted
    target), measured on the whole solids, not the pipeline's per-group check."""
    part, r, route = box12
    old_to_new, new_to_old = boundary_distances(part.shape, r.shape, 9, 24)
    # the exact surfaces are the old ones to rounding; the fit within its target
    limit = 1e-9 if route == "exact" else 1e-5
    assert old_to_new <= limit * r.diagonal and new_to_old <= limit * r.diagonal
    # the fit's own measured error is reported and within its share of the tolerance
    assert 0 < r.fit_error <= (1e-12 if route == "exact" else 1e-6) * r.diagonal


def test_box12_no_crease_across_new_edges(box12):
    """The merged faces meet tangentially along the medial curves (the original is smooth
    there): normals of the two faces at samples of every edge agree to 2e-3 rad (1.7e-3 at
    worst, near the fitted corners: the split solid's edge pieces put samples there)."""
    _, r, _ = box12
    fmap = shape_map(r.shape, TopAbs_FACE)
    emap = shape_map(r.shape, TopAbs_EDGE)
    e2f = edge_face_map(r.shape)
    worst = 0.0
    for i in range(1, emap.Size() + 1):
        e = TopoDS.Edge(emap.FindKey(i))
        f1, f2 = (TopoDS.Face(f) for f in e2f.FindFromKey(e))
        pts = edge_points(e, 9)[1:-1]
        worst = max(worst, max_normal_angle(f1, f2, pts))
    assert fmap.Size() == 6
    assert worst < 2e-3


def test_box12_face_groups(box12):
    part, r, route = box12
    groups = r.report()["face_groups"]
    kind = "rounded" if route == "exact" else "fitted"
    assert len(groups) == 6 and all(g["surface"] == kind for g in groups)
    cylinders = set(part.blends) - _spheres(part)
    for g in groups:
        assert len(g["original_faces"]) == 1
        halves = set(g["fillet_halves"])
        assert len(halves & cylinders) == 4 and len(halves - cylinders) == 4
    # each fillet gives its two halves to two faces, each corner its three pieces to three
    used = sorted(h for g in groups for h in g["fillet_halves"])
    assert used == sorted(list(cylinders) * 2 + list(_spheres(part)) * 3)


def test_box12_exact_surfaces(box12):
    """The rounded-box route: every merged face on one C1 rational bicubic with 8 poles
    across (the fit needs about 34; along it, knots inserted for OCCT's default mass
    properties: :func:`.occ.reader_spans`), the volume the closed form's to rounding."""
    from OCP.BRep import BRep_Tool

    from medax.cad.simplify.occ import faces_of

    _, r, route = box12
    if route != "exact":
        pytest.skip("the exact route only")
    for f in faces_of(r.shape):
        s = BRep_Tool.Surface_s(f)
        assert (s.NbUPoles(), s.UDegree(), s.VDegree()) == (8, 3, 3)
        assert s.NbVKnots() - 1 >= 8
        assert s.IsURational() and s.IsVRational()
        assert s.IsCNu(1) and s.IsCNv(1)
    exact = _rounded_box_volume(A, B, H, R)
    assert abs(r.volume_after - exact) <= 1e-9 * exact


def _rounded_box_volume(a: float, b: float, c: float, r: float) -> float:
    """Steiner's formula: a box ``a x b x c`` with all edges rounded by ``r``."""
    x, y, z = a - 2 * r, b - 2 * r, c - 2 * r
    return (
        x * y * z
        + 2 * r * (x * y + y * z + z * x)
        + math.pi * r**2 * (x + y + z)
        + 4 / 3 * (math.pi * r**3)
    )


def test_pocket_concave_rounded_faces():
    """Concave strips and sphere corners (a filleted pocket): the floor and the four walls
    merge onto exact rounded-box surfaces, the solid is the input to rounding (whole-solid
    distances both ways) and keeps the closed-form volume (the pocket mirrored across the
    top is a rounded box)."""
    from truth import assert_same_solid

    part = P.pocket_fillets(60.0, 50.0, 20.0, 12.0, 3.0)
    r = simplify(part.shape, specs_from_blend_faces(part.shape, part.blends))
    assert (r.faces_before, r.faces_after) == (23, 11) and not r.blends_kept
    kinds = [g["surface"] for g in r.report()["face_groups"]]
    assert kinds.count("rounded") == 5 and set(kinds) == {"rounded", "original"}
    assert_same_solid(part.shape, r, volume_tol=1e-9, deviation_tol=1e-9)
    exact = 60.0 * 50.0 * 20.0 - _rounded_box_volume(40.0, 30.0, 24.0, 3.0) / 2
    assert abs(r.volume_after - exact) <= 1e-9 * exact


def _faces_by_kind(shape):
    from OCP.BRepAdaptor import BRepAdaptor_Surface

    from medax.cad.simplify.occ import faces_of

    out: dict[str, list] = {}
    for f in faces_of(shape):
        kind = str(BRepAdaptor_Surface(f).GetType()).split("_")[-1]
        out.setdefault(kind, []).append(f)
    return out


def _top(faces):
    from medax.cad.simplify.occ import face_inside_point

    return max(faces, key=lambda f: face_inside_point(f)[2])


def test_rounded_surface_refusals():
    """Not a rounded box's face: a curved support, pieces of unequal radii, whole fillets
    (their arcs run to 90 degrees: no graph over the plane)."""
    from medax.cad.simplify.occ import face_inside_point
    from medax.cad.simplify.rounded import rounded_surface

    big, small = (_faces_by_kind(P.box_all_fillets(A, B, H, r).shape) for r in (R, 3.0))
    top = _top(big["Plane"])
    # the cylinders along the top face's edges: their inside points are highest
    cyl4 = sorted(big["Cylinder"], key=lambda f: -face_inside_point(f)[2])[:4]
    cyl3 = sorted(small["Cylinder"], key=lambda f: -face_inside_point(f)[2])[:4]
    assert "planar" in rounded_surface(cyl4[0], [top, *cyl4], 1e-7)
    assert "unequal radii" in rounded_surface(top, [top, cyl4[0], cyl3[1]], 1e-7)
    assert "too steep" in rounded_surface(top, [top, *cyl4], 1e-7)


def _spheres(part):
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Sphere

    fmap = shape_map(part.shape, TopAbs_FACE)
    return {
        i - 1
        for i in range(1, fmap.Size() + 1)
        if BRepAdaptor_Surface(TopoDS.Face(fmap.FindKey(i))).GetType() == GeomAbs_Sphere
    }


def test_torus_heights_match_occt_intersections():
    """Lines along the axis (closed form) against OCCT's own curve/surface intersection."""
    from matplotlib.path import Path
    from OCP.Geom import Geom_Line, Geom_ToroidalSurface
    from OCP.GeomAPI import GeomAPI_IntCS
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    from medax.cad.simplify.fitted import _heights, _Member

    centre, axis, big, small = np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 1.0]), 10.0, 2.0
    dummy = Path(np.zeros((3, 2)))
    m = _Member("torus", centre, axis, small, dummy, (), (np.zeros((1, 2)),), big)
    n = np.array([0.0, 0.0, -1.0])  # looking down onto the torus' top
    rng = np.random.default_rng(5)
    ang = rng.uniform(0, 2 * np.pi, 200)
    rad = big + rng.uniform(-1.99, 1.99, 200)
    q = centre + np.column_stack([rad * np.cos(ang), rad * np.sin(ang), np.full(200, 5.0)])
    t, ok = _heights(m, q, n)
    torus = Geom_ToroidalSurface(gp_Ax3(gp_Pnt(*centre), gp_Dir(*axis)), big, small)
    for qi, ti in zip(q, t, strict=True):
        inter = GeomAPI_IntCS(Geom_Line(gp_Pnt(*qi), gp_Dir(*n)), torus)
        hits = [qi[2] - inter.Point(k).Z() for k in range(1, inter.NbPoints() + 1)]
        assert abs(ti - min(hits, key=abs)) <= 1e-9
    # steep hits (the tube's normal more than 70 degrees from n) are flagged, not used:
    # the tube's slope angle at offset s from its crest is arcsin(s / small)
    slope = np.degrees(np.arcsin(np.abs(rad - big) / small))
    assert np.all(ok[slope < 69.0]) and not np.any(ok[slope > 71.0])
    assert ok.sum() > 10 and (~ok).sum() > 3


@pytest.mark.parametrize(
    "n", [(0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.3, -0.2, 0.93)], ids=["normal", "along", "oblique"]
)
def test_torus_heights_every_direction(n):
    """Lines normal to the axis (two circles per height, closed form), along it and oblique
    (the batched quartic): the root nearest the start against OCCT's intersections, and
    where OCCT finds none the line is refused (the closed forms refuse nothing else)."""
    from matplotlib.path import Path
    from OCP.Geom import Geom_Line, Geom_ToroidalSurface
    from OCP.GeomAPI import GeomAPI_IntCS
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    from medax.cad.simplify import fitted

    n = np.array(n) / np.linalg.norm(n)
    centre, axis, big, small = np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 1.0]), 6.0, 2.0
    m = fitted._Member("torus", centre, axis, small, Path(np.zeros((3, 2))), (), (), big)
    q = centre + np.random.default_rng(8).uniform(-9.0, 9.0, (150, 3))
    aligned = abs(n[2]) in (0.0, 1.0)
    if aligned:  # the closed forms, before the slope check
        t, ok = fitted._torus_heights_aligned(m, q - centre, n, float(n @ axis))
    else:
        t, ok = fitted._heights(m, q, n)
    torus = Geom_ToroidalSurface(gp_Ax3(gp_Pnt(*centre), gp_Dir(*axis)), big, small)
    for qi, ti, oki in zip(q, t, ok, strict=True):
        inter = GeomAPI_IntCS(Geom_Line(gp_Pnt(*qi), gp_Dir(*n)), torus)
        hits = [
            float((fitted.xyz(inter.Point(k)) - qi) @ n) for k in range(1, inter.NbPoints() + 1)
        ]
        if not hits:
            assert not oki
            continue
        assert oki or not aligned
        if oki:  # (the oblique path also refuses steep hits)
            assert abs(ti - min(hits, key=abs)) <= 1e-9
    assert ok.sum() > 20 and (~ok).sum() > 20


def test_box12_two_volume_measures_agree(box12):
    """The fits' own signed volumes against the exact heights (numpy) and OCCT's integrator
    on the rebuilt solid measure the same tiny volume change."""
    _, r, route = box12
    if route == "exact":  # no change, measured as none by OCCT too
        assert r.fit_volume_rel_change == 0.0 and abs(r.volume_rel_change) <= 1e-9
        return
    assert r.fit_volume_rel_change != 0.0
    assert abs(r.fit_volume_rel_change) <= 1e-6
    assert abs(r.fit_volume_rel_change - r.volume_rel_change) <= 1e-7
    assert r.report()["fit_volume_rel_change"] == r.fit_volume_rel_change


def test_grid_projection_matches_occt_surface_projection(box12):
    """The grid-started projection onto the fitted faces gives the distances of OCCT's global
    surface projection (point by point, on samples moved off every fitted face)."""
    from OCP.BRep import BRep_Tool
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    from medax.cad.simplify.occ import faces_of, uv_bounds
    from medax.cad.simplify.projection import GridProjection
    from medax.cad.simplify.validate import face_samples

    _, r, _ = box12
    rng = np.random.default_rng(5)
    n = 0
    for f in faces_of(r.shape):
        surf = BRep_Tool.Surface_s(f)
        grid = GridProjection.of(surf, uv_bounds(f))
        if grid is None:
            continue
        pts = face_samples(f, 6) + rng.normal(0.0, 0.3, (36, 3))
        for p in pts:
            grid.Perform(gp_Pnt(*map(float, p)))
            slow = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), surf)
            assert abs(grid.LowerDistance() - slow.LowerDistance()) <= 1e-9 * r.diagonal
            n += 1
    assert n == 6 * 36  # all six faces are fitted B-splines


def _default_volume(shape) -> float:
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)  # no accuracy: what FreeCAD/CadQuery report
    return float(props.Mass())


@pytest.fixture(scope="module")
def box12_file(box12, tmp_path_factory):
    """The simplified box written as STEP and read back, and the closed-form volume."""
    from medax.cad.reader import read_part
    from medax.cad.simplify.step_out import write_step

    _, r, _ = box12
    path = write_step(r.shape, tmp_path_factory.mktemp("box12") / "box12.step")
    exact = _rounded_box_volume(A, B, H, R)
    return read_part(path, unify=False).solids[0], exact


def test_box12_report_gives_the_default_integrator_on_the_file(box12, box12_file):
    """The result's ``default_volume_rel_change`` is what OCCT's default integrator gives on
    the file as written and read back (the input's default measure is exact here), so the
    report tells a FreeCAD/CadQuery user the volume they will see."""
    _, r, _ = box12
    back, exact = box12_file
    on_file = _default_volume(back) / exact - 1.0
    assert abs(_default_volume(box12[0].shape) / exact - 1.0) <= 1e-9
    assert abs(r.default_volume_rel_change - on_file) <= 1e-6


@pytest.mark.xfail(
    strict=True,
    reason="issue 18, open: OCCT's default integrator runs one Gauss rule of at most 61 "
    "points across a fitted face's whole u range; the curvature jumps at the fillets' "
    "tangent lines inside the merged faces leave it -1.0e-4 off here (docs/benchmarks.md)",
)
def test_box12_written_file_default_integrator_within_1e6(box12_file):
    """The issue's acceptance measure: OCCT's default mass properties on the written file
    within 1e-6 of the input's exact volume."""
    back, exact = box12_file
    assert abs(_default_volume(back) / exact - 1.0) <= 1e-6


def test_rounded_route_not_taken_on_loose_edges():
    """Where the pieces' edges lie farther off their faces than the fit tolerance (a loose
    input), the rounded-box closed form is not taken: the fitted route merges them, and
    the solid is checked as before."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
    from OCP.TopoDS import TopoDS

    from medax.cad.simplify.occ import edges_of

    part = P.box_all_fillets(A, B, H, R)
    shape = BRepBuilderAPI_Copy(part.shape).Shape()
    for e in edges_of(shape):
        BRep_Builder().UpdateEdge(TopoDS.Edge(e), 1e-3)  # ~20x the fit tolerance, 5.4e-5
    r = simplify(shape, specs_from_blend_faces(shape, part.blends))
    assert (r.faces_before, r.faces_after) == (26, 6) and not r.blends_kept
    assert {g.surface for g in r.face_groups if g.halves} == {"fitted"}


def _corner_as_bspline(r: float = 3.0):
    """A 30 x 20 x 10 box whose three edges at the corner (30, 20, 10) are filleted with
    radius ``r``, the sphere corner replaced by its exact NURBS copy (a corner blend that is
    no sphere piece, as other CAD systems write vertex blends): the solid, the sphere
    face it replaced."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepBuilderAPI import (
        BRepBuilderAPI_MakeSolid,
        BRepBuilderAPI_NurbsConvert,
        BRepBuilderAPI_Sewing,
    )
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.GeomAbs import GeomAbs_Sphere

    from medax.cad.simplify.occ import edges_of, faces_of

    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
    mk = BRepFilletAPI_MakeFillet(box)
    for e in edges_of(box):
        ends = edge_points(e, 2)
        if np.any(np.all(np.abs(ends - [30.0, 20.0, 10.0]) < 1e-9, axis=1)):
            mk.Add(r, e)
    rounded = mk.Shape()
    sphere = next(
        f for f in faces_of(rounded) if BRepAdaptor_Surface(f).GetType() == GeomAbs_Sphere
    )
    nurbs = BRepBuilderAPI_NurbsConvert(sphere, True).Shape()
    sew = BRepBuilderAPI_Sewing(1e-6)
    for f in faces_of(rounded):
        sew.Add(nurbs if f.IsSame(sphere) else f)
    sew.Perform()
    return BRepBuilderAPI_MakeSolid(TopoDS.Shell(sew.SewedShape())).Solid(), sphere


def test_a_vertex_blend_that_is_no_sphere_is_split_by_its_bisector_sections():
    """The corner's split edges are its sections by the fillets' bisector planes (truth:
    on the sphere the NURBS copy stands for, they are the great arcs of
    :func:`corner_arcs`, from the same end points, every point at the sphere's radius from
    its centre and equidistant from the fillet's two planes), and the part loses all four
    blends with its shape (whole-solid distances both ways, volume, OCCT's validity)."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface

    from medax.cad.classify import classify_solid
    from medax.cad.reader import heal
    from medax.cad.simplify.corner import corner_arcs, corner_sections, plane_normal
    from medax.cad.simplify.medial import medial_curve
    from medax.cad.simplify.occ import diagonal
    from medax.cad.simplify.specs import specs_from_classification
    from medax.tolerances import BUILD_TOL
    from truth import assert_same_solid

    solid, sphere = _corner_as_bspline()
    cls = classify_solid(heal(solid))
    blends = specs_from_classification(cls)
    (cs,) = blends.corners
    fmap, emap = shape_map(cls.shape, TopAbs_FACE), shape_map(cls.shape, TopAbs_EDGE)
    face = lambda i: TopoDS.Face(fmap.FindKey(i + 1))  # noqa: E731
    by_face = {s.face: s for s in blends.fillets}
    pairs = [by_face[f].supporting for f in cs.fillets]
    normals = {s: plane_normal(face(s)) for s in cs.supporting}
    planes = {
        s: (n, float(n @ np.array(BRepAdaptor_Surface(face(s)).Plane().Location().Coord())))
        for s, n in normals.items()
    }
    medials = []
    for f in cs.fillets:
        sides = (
            [TopoDS.Edge(emap.FindKey(i + 1)) for i in by_face[f].side_edges(k)] for k in (0, 1)
        )
        medials.append(medial_curve(face(f), *sides).edge)
    tol = BUILD_TOL * diagonal(cls.shape)
    got = corner_sections(face(cs.face), pairs, planes, medials, tol)
    assert not isinstance(got, str), got
    edges, centre = got
    want_edges, want_centre = corner_arcs(sphere, pairs, normals)
    assert np.linalg.norm(centre - want_centre) <= 1e-6
    c, r = np.array([27.0, 17.0, 7.0]), 3.0  # the sphere's centre and radius
    for e, w, (a, b) in zip(edges, want_edges, pairs, strict=True):
        p = edge_points(e, 25)
        assert np.max(np.abs(np.linalg.norm(p - c, axis=1) - r)) <= 1e-6
        da = p @ planes[a][0] - planes[a][1]
        db = p @ planes[b][0] - planes[b][1]
        assert np.max(np.abs(da - db)) <= 1e-6
        ends = {tuple(np.round(q, 5)) for q in edge_points(e, 2)}
        assert ends == {tuple(np.round(q, 5)) for q in edge_points(w, 2)}
    r_ = simplify(cls.shape, blends)
    assert sorted(r_.blends_removed) == sorted([*cs.fillets, cs.face]) and not r_.blends_kept
    assert (r_.faces_before, r_.faces_after) == (10, 6)
    assert_same_solid(cls.shape, r_)
