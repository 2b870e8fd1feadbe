"""The medial curve of a constant-radius fillet: the iso-line at the mid parameter.

On a fillet whose two smooth edges are iso-lines of its surface in one direction (a
cylinder between two planes, a torus around a boss), the curve at the mid parameter in that
direction is equidistant from both smooth edges by symmetry of the circular section. This
is verified, not assumed: :func:`medial_curve` measures ``|d1 - d2|`` with
``BRepExtrema_DistShapeShape`` at samples and refuses the fillet when it is above the tolerance,
except on a B-spline blend, whose medial curve is then traced per cross-section
(:mod:`.traced`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_Cylinder, GeomAbs_Torus
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt

from medax.cad.simplify.axis_medial import axis_medial_edge
from medax.cad.simplify.occ import compound, edge_points, uv_bounds
from medax.cad.simplify.traced import traced_medial_edge

#: The medial tool edge is extended past the fillet by this fraction of its length on both
#: sides (the splitter keeps only the part on the face), unless it is closed.
EXTEND = 0.02
#: ``Medial.iso`` of a traced medial curve (no iso-line; see :mod:`.traced`).
TRACED = "traced"
#: ``Medial.iso`` of the paper's medial axis traced across the face (:mod:`.axis_medial`).
AXIS = "axis"


@dataclass(frozen=True)
class Medial:
    """Medial curve of a fillet: ``edge`` (the splitter tool), the iso direction (``"u"``
    when the curve is ``u = mid``; ``TRACED`` when it is no iso-line, then ``mid`` is nan),
    the mid parameter, the measured equidistance error
    ``error`` (length unit), the blend ``radius`` and ``cross``, the cross parameters of the
    two smooth edges (side 0, side 1; nan on a traced curve)."""

    edge: Any
    iso: str
    mid: float
    error: float
    radius: float
    cross: tuple[float, float] = (float("nan"), float("nan"))


def _uv(surface: Any, p: np.ndarray) -> tuple[float, float]:
    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), surface)
    u, v = proj.LowerDistanceParameters()
    return float(u), float(v)


def _common_span(ends: list[np.ndarray], j: int, a: float, b: float) -> tuple[float, float]:
    """The part of ``[a, b]`` (the face's range in the along parameter ``j``) that both
    smooth edges span, by their sample parameters ``ends`` (each (n, 2), unwrapped), shrunk
    by 1 % of its length at either end; ``[a, b]`` when they share less."""
    lo = max(float(e[:, j].min()) for e in ends)
    hi = min(float(e[:, j].max()) for e in ends)
    lo, hi = max(lo, a), min(hi, b)
    if not hi > lo:
        return a, b
    pad = 0.01 * (hi - lo)
    return lo + pad, hi - pad


def _unwrapped(uv: np.ndarray, ad: Any, bounds: tuple[float, float, float, float]) -> np.ndarray:
    """Surface parameters ``uv`` (n, 2) of points along an edge, each periodic direction
    unwrapped along the edge (projections land on either side of a seam: the v = 0 circle
    of a quarter torus in ANC101 came back partly at v = 2 pi) and shifted by whole periods
    to the representative nearest the face's own range ``bounds`` (u0, u1, v0, v1)."""
    out = uv.copy()
    for k in (0, 1):
        per = _period(ad, k)
        if not per:
            continue
        # consecutive samples are less than half a period apart (5 along an edge of at most
        # a full turn): unwrapped step by step, an arc of more than half a turn stays whole
        out[:, k] = np.unwrap(out[:, k], period=per)
        mid = 0.5 * (bounds[2 * k] + bounds[2 * k + 1])
        out[:, k] -= per * np.round((out[0, k] - mid) / per)
    return out


def _speeds(surf: Any, uv: np.ndarray) -> np.ndarray:
    """Lengths of the surface's first derivatives (dS/du, dS/dv) at ``uv`` (2,): a parameter
    spread times these is a length."""
    u, v = float(uv[0]), float(uv[1])
    return np.array([surf.DN(u, v, 1, 0).Magnitude(), surf.DN(u, v, 0, 1).Magnitude()])


def _period(ad: Any, k: int) -> float:
    """Period of the surface in u (``k = 0``) or v (``k = 1``), 0 when not periodic."""
    if k == 0:
        return float(ad.UPeriod()) if ad.IsUPeriodic() else 0.0
    return float(ad.VPeriod()) if ad.IsVPeriodic() else 0.0


def medial_curve(
    face: Any, edge1: Any, edge2: Any, rel_tol: float = 1e-9, tol: float = 0.0
) -> Medial | str:
    """Medial curve of the fillet ``face`` between smooth edges ``edge1`` and ``edge2`` (each
    an edge, or the list of edges of a constraint side that is a chain).

    Returns a :class:`Medial`, or a one-line reason (str) when the fillet is not a
    constant-radius iso-line fillet whose mid iso-line is equidistant to ``rel_tol x radius``
    (or to twice the larger of ``tol``, a length, and the smooth edges' own tolerance: imported
    edges lie on iso-lines only to within these).
    """
    ad = BRepAdaptor_Surface(face)
    kind = ad.GetType()
    radius = None
    if kind == GeomAbs_Cylinder:
        radius = ad.Cylinder().Radius()
    elif kind == GeomAbs_Torus:
        radius = ad.Torus().MinorRadius()
    surf = BRep_Tool.Surface_s(face)
    u0, u1, v0, v1 = uv_bounds(face)
    sides = [list(e) if isinstance(e, list | tuple) else [e] for e in (edge1, edge2)]
    ends = [
        _unwrapped(
            np.array([_uv(surf, p) for e in side for p in edge_points(e, 5)]),
            ad,
            (u0, u1, v0, v1),
        )
        for side in sides
    ]
    # the input's own tolerance: imported edges lie on iso-lines only to within it (a
    # corpus part's straight smooth edges strayed 6e-7 mm round a 2 mm cylinder, tolerance 1e-7)
    slack = max([tol] + [BRep_Tool.Tolerance_s(e) for side in sides for e in side])
    edge1, edge2 = (side[0] if len(side) == 1 else compound(side) for side in sides)
    spread = [np.ptp(uv, axis=0) * _speeds(surf, uv[0]) for uv in ends]
    if all(s[0] <= slack for s in spread):  # smooth edges are u-iso lines: cross direction u
        iso, k, lo, hi, closed_dir = "u", 0, v0, v1, ad.IsVPeriodic()
    elif all(s[1] <= slack for s in spread):
        iso, k, lo, hi, closed_dir = "v", 1, u0, u1, ad.IsUPeriodic()
    else:  # the paper's medial axis, traced across the face between the smooth sides
        accept = max(rel_tol * (radius or 0.0), 2 * slack)
        return _by_axis(
            face, sides, accept, radius, "smooth edges are not iso-lines of the fillet surface"
        )
    # mid between the smooth edges' own parameters (the face may reach past them)
    c1, c2 = float(ends[0][0, k]), float(ends[1][0, k])
    # periods: 2 pi on cylinders and tori, the knot range on periodic B-splines
    cross_period = _period(ad, k)
    if cross_period and abs(c2 - c1) > 0.5 * cross_period:
        c2 -= math.copysign(cross_period, c2 - c1)
    mid = 0.5 * (c1 + c2)
    cross = (c1, c2)
    period = _period(ad, 1 - k) or 2 * math.pi
    full = closed_dir and abs((hi - lo) - period) < 1e-9
    if not full:
        ext = EXTEND * (hi - lo)
        lo, hi = lo - ext, hi + ext
        if closed_dir and hi - lo >= period:
            return "fillet wraps almost all around its axis: not supported"
        if not closed_dir:  # a bounded surface (a B-spline blend) is not continued past its end
            ub0, ub1, vb0, vb1 = surf.Bounds()
            lo, hi = (max(lo, ub0), min(hi, ub1)) if iso == "v" else (max(lo, vb0), min(hi, vb1))
    curve = surf.UIso(mid) if iso == "u" else surf.VIso(mid)
    mk = BRepBuilderAPI_MakeEdge(curve, lo, hi)
    if not mk.IsDone():
        return "could not build the medial edge"
    edge = mk.Edge()
    # Equidistance, measured with BRepExtrema at samples inside the face, along the stretch
    # both smooth edges span (beyond the end of the shorter one, where a fillet is trimmed
    # obliquely by a neighbour, the distance to that edge is to its end point, not to the
    # constraint: a random box's fillets measured 0.98 x radius there and were kept)
    a, b = (lo, hi) if full else (lo + (hi - lo) * EXTEND, hi - (hi - lo) * EXTEND)
    if not full:
        a, b = _common_span(ends, 1 - k, a, b)
    err, near = 0.0, float("inf")
    for t in np.linspace(a, b, 9):
        p = curve.Value(float(t))
        vtx = BRepBuilderAPI_MakeVertex(p).Vertex()
        d = []
        for e in (edge1, edge2):
            ext = BRepExtrema_DistShapeShape(vtx, e)
            d.append(ext.Value())
        err, near = max(err, abs(d[0] - d[1])), min(near, *d)
    freeform = radius is None
    if radius is None:  # a variable-radius or freeform blend: the scale is its half-width
        radius = near
    accept = max(rel_tol * radius, 2 * slack)  # the iso-line may be as off as the input
    if err <= accept:
        return Medial(edge, iso, float(mid), float(err), float(radius), (float(c1), float(c2)))
    why = f"mid iso-line not equidistant ({err:.2e} > {accept / radius:.2g} x radius)"
    if freeform and kind == GeomAbs_BSplineSurface and max(len(side) for side in sides) == 1:
        # a B-spline blend whose mid iso-line is off (a rolling ball between a plane and a
        # slanted cylinder): the medial curve traced per cross-section, to rel_tol x radius,
        # or (with the most nodes) to the tolerance an iso-line is accepted with
        traced = traced_medial_edge(
            face, (edge1, edge2), k, cross, (lo, hi), rel_tol * radius, accept, tol
        )
        if not isinstance(traced, str):
            return Medial(traced[0], TRACED, float("nan"), traced[1], float(radius))
        why += f", {traced}"
    return _by_axis(face, sides, accept, radius, why)


def _by_axis(
    face: Any, sides: list[list[Any]], accept: float, radius: float | None, why: str
) -> Medial | str:
    """The medial curve of ``face`` as the paper's axis between the smooth ``sides``
    (:func:`.axis_medial.axis_medial_edge`, equidistant to ``accept``), or ``why`` with
    the reason it failed too."""
    by_axis = axis_medial_edge(face, sides[0], sides[1], accept)
    if isinstance(by_axis, str):
        return f"{why}; {by_axis}"
    edge, err, near = by_axis
    return Medial(edge, AXIS, float("nan"), err, float(radius or near))
