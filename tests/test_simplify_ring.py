"""The ring route (issue 5): the catalogue's slanted boss, a plate with a slanted cylinder
whose root fillet is a degree-13 B-spline rolling-ball blend, loses the blend (11 -> 10
faces): its plate half merged into the plate and its cylinder half into the cylinder, each
on a periodic B-spline fitted in ring coordinates.

Truth from OCCT, not from the simplifier's own validation: ``BRepCheck_Analyzer``, the
shell and free-edge counts, ``BRepGProp`` volumes of both solids, and
``BRepExtrema_DistShapeShape`` distances from random points on the old faces to the new
ones and back. The geometry helpers are checked against closed forms.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepGProp import BRepGProp
from OCP.BRepTools import BRepTools
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.GProp import GProp_GProps
from OCP.IntTools import IntTools_FClass2d
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_IN, TopAbs_SHELL
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from medax.cad import parts
from medax.cad.classify import classify_solid
from medax.cad.simplify import simplify, specs_from_classification
from medax.cad.simplify.occ import compound, shape_map
from medax.cad.simplify.pipeline import ACCEPT_SHARE, FIT_SHARE
from medax.geometry.periodic_fit import PERIOD, PeriodicFit, fit_radial_height
from medax.geometry.ring_heights import RingFrame, ray_points
from medax.geometry.surfaces import NurbsSurface
from medax.geometry.tensor_fit import knot_vector
from truth import assert_same_solid

pytestmark = pytest.mark.slow  # OCCT-heavy: module fixtures build and simplify parts


@pytest.fixture(scope="module")
def slanted():
    cls = classify_solid(parts.slanted_boss().shape)
    specs = specs_from_classification(cls)
    return cls, specs, simplify(cls.shape, specs)


def _count(shape, kind) -> int:
    exp, n = TopExp_Explorer(shape, kind), 0
    while exp.More():
        n += 1
        exp.Next()
    return n


def _volume(shape) -> float:
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, 1e-9)
    return float(props.Mass())


def _face_points(face, n: int, rng) -> np.ndarray:
    """``n`` random points inside ``face`` (OCCT's surface and face classifier)."""
    u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
    surf = BRepAdaptor_Surface(face)
    cls = IntTools_FClass2d(face, 1e-9)
    out: list[tuple[float, float, float]] = []
    while len(out) < n:
        u, v = float(rng.uniform(u0, u1)), float(rng.uniform(v0, v1))
        if cls.Perform(gp_Pnt2d(u, v)) == TopAbs_IN:
            p = surf.Value(u, v)
            out.append((p.X(), p.Y(), p.Z()))
    return np.array(out)


def _distance(points: np.ndarray, shape) -> float:
    worst = 0.0
    for p in points:
        d = BRepExtrema_DistShapeShape(
            BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, p))).Vertex(), shape
        )
        assert d.IsDone()
        worst = max(worst, float(d.Value()))
    return worst


def _faces(shape) -> list:
    fmap = shape_map(shape, TopAbs_FACE)
    return [TopoDS.Face(fmap.FindKey(i + 1)) for i in range(fmap.Size())]


def test_slanted_boss_loses_its_blend(slanted):
    cls, specs, r = slanted
    (spec,) = specs.fillets
    assert (r.faces_before, r.faces_after) == (11, 10)
    assert r.blends_removed == [spec.face] and not r.blends_kept and r.valid
    fitted = [g for g in r.face_groups if g.surface == "fitted"]
    assert sorted(w for g in fitted for w in g.whole) == sorted(spec.supporting)
    assert all(g.halves == (spec.face,) for g in fitted)
    # the report's own numbers within the targets
    assert abs(r.volume_rel_change) <= 1e-6
    assert r.max_deviation <= 1e-5 * r.diagonal
    assert 0 < r.fit_error <= 1e-6 * r.diagonal


def test_slanted_boss_result_by_occt(slanted):
    cls, specs, r = slanted
    assert BRepCheck_Analyzer(r.shape).IsValid()
    assert _count(r.shape, TopAbs_SHELL) == 1
    free = ShapeAnalysis_FreeBounds(r.shape)
    assert _count(free.GetClosedWires(), TopAbs_EDGE) == 0
    assert _count(free.GetOpenWires(), TopAbs_EDGE) == 0
    assert _count(r.shape, TopAbs_FACE) == 10
    v0, v1 = _volume(cls.shape), _volume(r.shape)
    assert abs(v1 - v0) <= 1e-6 * v0
    # distances both ways: the old blend, plate and cylinder to the new faces, the new
    # merged faces to the old solid
    (spec,) = specs.fillets
    rng = np.random.default_rng(5)
    old = _faces(cls.shape)
    new = _faces(r.shape)
    merged = [f for f in new if BRepAdaptor_Surface(f).GetType().name == "GeomAbs_BSplineSurface"]
    assert len(merged) == 2
    old_pts = np.vstack([_face_points(old[k], 40, rng) for k in (spec.face, *spec.supporting)])
    new_pts = np.vstack([_face_points(f, 40, rng) for f in merged])
    tol = 1e-5 * r.diagonal
    assert _distance(old_pts, compound(merged)) <= tol
    assert _distance(new_pts, cls.shape) <= tol


def _area(shape) -> float:
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, props, 1e-10)
    return float(props.Mass())


def test_slanted_boss_area_and_pcurves_by_occt(slanted):
    """The boundary's area is kept (a wrong trimming curve on a merged face shows here
    even where the sampled distances do not: a bad pcurve once added a 0.16 mm2 sliver,
    1.8e-5 of the area, with every sampled distance within 1e-5 x diagonal), and on each
    new face every edge's pcurve follows its 3-D curve within the edge's tolerance at 2001
    samples."""
    cls, _, r = slanted
    a0 = _area(cls.shape)
    assert abs(_area(r.shape) - a0) <= 1e-7 * a0
    for f in _faces(r.shape):
        if BRepAdaptor_Surface(f).GetType().name != "GeomAbs_BSplineSurface":
            continue
        surf = BRep_Tool.Surface_s(f)
        exp = TopExp_Explorer(f, TopAbs_EDGE)
        while exp.More():
            e = TopoDS.Edge(exp.Current())
            exp.Next()
            c2 = BRep_Tool.CurveOnSurface_s(e, f, 0.0, 0.0)
            c3 = BRep_Tool.Curve_s(e, 0.0, 0.0)
            a, b = BRep_Tool.Range_s(e)
            worst = max(
                surf.Value(c2.Value(t).X(), c2.Value(t).Y()).Distance(c3.Value(t))
                for t in np.linspace(a, b, 2001).tolist()
            )
            assert worst <= BRep_Tool.Tolerance_s(e)


def test_plate_stays_exactly_plane_off_the_blend(slanted):
    """Points of the new plate face farther than 0.1 from the old blend lie exactly on the
    old plate's plane (the height off the plane is held at zero there, not fitted)."""
    cls, specs, r = slanted
    (spec,) = specs.fillets
    old = _faces(cls.shape)
    plate = next(
        old[k]
        for k in spec.supporting
        if BRepAdaptor_Surface(old[k]).GetType().name == "GeomAbs_Plane"
    )
    pl = BRepAdaptor_Surface(plate).Plane()
    o = np.array([pl.Location().X(), pl.Location().Y(), pl.Location().Z()])
    d = pl.Axis().Direction()
    n = np.array([d.X(), d.Y(), d.Z()])
    new = next(
        f
        for f in _faces(r.shape)
        if BRepAdaptor_Surface(f).GetType().name == "GeomAbs_BSplineSurface"
        and _distance(_face_points(f, 1, np.random.default_rng(0)), plate) < 1.0
        and abs((_face_points(f, 1, np.random.default_rng(0))[0] - o) @ n) < 1.0
    )
    pts = _face_points(new, 80, np.random.default_rng(7))
    blend = old[spec.face]
    far = [p for p in pts if _distance(p[None, :], blend) > 0.1]
    assert len(far) > 40
    assert max(abs((p - o) @ n) for p in far) <= 1e-12


def test_merged_surfaces_are_periodic_round_the_boss(slanted):
    _, _, r = slanted
    for f in _faces(r.shape):
        ad = BRepAdaptor_Surface(f)
        if ad.GetType().name == "GeomAbs_BSplineSurface":
            s = ad.BSpline()
            assert s.IsUPeriodic() and not s.IsVPeriodic()
            assert s.UDegree() == s.VDegree() == 3


def test_periodic_surface_evaluates_as_the_fit():
    """OCCT's periodic B-spline built from a fit's coefficients is the fit (pole order)."""
    from medax.cad.simplify.ring import periodic_surface

    rng = np.random.default_rng(0)
    ts = knot_vector(0.0, 2.0, [1.0], [True, True], 0.5)
    fit = PeriodicFit(12, ts, rng.normal(size=(12, ts.size - 4, 3)), 0.0)
    surf = periodic_surface(fit)
    th, s = rng.uniform(-1.0, 2 * PERIOD, 60), rng.uniform(0.0, 2.0, 60)
    p = fit.at(th, s)
    q = np.array(
        [
            [c.X(), c.Y(), c.Z()]
            for c in (surf.Value(float(a), float(b)) for a, b in zip(th, s, strict=True))
        ]
    )
    assert np.abs(p - q).max() <= 1e-12


def _frame(kind: str) -> RingFrame:
    """A frame round the z axis; the contact curve an ellipse-like star (plane) or a tilted
    circle's height (cylinder)."""
    th = np.linspace(0, PERIOD, 400, endpoint=False)
    if kind == "plane":
        rho = 3.0 + 0.4 * np.cos(th) + 0.1 * np.sin(2 * th)
        pts = np.column_stack([rho * np.cos(th), rho * np.sin(th), np.zeros_like(th)])
        r = RingFrame.around(
            "plane", np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), pts, 1.0
        )
    else:
        pts = np.column_stack([2 * np.cos(th), 2 * np.sin(th), 1.0 + 0.3 * np.cos(th)])
        r = RingFrame.around(
            "cylinder", np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), pts, -1.0, 2.0
        )
    assert isinstance(r, RingFrame)
    return r


@pytest.mark.parametrize("kind", ["plane", "cylinder"])
def test_ring_coordinates_round_trip(kind):
    frame = _frame(kind)
    rng = np.random.default_rng(2)
    th, sg, h = rng.uniform(0, PERIOD, 200), rng.uniform(-1, 1, 200), rng.uniform(-0.5, 0.5, 200)
    x = frame.point(th, sg, h)
    t2, s2, h2 = frame.coords(x)
    assert np.abs(np.mod(t2 - th + np.pi, PERIOD) - np.pi).max() <= 1e-12
    assert np.abs(s2 - sg).max() <= 1e-9 and np.abs(h2 - h).max() <= 1e-12
    # sigma = 0, h = 0 is the contact curve itself (the frame's samples)
    if kind == "cylinder":
        t0 = np.linspace(0, PERIOD, 7)
        z = frame.point(t0, np.zeros(7))[:, 2]
        assert np.abs(z - (1.0 + 0.3 * np.cos(t0))).max() <= 1e-7


def test_star_shape_is_required():
    th = np.linspace(0, PERIOD, 200, endpoint=False)
    # a curve that does not go round the origin
    pts = np.column_stack([5 + np.cos(th), np.sin(th), np.zeros_like(th)])
    r = RingFrame.around(
        "plane", np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), pts, 1.0
    )
    assert isinstance(r, str)


@pytest.mark.parametrize("kind", ["plane", "cylinder"])
def test_ray_points_on_a_tilted_plane(kind):
    """Rays meet a tilted plane given as a bilinear NURBS: the points found are on it (closed
    form) and on their rays."""
    frame = _frame(kind)
    # the plane z = 0.2 x + 0.1 y + c0 (plane frame: h along z) or x = 2.6 + 0.1 z (cylinder
    # frame: h radial, rays at theta near 0)
    if kind == "plane":
        c0 = 0.3
        xs = np.array([-6.0, 6.0])
        grid = np.array([[[x, y, 0.2 * x + 0.1 * y + c0] for y in xs] for x in xs])
    else:
        grid = np.array([[[2.6 + 0.1 * z, y, z] for y in (-3.0, 3.0)] for z in (-2.0, 4.0)])
    kn = np.array([0.0, 0.0, 1.0, 1.0])
    surf = NurbsSurface(grid, 1, 1, kn, kn)
    rng = np.random.default_rng(4)
    if kind == "plane":
        th, sg = rng.uniform(0, PERIOD, 300), rng.uniform(-1, 1, 300)
    else:
        th, sg = rng.uniform(-0.3, 0.3, 300), rng.uniform(-1, 1, 300)
    x, ok = ray_points(surf, frame, th, sg, (0.0, 1.0, 0.0, 1.0), 1e-10)
    assert ok.all()
    if kind == "plane":
        assert np.abs(x[:, 2] - (0.2 * x[:, 0] + 0.1 * x[:, 1] + c0)).max() <= 1e-9
    else:
        assert np.abs(x[:, 0] - (2.6 + 0.1 * x[:, 2])).max() <= 1e-9
    t2, s2, _ = frame.coords(x)
    assert np.abs(np.mod(t2 - th + np.pi, PERIOD) - np.pi).max() <= 1e-9
    assert np.abs(s2 - sg).max() <= 1e-9


def test_vector_fit_with_a_linear_interval():
    """Points of a flared cylinder, linear in s above the break: three components share the
    knots, spans doubling away from the break cover the linear interval, the measured
    error is honest."""

    def pts(th, s):
        r = 2.0 + 0.2 * np.minimum(s, 0.0) ** 2 * (1 + 0.3 * np.cos(th))
        p = np.stack([r * np.cos(th), r * np.sin(th), s], axis=-1)
        ok = np.ones(th.shape, bool)
        return p, ok, ok

    fit = fit_radial_height((-1.0, 3.0), [0.0], pts, 1e-6, 0.5, 2.0, levels=6, s_fine=[True, False])
    assert fit is not None and fit.error <= 1e-6 and fit.coef.shape[2] == 3
    # over [0, 3]: spans doubling from the break's fine spacing, a few, not 3 / spacing
    flat = np.diff(np.unique(fit.ts[fit.ts >= 0.0]))
    assert len(flat) <= 5 and np.allclose(flat[1:-1] / flat[:-2], 2.0)
    rng = np.random.default_rng(1)
    th, s = rng.uniform(0, PERIOD, 5000), rng.uniform(-1, 3, 5000)
    worst = np.linalg.norm(fit.at(th, s) - pts(th, s)[0], axis=1).max()
    assert worst <= 1.5e-6


def test_zero_last_component_is_exactly_zero_after_the_break():
    """A component held at zero on the last interval is zero there to rounding, and the fit
    of the others and of it before the break is as accurate as without the constraint."""

    def pts(th, s):
        hgt = 0.2 * np.minimum(s, 0.0) ** 2 * (1 + 0.3 * np.cos(th))
        p = np.stack([np.cos(th) * (3 + s), np.sin(th) * (3 + s), hgt], axis=-1)
        ok = np.ones(th.shape, bool)
        return p, ok, ok

    fit = fit_radial_height(
        (-1.0, 3.0), [0.0], pts, 1e-6, 0.5, 3.0, levels=6, s_fine=[True, False], zero_last=2
    )
    assert fit is not None and fit.error <= 1e-6
    th, s = np.linspace(0, PERIOD, 50), np.linspace(0.0, 3.0, 40)
    assert np.abs(fit(th, s)[..., 2]).max() <= 1e-15


def _flat_top_boss():
    """The slanted cylinder cut flat at z = 15, its top edge filleted (a B-spline blend
    between the horizontal top and the slanted cylinder; the root not filleted)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Fuse
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir

    from medax.cad.parts import _select, _solid, fillet

    plate = BRepPrimAPI_MakeBox(60.0, 60.0, 5.0).Shape()
    axis = gp_Ax2(gp_Pnt(30.0, 30.0, -5.0), gp_Dir(0.3, 0.0, 1.0))
    cyl = BRepPrimAPI_MakeCylinder(axis, 8.0, 30.0).Shape()
    keep = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, -10), 80.0, 80.0, 25.0).Shape()
    body = BRepAlgoAPI_Fuse(plate, BRepAlgoAPI_Common(cyl, keep).Shape()).Shape()
    return fillet(_solid(body), _select(body, lambda m: abs(m[2] - 15.0) < 1e-6), 1.5, "top")


def test_flat_top_boss_top_refused_by_ring_taken_by_stalled_height_field():
    """Over the cylinder the blend lies above the support (sigma runs down the axis): the
    ring fit is within its tolerance; the top plane lies inside the contact curve (the
    polar frame's pole would be on it), so the ring route refuses it. The planar height
    field stalls above its fit tolerance (the curvature jump runs along a circle) but
    within the accepted share, so the fillet goes, and the solid is the same to the
    issue's tolerances (whole solids, OCCT's checks)."""
    from medax.cad.simplify.groups import build_groups
    from medax.cad.simplify.medial import medial_curve
    from medax.cad.simplify.occ import diagonal
    from medax.cad.simplify.ring import ring_surface
    from medax.cad.simplify.split import split_along

    cls = classify_solid(_flat_top_boss().shape)
    specs = specs_from_classification(cls)
    (spec,) = specs.fillets
    faces = _faces(cls.shape)
    emap = shape_map(cls.shape, TopAbs_EDGE)
    m = medial_curve(
        faces[spec.face], *[TopoDS.Edge(emap.FindKey(i + 1)) for i in spec.smooth_edges]
    )
    assert not isinstance(m, str)
    split = split_along(cls.shape, [m.edge])
    diag = diagonal(cls.shape)
    results = {}
    for g in build_groups(split, {spec.face: spec.supporting}, {}):
        if g.support is not None:
            members = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
            results[g.support] = ring_surface(faces[g.support], members, 1e-6 * diag, 1e-7 * diag)
    kinds = {k: BRepAdaptor_Surface(faces[k]).GetType().name for k in results}
    (cyl,) = [k for k, v in kinds.items() if v == "GeomAbs_Cylinder"]
    (top,) = [k for k, v in kinds.items() if v == "GeomAbs_Plane"]
    assert not isinstance(results[cyl], str) and results[cyl].error <= 1e-6 * diag
    assert isinstance(results[top], str) and "inside the contact curve" in results[top]
    r = simplify(cls.shape, specs)
    assert (r.faces_before, r.faces_after) == (11, 10) and not r.blends_kept
    assert BRepCheck_Analyzer(r.shape).IsValid()
    assert FIT_SHARE * 1e-5 * r.diagonal < r.fit_error <= ACCEPT_SHARE * 1e-5 * r.diagonal
    assert_same_solid(cls.shape, r, 9, 16)


@pytest.fixture(scope="module")
def hole():
    cls = classify_solid(parts.slanted_hole().shape)
    specs = specs_from_classification(cls)
    return cls, specs, simplify(cls.shape, specs)


def test_slanted_hole_loses_both_rim_blends(hole):
    """Both rims of a slanted hole filleted (two B-spline blends on one cylinder): the
    cylinder takes both its halves on one ring surface with two C1 knot lines, each plate
    its own half (9 -> 7 faces); OCCT's checks, volumes and distances both ways."""
    cls, specs, r = hole
    assert len(specs.fillets) == 2
    assert (r.faces_before, r.faces_after) == (9, 7) and r.valid and not r.blends_kept
    (cylinder,) = {
        s
        for spec in specs.fillets
        for s in spec.supporting
        if sum(s in other.supporting for other in specs.fillets) == 2
    }
    group = next(g for g in r.face_groups if cylinder in g.whole)
    assert sorted(group.halves) == sorted(spec.face for spec in specs.fillets)
    assert BRepCheck_Analyzer(r.shape).IsValid()
    assert _count(r.shape, TopAbs_SHELL) == 1
    v0, v1 = _volume(cls.shape), _volume(r.shape)
    assert abs(v1 - v0) <= 1e-6 * v0
    rng = np.random.default_rng(11)
    old = _faces(cls.shape)
    old_pts = np.vstack(
        [_face_points(old[k], 30, rng) for k in (cylinder, *(s.face for s in specs.fillets))]
    )
    new = _faces(r.shape)
    ring = [f for f in new if BRepAdaptor_Surface(f).GetType().name == "GeomAbs_BSplineSurface"]
    new_pts = np.vstack([_face_points(f, 30, rng) for f in ring])
    tol = 1e-5 * r.diagonal
    assert _distance(old_pts, r.shape) <= tol
    assert _distance(new_pts, cls.shape) <= tol
