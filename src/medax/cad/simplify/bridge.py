"""The split curve of a fillet that rides on another fillet (a fillet on a fillet).

When a fillet ``T`` has another fillet ``V`` as a supporting face (the top edge loop of a box
whose vertical edges were rounded first: ``T`` is a torus around ``V``'s cylinder) and both
are simplified, ``V``'s halves go to ``V``'s two supporting faces ``a`` and ``b``, so ``T``'s
half on ``V`` must be shared between them too. It is split by the *bridge*: the
continuation of ``V``'s medial curve across ``T``, from the point where ``V``'s medial curve
meets ``T``'s smooth edge on ``V`` to ``T``'s own medial curve. When ``a`` and ``b`` are
planes and ``T`` is a torus coaxial with ``V`` (or, in general, when ``T``'s cross iso-line
through that point lies in the bisector plane of ``a`` and ``b``), the bridge is that
iso-line, and every point of it is equidistant from ``a`` and ``b``: this is measured, not
assumed, and the bridge is refused above the tolerance.
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
from medax.cad.simplify.occ import Array, face_inside_point, xyz

#: Samples along the bridge where its equidistance from the two planes is measured.
CHECK_SAMPLES = 11


def bridge_edge(
    rider: Any,
    rider_medial: Medial,
    base_medial: Medial,
    smooth_edge: Any,
    planes: tuple[Any, Any],
    tol: float,
    rel_tol: float = 1e-9,
) -> tuple[Any, float] | str:
    """The bridge of fillet face ``rider`` over the fillet whose medial curve is
    ``base_medial``: a tool edge and its measured equidistance error (length unit).

    ``smooth_edge``: the rider's smooth edge on the base fillet; ``planes``: the base
    fillet's two supporting faces; ``tol``: length tolerance for the bridge's start on
    ``smooth_edge``. Returns a one-line reason when there is no such bridge.
    """
    if rider_medial.iso not in ("u", "v"):
        return "the rider's medial curve is traced, not an iso-line (no bridge along it)"
    found = [(plane_normal(p), face_inside_point(p)) for p in planes]
    normals = [n for n, _ in found if n is not None]
    points = [q for _, q in found if q is not None]
    if len(normals) != 2 or len(points) != 2:
        return "the fillet it rides on is not between two planes"
    ext = BRepExtrema_DistShapeShape(base_medial.edge, smooth_edge)
    if not ext.IsDone() or ext.NbSolution() < 1 or ext.Value() > tol:
        return "the medial curve of the fillet it rides on does not reach its smooth edge"
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
    err = _equidistance(curve, lo, hi, normals, points)
    if err > rel_tol * rider_medial.radius:
        return f"the bridge is not equidistant from the two planes ({err:.2e})"
    mk = BRepBuilderAPI_MakeEdge(curve, lo, hi)
    if not mk.IsDone():
        return "could not build the bridge edge"
    return mk.Edge(), err


def _equidistance(
    curve: Any, lo: float, hi: float, normals: list[Array], points: list[Array]
) -> float:
    """Largest ``| |dist to plane a| - |dist to plane b| |`` at samples of ``curve``."""
    pts = np.array([xyz(curve.Value(float(t))) for t in np.linspace(lo, hi, CHECK_SAMPLES)])
    da = np.abs((pts - points[0]) @ normals[0])
    db = np.abs((pts - points[1]) @ normals[1])
    return float(np.max(np.abs(da - db)))
