"""The medial curve of a B-spline blend whose mid iso-line is not equidistant, traced.

A rolling-ball blend between a plane and a slanted cylinder has its smooth edges on iso-lines
``c = c1``, ``c = c2`` of its surface (``c`` the cross parameter), but the iso-line at the mid
parameter is not equidistant from them (1.4e-3 off on the catalogue's slanted boss). Here the
medial curve is traced per cross-section: on every cross iso-line ``a = const`` (``a`` the
parameter along the blend) the point ``S(c*(a), a)`` where the distances to the two smooth
edges (their own 3-D curves) are equal, found by Newton on ``g(c) = d1 - d2`` from the mid
parameter (``g'(c) = ((S - F1) / d1 - (S - F2) / d2) . dS/dc``, ``F`` the feet on the edges),
all sections at once on the numpy copies of the blend and the edges
(:func:`~medax.cad.face_region.bspline_embedding`, :func:`~medax.cad.face_region.curve_copy`,
global :meth:`~medax.geometry.curve.Curve.closest`): two or three steps.
The traced points are interpolated by a quintic spline in space per knot span of the surface
along ``a`` (C0 joins at the surface's own knots, where ``c*(a)`` may lose smoothness), and
the cross parameters by the same spline in the plane (the edge's pcurve on the blend).

Nothing is assumed: the equidistance is measured between the nodes with
``BRepExtrema_DistShapeShape`` (polished by ``GeomAPI_ProjectPointOnCurve``, which is good to
~1e-12 where BRepExtrema stops near 1e-7 on B-spline edges), and so is the distance of the
space curve from the surface (against ``S`` at the pcurve); the nodes are doubled until both
are within the tolerance.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
from OCP.gp import gp_Pnt
from scipy.interpolate import BSpline, make_interp_spline

from medax.cad.face_region import bspline_embedding, curve_copy
from medax.cad.simplify.occ import Array, edge_curve, pnt, xyz
from medax.geometry.curve import Curve
from medax.geometry.surfaces import NurbsSurface

#: Interpolation nodes per knot span of the surface along the blend, first try; doubled up
#: to MAX_NODES while the measured error is above the tolerance.
NODES, MAX_NODES = 24, 384
#: Poles of the traced curve beyond which the nodes are no longer doubled once the error is
#: within the construction's tolerance (and the one an iso-line is accepted with): OCCT's
#: splitter, which takes the curve as a tool, slows down steeply with its poles (a 62 mm
#: medial curve over 15 knot spans of its blend: 721 poles 1.7 s, 1441 poles 10 s, 5761
#: poles past 5 minutes).
MAX_POLES = 512
#: Degree of the interpolating splines (quintic: the error falls as h^6; cubic splines
#: needed 384 nodes per span for 2e-9 on the slanted boss, whose blend is of degree 13).
DEGREE = 5
#: Newton steps per cross-section at most.
NEWTON_STEPS = 30
#: Equidistance samples per knot span besides the midpoints between the nodes (at fractions
#: of the span unrelated to the nodes).
CHECK_SAMPLES = 16
CHECK_AT = (np.arange(CHECK_SAMPLES) + 0.4269) / CHECK_SAMPLES


def _foot(curve: tuple[Any, float, float], p: Array) -> tuple[Array, float]:
    """Foot (3,) of ``p`` on an edge curve and the distance."""
    c, a, b = curve
    proj = GeomAPI_ProjectPointOnCurve(pnt(p), c, a, b)
    if proj.NbPoints() == 0:  # the nearest point is an end
        ends = [xyz(c.Value(a)), xyz(c.Value(b))]
        d = [float(np.linalg.norm(p - e)) for e in ends]
        k = int(np.argmin(d))
        return ends[k], d[k]
    return xyz(proj.NearestPoint()), float(proj.LowerDistance())


def trace_cross_params(
    surf: NurbsSurface,
    k: int,
    along: Array,
    c1: float,
    c2: float,
    edges: Sequence[Curve],
    tol: float,
) -> Array | None:
    """Cross parameters ``c*`` (n,) of the equidistant points on the cross iso-lines
    ``along`` (``k``: index of the cross parameter in (u, v)) of the numpy copy ``surf`` of
    the blend, between ``c1`` and ``c2``, from the numpy copies ``edges`` of the smooth
    edges (global closest points): Newton on all sections at once from the mid parameter
    until ``|d1 - d2| < tol``. None when a section does not converge."""
    c = np.full(len(along), 0.5 * (c1 + c2))
    lo, hi = min(c1, c2), max(c1, c2)
    live = np.arange(len(along))
    for _ in range(NEWTON_STEPS):
        uv = np.column_stack((c[live], along[live]) if k == 0 else (along[live], c[live]))
        p, du, dv = surf.jet(uv)
        dp = du if k == 0 else dv
        f1, f2 = edges[0].closest(p), edges[1].closest(p)
        g = f1.distance - f2.distance
        done = np.abs(g) < tol
        u1 = (p - f1.foot) / np.maximum(f1.distance, 1e-300)[:, None]
        u2 = (p - f2.foot) / np.maximum(f2.distance, 1e-300)[:, None]
        dg = np.einsum("ij,ij->i", u1 - u2, dp)
        if np.any((dg == 0.0) & ~done):
            return None
        step = np.where(done, 0.0, g / np.where(dg == 0.0, 1.0, dg))
        c[live] = np.clip(c[live] - step, lo, hi)
        live = live[~done]
        if live.size == 0:
            return c
    return None


def occt_distance(p: Array, edge: Any, curve: tuple[Any, float, float]) -> float:
    """Distance from ``p`` to ``edge`` by ``BRepExtrema_DistShapeShape``, polished by
    ``GeomAPI_ProjectPointOnCurve`` on the edge's own curve (the smaller of the two)."""
    vtx = BRepBuilderAPI_MakeVertex(pnt(p)).Vertex()
    ext = BRepExtrema_DistShapeShape(vtx, edge)
    d = float(ext.Value()) if ext.IsDone() else np.inf
    return min(d, _foot(curve, p)[1])


def _spans(surf: Any, k: int, lo: float, hi: float) -> list[tuple[float, float]]:
    """Knot spans of the surface along the blend (direction ``1 - k``) clipped to
    ``[lo, hi]``."""
    if k == 0:
        knots = [surf.VKnot(i) for i in range(1, surf.NbVKnots() + 1)]
    else:
        knots = [surf.UKnot(i) for i in range(1, surf.NbUKnots() + 1)]
    inner = [t for t in knots if lo + 1e-9 * (hi - lo) < t < hi - 1e-9 * (hi - lo)]
    cuts = [lo, *inner, hi]
    return list(zip(cuts[:-1], cuts[1:], strict=True))


def _joined(splines: list[BSpline]) -> tuple[Array, Array]:
    """Knots and coefficients of clamped splines of degree ``DEGREE`` on consecutive
    intervals joined C0 (the shared end coefficient once, the joint knot ``DEGREE`` times)."""
    t = splines[0].t[:-1]
    c = splines[0].c
    for s in splines[1:]:
        t = np.concatenate([t, s.t[DEGREE + 1 : -1]])
        c = np.concatenate([c, s.c[1:]])
    return np.concatenate([t, splines[-1].t[-1:]]), c


def geom_bspline(t: Array, c: Array, degree: int = DEGREE) -> Any:
    """A ``Geom_BSplineCurve`` or ``Geom2d_BSplineCurve`` (by the poles' dimension) of
    knots ``t`` (with repeats), poles ``c`` (n, 3) or (n, 2) and ``degree``."""
    from OCP.collections import Array1_double, Array1_gp_Pnt, Array1_gp_Pnt2d, Array1_int
    from OCP.Geom import Geom_BSplineCurve
    from OCP.Geom2d import Geom2d_BSplineCurve
    from OCP.gp import gp_Pnt2d

    u, m = np.unique(t, return_counts=True)
    ak, am = Array1_double(1, len(u)), Array1_int(1, len(u))
    for i, (kv, mult) in enumerate(zip(u, m, strict=True)):
        ak.SetValue(i + 1, float(kv))
        am.SetValue(i + 1, int(mult))
    if c.shape[1] == 3:
        poles = Array1_gp_Pnt(1, len(c))
        for i, p in enumerate(c):
            poles.SetValue(i + 1, gp_Pnt(*map(float, p)))
        return Geom_BSplineCurve(poles, ak, am, degree)
    poles2 = Array1_gp_Pnt2d(1, len(c))
    for i, p in enumerate(c):
        poles2.SetValue(i + 1, gp_Pnt2d(float(p[0]), float(p[1])))
    return Geom2d_BSplineCurve(poles2, ak, am, degree)


def traced_medial_edge(
    face: Any,
    edges: tuple[Any, Any],
    k: int,
    cross: tuple[float, float],
    along: tuple[float, float],
    tol: float,
    accept: float = 0.0,
    early: float = 0.0,
) -> tuple[Any, float] | str:
    """The traced medial edge of the B-spline blend ``face`` between smooth ``edges`` (on
    the iso-lines ``cross`` of parameter ``k``), over ``along`` = (lo, hi) of the other
    parameter: (edge with its 3-D curve and its pcurve on the face, measured error: the
    larger of the equidistance and the distance from the surface, length unit), or the
    reason when the error stays above ``tol``, or above ``accept`` (length unit, when larger)
    with the most nodes. The nodes are doubled until the error is within ``tol``, or within
    ``early`` (and ``accept``: the construction's tolerance, so the split edge lies on the
    blend to it) when doubling would take the curve past ``MAX_POLES``."""
    surf = BRep_Tool.Surface_s(face)
    curves = [edge_curve(e) for e in edges]
    if not isinstance(surf, Geom_BSplineSurface) or not all(
        isinstance(cv, Geom_BSplineCurve) for cv, _, _ in curves
    ):
        return "traced medial curve: the blend or its smooth edges are not B-splines"
    numpy_surf = bspline_embedding(surf)
    numpy_edges = [curve_copy(cv) for cv, _, _ in curves]
    lo, hi = along
    spans = _spans(surf, k, lo, hi)
    closed = False
    n, err = NODES, np.inf
    while n <= MAX_NODES:
        s3, s2 = [], []
        for a0, a1 in spans:
            a = np.linspace(a0, a1, n + 1)
            c = trace_cross_params(numpy_surf, k, a, cross[0], cross[1], numpy_edges, 1e-2 * tol)
            if c is None:
                return "traced medial curve: Newton did not converge on a cross-section"
            uv = np.column_stack([c, a] if k == 0 else [a, c])
            pts = numpy_surf.evaluate(uv)
            s3.append(make_interp_spline(a, pts, k=DEGREE))
            s2.append(make_interp_spline(a, uv, k=DEGREE))
        t3, c3 = _joined(s3)
        t2, c2 = _joined(s2)
        closed = float(np.linalg.norm(c3[0] - c3[-1])) <= tol
        if closed:  # one point, so that the edge gets one vertex
            c3[-1] = c3[0]
        space, plane = BSpline(t3, c3, DEGREE), BSpline(t2, c2, DEGREE)
        err = _measure(surf, k, edges, curves, space, plane, spans, n)
        if err <= tol or (err <= min(accept, early) and len(spans) * 2 * n > MAX_POLES):
            break
        n *= 2
    if err > max(tol, accept):
        return f"traced medial curve error {err:.2e} above {tol:.2e} with {n // 2} nodes per span"
    curve3, curve2 = geom_bspline(t3, c3), geom_bspline(t2, c2)
    mk = BRepBuilderAPI_MakeEdge(curve3, lo, hi)
    if not mk.IsDone():
        return "could not build the traced medial edge"
    edge = mk.Edge()
    from OCP.BRep import BRep_Builder

    BRep_Builder().UpdateEdge(edge, curve2, face, max(err, 1e-7))
    return edge, float(err)


def _measure(
    surf: Any,
    k: int,
    edges: tuple[Any, Any],
    curves: list[Any],
    s3: BSpline,
    s2: BSpline,
    spans: list[tuple[float, float]],
    n: int,
) -> float:
    """Largest equidistance error (OCCT distances) and distance of the space curve from
    the surface at the midpoints between the ``n + 1`` nodes of every span and at
    ``CHECK_SAMPLES`` more."""
    err = 0.0
    for a0, a1 in spans:
        # between the nodes, where the interpolation is worst (the nodes are exact by
        # construction), and at samples independent of them
        a = np.linspace(a0, a1, n + 1)
        a = np.concatenate([0.5 * (a[1:] + a[:-1]), a0 + (a1 - a0) * CHECK_AT])
        p3 = s3(a)
        uv = s2(a)
        for p, q in zip(p3, uv, strict=True):
            on = xyz(surf.Value(float(q[0]), float(q[1])))
            d1 = occt_distance(p, edges[0], curves[0])
            d2 = occt_distance(p, edges[1], curves[1])
            err = max(err, abs(d1 - d2), float(np.linalg.norm(p - on)))
    return err
