"""Exact surfaces for a merged face: a supporting face plus its fillet halves.

Two cases have an exact answer (the issue's step 3):

- **extrusion**: the halves are cylinders with parallel axes ``d`` and the supporting face is
  a plane containing ``d`` (or a cylinder on an axis along ``d``: the end face of a chain of
  fillets, :mod:`.chains`, whose half is a sequence of arcs). The section by a plane normal
  to ``d`` is a G1 chain arc(s) - line (or arc) - arc(s); joined into one rational B-spline
  it is extruded along ``d``, as the exact B-spline surface of that extrusion
  (:func:`extruded_bspline`).
- **revolution**: the halves are tori (or cylinders) on one axis and the supporting face is a
  plane normal to it or a coaxial cylinder or cone. The meridian section (line and arcs)
  joined into one B-spline is revolved about the axis, starting at the x-direction of the
  first torus so closed medial circles meet the seam.

Anything else returns a reason string; the caller keeps those fillets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.GC import GC_MakeArcOfCircle, GC_MakeSegment
from OCP.Geom import (
    Geom_SurfaceOfRevolution,
)
from OCP.GeomAbs import GeomAbs_Cone, GeomAbs_Cylinder, GeomAbs_Plane, GeomAbs_Torus
from OCP.GeomConvert import GeomConvert, GeomConvert_CompCurveToBSplineCurve
from OCP.gp import gp_Ax1, gp_Dir

from medax.cad.simplify.canonical import canonical_adaptor
from medax.cad.simplify.medial import Medial
from medax.cad.simplify.occ import Array, edge_points, edges_of, pnt, xyz

#: Free ends of the profile are extended by this fraction of the profile's length.
FREE_END_EXTENSION = 0.1
#: The medial end of each half-arc is extended past the medial curve by this angle (rad).
MEDIAL_OVERSHOOT = 0.05


@dataclass(frozen=True)
class Half:
    """A fillet half going to a supporting face: the fillet ``face``, its ``medial`` curve and
    the smooth ``edge`` it shares with the supporting face."""

    face: Any
    medial: Medial
    edge: Any
    #: For the first fillet of a chain (:mod:`.chains`): the faces of the members after it
    #: and the section arcs (each (3, 3)) of all the members that join this face, in order.
    chain: tuple[Any, ...] = ()
    arcs: tuple[Array, ...] = ()


@dataclass(frozen=True)
class MergedSurface:
    """The surface of a merged face, its ``kind`` (``extrusion``/``revolution``) and the
    profile (a ``Geom_BSplineCurve``)."""

    surface: Any
    kind: str
    profile: Any


def _axis(ad: Any) -> tuple[Array, Array]:
    kind = ad.GetType()
    ax = {
        GeomAbs_Cylinder: lambda: ad.Cylinder().Axis(),
        GeomAbs_Torus: lambda: ad.Torus().Axis(),
        GeomAbs_Cone: lambda: ad.Cone().Axis(),
    }[kind]()
    return xyz(ax.Location()), xyz(ax.Direction())


def _half_params(half: Half) -> tuple[float, float, float]:
    """(smooth-edge cross parameter, extended medial parameter, a parameter along the iso)."""
    surf = BRep_Tool.Surface_s(half.face)
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf

    p = edge_points(half.edge, 3)[1]
    u, v = GeomAPI_ProjectPointOnSurf(pnt(p), surf).LowerDistanceParameters()
    cross, along = (u, v) if half.medial.iso == "u" else (v, u)
    mid = half.medial.mid
    # bring the edge parameter within half a period of mid (periodic directions)
    if math.isfinite(cross - mid):
        cross = mid + math.remainder(cross - mid, 2 * math.pi)
    over = mid + np.sign(mid - cross) * MEDIAL_OVERSHOOT
    return float(cross), float(over), float(along)


def _half_points(half: Half, n: int = 3) -> Array:
    """``n`` points across the half, from the smooth edge to past the medial curve (n, 3)."""
    surf = BRep_Tool.Surface_s(half.face)
    c0, c1, along = _half_params(half)
    pts = []
    for c in np.linspace(c0, c1, n):
        uv = (c, along) if half.medial.iso == "u" else (along, c)
        pts.append(xyz(surf.Value(float(uv[0]), float(uv[1]))))
    return np.array(pts)


def _boundary_samples(face: Any, n: int = 17) -> Array:
    return np.vstack([edge_points(e, n) for e in edges_of(face)])


def _chain(
    segment: tuple[Array, Array],
    arcs: list[list[Array]],
    tol: float,
    fixed: Array | None = None,
) -> list[Any] | str:
    """Profile pieces: line ``segment`` (p0, p1) with each sequence of arcs (each arc 3
    points, the first arc's first on the line's end, each next one starting where the one
    before ends) attached at the matching end; free line ends extended, except an end at
    ``fixed`` (a point on the axis of revolution). Returns curves in order."""
    p0, p1 = segment
    at: dict[int, list[Array]] = {}
    for arc in arcs:
        d0, d1 = np.linalg.norm(arc[0][0] - p0), np.linalg.norm(arc[0][0] - p1)
        end = 0 if d0 < d1 else 1
        if min(d0, d1) > tol:
            return "a fillet half does not meet an end of the face's section"
        if end in at:
            return "two fillet halves meet the same end of the face's section"
        at[end] = arc
    length = float(np.linalg.norm(p1 - p0))
    if length < tol:
        return "degenerate section of the supporting face"
    t = (p1 - p0) / length

    def stays(p: Array) -> bool:
        return fixed is not None and float(np.linalg.norm(p - fixed)) <= tol

    q0 = p0 if 0 in at or stays(p0) else p0 - FREE_END_EXTENSION * length * t
    q1 = p1 if 1 in at or stays(p1) else p1 + FREE_END_EXTENSION * length * t
    pieces: list[Any] = []
    if 0 in at:
        pieces += [_arc_piece(a[::-1]) for a in reversed(_attached(at[0], q0, tol))]
    pieces.append(GC_MakeSegment(pnt(q0), pnt(q1)).Value())
    if 1 in at:
        pieces += [_arc_piece(a) for a in _attached(at[1], q1, tol)]
    return pieces


def _arc_core(
    centre: Array, radius: float, d: Array, pts: Array, arcs: list[list[Array]], tol: float
) -> list[Any] | str:
    """Profile pieces when the supporting face is a cylinder on an axis along ``d``: its
    section is the arc of ``centre`` (3,) and ``radius`` spanned by ``pts`` (n, 3, projected
    on the section plane through ``centre``), with each sequence of ``arcs`` attached at the
    matching end as in :func:`_chain`; free ends continued by a tenth of the sweep."""
    e1 = pts[0] - centre
    e1 -= (e1 @ d) * d
    if np.linalg.norm(e1) < tol:
        return "degenerate section of the supporting cylinder"
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    r = pts - centre
    if np.abs(np.linalg.norm(r, axis=1) - radius).max() > tol:
        return "the supporting cylinder's boundary is not on its circle"
    th = np.sort(np.mod(np.arctan2(r @ e2, r @ e1), 2 * math.pi))
    gaps = np.diff(np.concatenate([th, th[:1] + 2 * math.pi]))
    g = int(np.argmax(gaps))
    if gaps[g] < 0.1:
        return "the supporting cylinder is closed round its axis"
    t0 = float(th[(g + 1) % len(th)])
    t1 = t0 + 2 * math.pi - float(gaps[g])

    def at(t: float) -> Array:
        return centre + radius * (math.cos(t) * e1 + math.sin(t) * e2)

    ends = (at(t0), at(t1))
    where: dict[int, list[Array]] = {}
    for seq in arcs:
        dist = [float(np.linalg.norm(seq[0][0] - p)) for p in ends]
        k = int(np.argmin(dist))
        if dist[k] > tol:
            return "a fillet half does not meet an end of the face's section"
        if k in where:
            return "two fillet halves meet the same end of the face's section"
        where[k] = seq
    room = min(0.1 * (t1 - t0), 0.5 * float(gaps[g]))
    a0 = t0 if 0 in where else t0 - room
    a1 = t1 if 1 in where else t1 + room
    q0, q1 = at(a0), at(a1)
    pieces: list[Any] = []
    if 0 in where:
        pieces += [_arc_piece(a[::-1]) for a in reversed(_attached(where[0], q0, tol))]
    pieces.append(_arc_piece(np.array([q0, at(0.5 * (a0 + a1)), q1])))
    if 1 in where:
        pieces += [_arc_piece(a) for a in _attached(where[1], q1, tol)]
    return pieces


def _attached(arcs: list[Array], start: Array, tol: float) -> list[Array]:
    """Copies of ``arcs`` (each (3, 3)), the first starting exactly at ``start`` and each
    next one exactly where the one before ends (they meet within ``tol`` already: edges
    shared by two faces, sampled on each)."""
    out, p = [], start
    for a in arcs:
        if float(np.linalg.norm(a[0] - p)) > tol:
            raise ValueError("the arcs of a chain of fillets do not meet")
        b = a.copy()
        b[0] = p
        out.append(b)
        p = b[-1]
    return out


def _arc_piece(a: Array) -> Any:
    return GC_MakeArcOfCircle(pnt(a[0]), pnt(a[1]), pnt(a[2])).Value()


def _join(pieces: list[Any], tol: float) -> Any:
    comp = GeomConvert_CompCurveToBSplineCurve(GeomConvert.CurveToBSplineCurve_s(pieces[0]))
    for c in pieces[1:]:
        if not comp.Add(GeomConvert.CurveToBSplineCurve_s(c), tol, True):
            raise ValueError("profile pieces do not join")
    return comp.BSplineCurve()


def _line_extent(points: Array, tol: float) -> tuple[Array, Array] | None:
    """Extreme points of ``points`` (n, 3) when they are collinear within ``tol``."""
    c = points.mean(axis=0)
    _, s, vt = np.linalg.svd(points - c)
    if s.size > 1 and np.abs((points - c) @ vt[1]).max() > tol:
        return None
    s_along = (points - c) @ vt[0]
    return points[np.argmin(s_along)], points[np.argmax(s_along)]


def _point_in_face(face: Any, p: Array, tol: float) -> bool:
    """True when ``p`` (3,) lies inside ``face`` (or on its boundary)."""
    from OCP.BRepClass import BRepClass_FaceClassifier
    from OCP.TopAbs import TopAbs_OUT

    return BRepClass_FaceClassifier(face, pnt(p), tol).State() != TopAbs_OUT


def merged_surface(support: Any, halves: list[Half], tol: float) -> MergedSurface | str:
    """Exact surface covering ``support`` and its ``halves``, or the reason why there is none.

    ``tol`` is the length tolerance of the geometric tests (e.g. 1e-7 x the part diagonal).
    """
    if any(h.medial.iso not in ("u", "v") for h in halves):  # traced: no profile to sweep
        return "a half's medial curve is no iso-line (no exact surface sweeps it)"
    sad = canonical_adaptor(support, tol)
    hads = [canonical_adaptor(f, tol) for h in halves for f in (h.face, *h.chain)]
    kinds = {a.GetType() for a in hads}
    if kinds == {GeomAbs_Cylinder} and sad.GetType() == GeomAbs_Plane:
        return _extrusion(support, sad, halves, hads, tol)
    if kinds == {GeomAbs_Cylinder} and sad.GetType() == GeomAbs_Cylinder:
        # a cylinder on a parallel axis (the end face of a chain of fillets, :mod:`.chains`)
        return _extrusion(support, sad, halves, hads, tol)
    if kinds <= {GeomAbs_Torus, GeomAbs_Cylinder} and GeomAbs_Torus in kinds:
        return _revolution(support, sad, halves, hads, tol)
    return "no exact surface for this face and its fillet halves (fitting not implemented)"


def _extrusion(support: Any, sad: Any, halves: list[Half], hads: list[Any], tol: float) -> Any:
    dirs = [_axis(a)[1] for a in hads]
    d = dirs[0]
    if any(np.linalg.norm(np.cross(d, e)) > 1e-9 for e in dirs[1:]):
        return "fillets along non-parallel edges of one plane: no extrusion (not supported)"
    pts = _boundary_samples(support)
    o = pts[0]

    def proj(p: Array) -> Array:
        return p - np.outer((p - o) @ d, d) if p.ndim == 2 else p - ((p - o) @ d) * d

    arcs = [[proj(a) for a in h.arcs] if h.arcs else [proj(_half_points(h))] for h in halves]
    if sad.GetType() == GeomAbs_Cylinder:
        c, a = _axis(sad)
        if np.linalg.norm(np.cross(d, a)) > 1e-9:
            return "fillet axis not parallel to the supporting cylinder's axis"
        pieces = _arc_core(proj(c), sad.Cylinder().Radius(), d, proj(pts), arcs, 10 * tol)
    else:
        n = xyz(sad.Plane().Axis().Direction())
        if abs(n @ d) > 1e-9:
            return "fillet axis not parallel to the supporting plane"
        ext = _line_extent(proj(pts), tol)
        if ext is None:
            return "supporting plane's section is not a line"
        pieces = _chain(ext, arcs, 10 * tol)
    if isinstance(pieces, str):
        return pieces
    profile = _join(pieces, tol)
    # finite along d: the group's extent along d plus a margin (projections need bounds)
    along = np.concatenate(
        [(pts - o) @ d]
        + [(_boundary_samples(f) - o) @ d for h in halves for f in (h.face, *h.chain)]
    )
    start = float((o - xyz(profile.StartPoint())) @ d)
    lo, hi = float(along.min()), float(along.max())
    margin = 0.1 * (hi - lo) + 10 * tol
    surf = extruded_bspline(profile, d, lo - margin + start, hi + margin + start)
    return MergedSurface(surf, "extrusion", profile)


def extruded_bspline(profile: Any, d: Array, a0: float, a1: float) -> Any:
    """The exact B-spline surface ``S(a, t) = profile(t) + a d`` for ``a`` in ``[a0, a1]``
    (``d`` a unit (3,) vector): degree 1 in ``u = a``, the profile's knots in ``v = t``.

    The straight direction is ``u`` on purpose. OCCT's default mass properties (what
    FreeCAD and CadQuery report) integrate in ``u`` with a fixed number of Gauss points
    over the whole range, with no split at knots: across a line - arc joint of the profile
    (only C1) that costs 1e-4 of the volume, while along ``d`` the integrand is constant.
    ``Geom_SurfaceOfLinearExtrusion`` has the profile in ``u``.
    """
    from OCP.collections import Array1_double, Array1_int, Array2_double, Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface

    n = profile.NbPoles()
    poles = Array2_gp_Pnt(1, 2, 1, n)
    weights = Array2_double(1, 2, 1, n)
    for j in range(1, n + 1):
        p = xyz(profile.Pole(j))
        w = profile.Weight(j)
        for i, a in ((1, a0), (2, a1)):
            poles.SetValue(i, j, pnt(p + a * d))
            weights.SetValue(i, j, w)
    uknots, umults = Array1_double(1, 2), Array1_int(1, 2)
    uknots.SetValue(1, a0)
    uknots.SetValue(2, a1)
    umults.SetValue(1, 2)
    umults.SetValue(2, 2)
    k = profile.NbKnots()
    vknots, vmults = Array1_double(1, k), Array1_int(1, k)
    for j in range(1, k + 1):
        vknots.SetValue(j, profile.Knot(j))
        vmults.SetValue(j, profile.Multiplicity(j))
    return Geom_BSplineSurface(
        poles, weights, uknots, vknots, umults, vmults, 1, profile.Degree(), False, False
    )


def _revolution(support: Any, sad: Any, halves: list[Half], hads: list[Any], tol: float) -> Any:
    axes = [_axis(a) for a in hads]
    c, a = axes[0]
    for c2, a2 in axes[1:]:
        off = (c2 - c) - ((c2 - c) @ a) * a
        if np.linalg.norm(np.cross(a, a2)) > 1e-9 or np.linalg.norm(off) > tol:
            return "fillet halves on different axes: no revolution (not supported)"
    sk = sad.GetType()
    if sk == GeomAbs_Plane:
        if np.linalg.norm(np.cross(xyz(sad.Plane().Axis().Direction()), a)) > 1e-9:
            return "supporting plane not normal to the fillet axis"
    elif sk in (GeomAbs_Cylinder, GeomAbs_Cone):
        c2, a2 = _axis(sad)
        off = (c2 - c) - ((c2 - c) @ a) * a
        if np.linalg.norm(np.cross(a, a2)) > 1e-9 or np.linalg.norm(off) > tol:
            return "supporting face not coaxial with its fillet"
    else:
        return "supporting face is not a plane, cylinder or cone: no revolution"
    tor = next(h for h in hads if h.GetType() == GeomAbs_Torus).Torus()
    x0 = xyz(tor.XAxis().Direction())
    x0 = x0 - (x0 @ a) * a
    x0 /= np.linalg.norm(x0)

    def meridian(p: Array) -> Array:
        r = p - c
        z = r @ a
        rho = np.linalg.norm(r - np.outer(z, a), axis=1)
        return c + np.outer(rho, x0) + np.outer(z, a)

    pts = meridian(_boundary_samples(support))
    rho = np.linalg.norm(pts - c - np.outer((pts - c) @ a, a), axis=1)
    fixed = None
    if sk == GeomAbs_Plane:
        # a disk around the axis (a filleted boss top): the profile starts on the axis
        z = float((pts[0] - c) @ a)
        centre = c + z * a
        inside = _point_in_face(support, centre, 10 * tol)
        if inside:
            pts = np.vstack([pts, centre])
            fixed = centre
        elif rho.min() < 10 * tol:
            return "supporting face touches the axis of revolution: not supported"
    elif rho.min() < 10 * tol:
        return "supporting face reaches the axis (pole): not supported"
    ext = _line_extent(pts, tol)
    if ext is None:
        return "supporting face's meridian section is not a line"
    if any(h.chain for h in halves):
        return "a chain of fillets on a face of revolution (not supported)"
    arcs = [[meridian(_half_points(h))] for h in halves]
    pieces = _chain(ext, arcs, 10 * tol, fixed)
    if isinstance(pieces, str):
        return pieces
    profile = _join(pieces, tol)
    surf = Geom_SurfaceOfRevolution(profile, gp_Ax1(pnt(c), gp_Dir(*map(float, a))))
    return MergedSurface(surf, "revolution", profile)
