"""Medial axes on fillet faces, checked by analytic truth and by OCCT's own distances."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex  # noqa: E402
from OCP.BRepExtrema import BRepExtrema_DistShapeShape  # noqa: E402
from OCP.GeomAbs import GeomAbs_Line  # noqa: E402
from OCP.gp import gp_Pnt  # noqa: E402

from medax.cad import parts  # noqa: E402
from medax.cad.classify import classify_solid  # noqa: E402
from medax.cad.face_region import fillet_axis, fillet_region  # noqa: E402
from medax.geometry.surfaces import CylinderSurface, TorusSurface  # noqa: E402

BUILDERS = dict(parts.CATALOGUE)
BUILDERS["box_random_0"] = lambda: parts.box_random(0)
BUILDERS["box_random_5"] = lambda: parts.box_random(5)


def occt_distance(point: np.ndarray, shapes) -> float:
    """Distance from ``point`` (3,) to the nearest of ``shapes`` by BRepExtrema.

    BRepExtrema works to about ``Precision::Confusion`` (1e-7) on B-spline edges; there the
    foot is polished with ``GeomAPI_ProjectPointOnCurve`` (Newton on OCCT's own curve), so
    the answer stays independent of medax and good to ~1e-12.
    """
    from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopoDS import TopoDS

    p = gp_Pnt(*map(float, point))
    v = BRepBuilderAPI_MakeVertex(p).Vertex()
    best = np.inf
    for s in shapes:
        d = BRepExtrema_DistShapeShape(v, s)
        assert d.IsDone()
        best = min(best, d.Value())
        if s.ShapeType() == TopAbs_EDGE:
            ad = BRepAdaptor_Curve(TopoDS.Edge(s))
            a, b = ad.FirstParameter(), ad.LastParameter()
            curve = BRep_Tool.Curve_s(TopoDS.Edge(s), a, b)
            proj = GeomAPI_ProjectPointOnCurve(p, curve, a, b)
            if proj.NbPoints() > 0:
                assert abs(proj.LowerDistance() - d.Value()) < 1e-6
                best = min(best, proj.LowerDistance())
    return float(best)


# slanted_boss has degree-13 rational B-spline smooth edges: geometry.bspline evaluates
# degrees above 5 by de Boor (scipy), not the power basis, which lost 6e-10 there.
_KNOWN: dict[str, pytest.MarkDecorator] = {}


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=_KNOWN[n]) if n in _KNOWN else n for n in sorted(BUILDERS)]
)
def test_axis_points_equidistant_from_smooth_edges_by_occt(name):
    built = BUILDERS[name]()
    c = classify_solid(built.shape)
    assert c.fillets
    for rec in c.fillets:
        axis = fillet_axis(c, rec)
        r = rec.radius if rec.radius is not None else min(built.radii, default=1.0)
        e0 = [c.edge(j) for j in rec.smooth_edges[0]]
        e1 = [c.edge(j) for j in rec.smooth_edges[1]]
        d0 = np.array([occt_distance(x, e0) for x in axis.space_points])
        d1 = np.array([occt_distance(x, e1) for x in axis.space_points])
        assert np.max(np.abs(d0 - d1)) < 1e-9 * r, (name, rec.face)
        # the ends lie on the cross edges (within the edges' own pcurve-vs-3D tolerance)
        crosses = [c.edge(j) for j in rec.cross_edges]
        tol = max([1e-9 * r] + [BRep_Tool.Tolerance_s(e) for e in crosses])
        assert occt_distance(axis.space_points[0], crosses) < tol
        assert occt_distance(axis.space_points[-1], crosses) < tol
        # interior points lie on the face itself (OCCT distance to the trimmed face)
        f = c.face(rec.face)
        assert max(occt_distance(x, [f]) for x in axis.space_points[1:-1:2]) < 1e-9 * r


@pytest.mark.parametrize("builder", ["pocket", "box"])
def test_axis_of_cylinder_fillet_between_planes_is_mid_angle_ruling(builder):
    if builder == "pocket":
        built = parts.pocket()
    else:
        box = parts.BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
        built = parts.fillet(box, [parts._edges(box)[j] for j in (0, 5)], 3.0, "box2")
    c = classify_solid(built.shape)
    for rec in c.fillets:
        r = rec.radius
        cyl = BRepAdaptor_Surface(c.face(rec.face)).Cylinder()
        loc, z = cyl.Location(), cyl.Axis().Direction()
        o = np.array([loc.X(), loc.Y(), loc.Z()])
        zd = np.array([z.X(), z.Y(), z.Z()])
        # the two smooth edges are lines on the cylinder: their radial directions
        rad = []
        for side in rec.smooth_edges:
            ad = BRepAdaptor_Curve(c.edge(side[0]))
            assert ad.GetType() == GeomAbs_Line
            p = ad.Value(ad.FirstParameter())
            w = np.array([p.X(), p.Y(), p.Z()]) - o
            w -= zd * (w @ zd)
            rad.append(w / np.linalg.norm(w))
        bis = rad[0] + rad[1]
        bis /= np.linalg.norm(bis)
        ruling = o + r * bis  # a point of the mid-angle ruling line, direction zd
        axis = fillet_axis(c, rec)
        w = axis.space_points - ruling
        off = w - np.outer(w @ zd, zd)
        assert np.max(np.linalg.norm(off, axis=1)) < 1e-9 * r
        # the fitted spline, sampled densely, stays within the tracer's curve tolerance
        dense = axis.region.embedding.evaluate(axis.spline.sample(200))
        w = dense - ruling
        off = w - np.outer(w @ zd, zd)
        assert np.max(np.linalg.norm(off, axis=1)) < 1e-6 * axis.diagonal


def test_torus_fillet_axis_is_the_mid_circle():
    """The shaft's shoulder fillets: the axis is the torus circle at the mid minor angle."""
    c = classify_solid(parts.stepped_shaft().shape)
    for rec in c.fillets:
        region = fillet_region(c, rec)
        assert isinstance(region.embedding, TorusSurface)
        axis = fillet_axis(c, rec)
        v = axis.points[:, 1]
        # the smooth sides are v = const lines of the parameter plane
        v0 = region.sides[0].evaluate(np.array([0.5]))[0, 1]
        v2 = region.sides[2].evaluate(np.array([0.5]))[0, 1]
        assert np.max(np.abs(v - 0.5 * (v0 + v2))) * rec.radius < 1e-9 * rec.radius
        # it goes all the way round: from the seam to the seam
        u = axis.points[:, 0]
        assert abs(abs(u[-1] - u[0]) - 2 * np.pi) < 1e-9


def test_cylinder_region_uses_numpy_embedding():
    c = classify_solid(parts.pocket().shape)
    region = fillet_region(c, c.fillets[0])
    assert isinstance(region.embedding, CylinderSurface)
    assert region.space_sides is not None
    # space sides are the exact edges: the embedded pcurves lie on them (as point sets;
    # the parametrisations differ)
    for k in range(4):
        b = region.embedding.evaluate(region.sides[k].evaluate(np.linspace(0, 1, 11)))
        assert np.max(region.space_sides[k].closest(b).distance) < 1e-9
