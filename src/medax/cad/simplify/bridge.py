"""The split curve of a fillet that rides on another fillet (a fillet on a fillet).

When a fillet ``T`` has another fillet ``V`` as a supporting face (the top edge loop of a box
whose vertical edges were rounded first: ``T`` is a torus around ``V``'s cylinder) and both
are simplified, ``V``'s halves go to ``V``'s two supporting faces ``a`` and ``b``, so ``T``'s
half on ``V`` must be shared between them too. It is split by the *bridge*: the
continuation of ``V``'s medial curve across ``T``, from the point where ``V``'s medial curve
meets ``T``'s smooth edge on ``V`` to ``T``'s own medial curve. When ``a`` and ``b`` are
planes and ``T`` is a torus coaxial with ``V`` (or, in general, when ``T``'s cross iso-line
through that point lies in the bisector of ``a`` and ``b``: also for coaxial cylinders,
cones and tori), the bridge is that iso-line, and every point of it is equidistant from the
surfaces of ``a`` and ``b``: this is measured, not assumed, and the bridge is refused above
the tolerance.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf

from medax.cad.simplify.corner import plane_normal
from medax.cad.simplify.medial import Medial
from medax.cad.simplify.occ import Array, face_inside_point, pnt, xyz

#: Samples along the bridge where its equidistance from the two supporting faces is measured.
CHECK_SAMPLES = 11
#: A loose smooth edge lets the base's medial curve end up to its tolerance from it, at most
#: this many times the build tolerance (the rebuilt solid's checks have the last word).
LOOSE_REACH = 10.0


def bridge_edge(
    rider: Any,
    rider_medial: Medial,
    base_medial: Medial,
    smooth_edge: Any,
    supports: tuple[Any, Any],
    tol: float,
    rel_tol: float = 1e-9,
) -> tuple[Any, float] | str:
    """The bridge of fillet face ``rider`` over the fillet whose medial curve is
    ``base_medial``: a tool edge and its measured equidistance error (length unit).

    ``smooth_edge``: the rider's smooth edge on the base fillet; ``supports``: the base
    fillet's two supporting faces; ``tol``: length tolerance for the bridge's start on
    ``smooth_edge`` (up to the edge's own, looser tolerance: :func:`_reach`). The bridge is
    taken when it is equidistant to ``rel_tol x radius`` or to twice the larger of ``tol``
    and the smooth edge's tolerance, the rule the medial curves follow
    (:func:`.medial.medial_curve`). Returns a one-line reason when there is no such bridge.
    """
    if rider_medial.iso not in ("u", "v"):
        return "the rider's medial curve is traced, not an iso-line (no bridge along it)"
    ext = BRepExtrema_DistShapeShape(base_medial.edge, smooth_edge)
    if not ext.IsDone() or ext.NbSolution() < 1:
        return "the medial curve of the fillet it rides on does not reach its smooth edge"
    if ext.Value() > _reach(smooth_edge, tol):
        return (
            "the medial curve of the fillet it rides on does not reach its smooth edge "
            f"(gap {ext.Value():.2e})"
        )
    start = ext.PointOnShape1(1)
    surf = BRep_Tool.Surface_s(rider)
    u, v = GeomAPI_ProjectPointOnSurf(start, surf).LowerDistanceParameters()
    if rider_medial.iso == "u":  # the rider's medial is u = mid: the bridge runs along u at v
        a, curve = float(u), surf.VIso(float(v))
        period = surf.UPeriod() if surf.IsUPeriodic() else 0.0
    else:
        a, curve = float(v), surf.UIso(float(u))
        period = surf.VPeriod() if surf.IsVPeriodic() else 0.0
    b = rider_medial.mid
    if period and abs(b - a) > 0.5 * period:  # the same period as the medial's
        a += math.copysign(period, b - a)
    if abs(b - a) < 1e-12:
        return "the bridge has zero length"
    lo, hi = min(a, b), max(a, b)
    err = _equidistance(curve, lo, hi, supports)
    slack = max(tol, BRep_Tool.Tolerance_s(smooth_edge))
    if err > max(rel_tol * rider_medial.radius, 2.0 * slack):
        return f"the bridge is not equidistant from the two supporting faces ({err:.2e})"
    mk = BRepBuilderAPI_MakeEdge(curve, lo, hi)
    if not mk.IsDone():
        return "could not build the bridge edge"
    return mk.Edge(), err


def _reach(edge: Any, tol: float) -> float:
    """How far the base's medial curve may end from the rider's smooth ``edge``: ``tol``,
    or the edge's own tolerance where the input is looser (its curve is only known to
    that), at most ``LOOSE_REACH`` times ``tol``."""
    return max(tol, min(BRep_Tool.Tolerance_s(edge), LOOSE_REACH * tol))


def _equidistance(curve: Any, lo: float, hi: float, supports: tuple[Any, Any]) -> float:
    """Largest ``| dist to surface a - dist to surface b |`` at samples of ``curve``
    (unsigned distances to the supporting faces' whole surfaces)."""
    pts = np.array([xyz(curve.Value(float(t))) for t in np.linspace(lo, hi, CHECK_SAMPLES)])
    da, db = (_distances(pts, f) for f in supports)
    return float(np.max(np.abs(da - db)))


def _distances(pts: Array, face: Any) -> Array:
    """Unsigned distances (n,) of points (n, 3) from the surface of ``face``: closed form
    on a plane, else by projection (``GeomAPI_ProjectPointOnSurf``)."""
    n, q = plane_normal(face), face_inside_point(face)
    if n is not None and q is not None:
        return np.asarray(np.abs((pts - q) @ n))
    surf = BRep_Tool.Surface_s(face)
    out = np.full(len(pts), np.inf)
    for i, p in enumerate(pts):  # 11 samples per bridge, once per rider
        proj = GeomAPI_ProjectPointOnSurf(pnt(p), surf)
        if proj.NbPoints() > 0:
            out[i] = proj.LowerDistance()
    return out
