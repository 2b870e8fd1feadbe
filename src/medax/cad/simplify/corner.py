"""Split curves of a spherical corner blend (the paper's point-transition fillet).

A corner where fillets between planes meet is a sphere piece. Each fillet's medial curve
ends on the corner at ``M = C + s R (n_a + n_b) / |n_a + n_b|`` (``n_a``, ``n_b`` the outward
normals of its supporting planes, ``C`` and ``R`` the sphere's centre and radius, ``s = +1`` on
a convex corner, ``-1`` on a concave one). The corner's centre is the point of the sphere
equidistant from all its supporting planes, ``P = C + s R u`` with ``u . n_i`` equal for all
``i``. The great arc from ``M`` to ``P`` lies in the plane through ``C`` spanned by
``n_a + n_b`` and ``u``, where every point of the sphere is equidistant from planes ``a`` and
``b``: it is the corner's medial curve between the two faces, continuing the fillet's.
Each piece then goes to the supporting face whose normal is nearest to its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.GC import GC_MakeArcOfCircle
from OCP.GeomAbs import GeomAbs_Plane, GeomAbs_Sphere
from OCP.gp import gp_Ax2, gp_Circ, gp_Dir

from medax.cad.simplify.occ import Array, face_inside_point, face_normal_at, pnt, xyz


def plane_normal(face: Any) -> Array | None:
    """Outward unit normal of a planar face (orientation applied), None if not a plane."""
    if BRepAdaptor_Surface(face).GetType() != GeomAbs_Plane:
        return None
    p = face_inside_point(face)
    return None if p is None else face_normal_at(face, p)


def _equidistant_direction(n: Array) -> Array | None:
    """Unit ``u`` (3,) with ``n_i . u`` equal for every row of the unit normals ``n``
    (k, 3): along it a point moves equally far from all their planes; None when there is
    none (least squares misses it)."""
    sol, *_ = np.linalg.lstsq(n, np.ones(len(n)), rcond=None)
    u: Array = sol / np.linalg.norm(sol)
    return None if np.ptp(n @ u) > 1e-9 else u


def corner_arcs(
    corner: Any, pairs: Sequence[tuple[int, int]], normals: dict[int, Array]
) -> tuple[list[Any], Array] | str:
    """Great-arc tool edges of ``corner`` (a face), one per fillet meeting it, and its centre.

    ``pairs``: the two supporting faces (indices) of each fillet that meets the corner;
    ``normals``: outward unit normal of each of those faces (all planes). Returns the edges and
    the centre point (3,), or a one-line reason when this corner is not a sphere piece.
    """
    ad = BRepAdaptor_Surface(corner)
    if ad.GetType() != GeomAbs_Sphere:
        return "corner blend is not a sphere piece (not supported)"
    sph = ad.Sphere()
    c, r = xyz(sph.Location()), float(sph.Radius())
    inside = face_inside_point(corner)
    n_in = None if inside is None else face_normal_at(corner, inside)
    if inside is None or n_in is None:
        return "corner blend: no inside point"
    s = 1.0 if float(n_in @ (inside - c)) > 0 else -1.0
    faces = sorted({f for pair in pairs for f in pair})
    u = _equidistant_direction(np.array([normals[f] for f in faces]))
    if u is None:
        return "corner blend: no point equidistant from all its supporting planes"
    centre = c + s * r * u
    edges = []
    for fa, fb in pairs:
        w = normals[fa] + normals[fb]
        if np.linalg.norm(w) < 1e-9:
            return "corner blend: opposite supporting planes"
        m = c + s * r * w / np.linalg.norm(w)
        axis = np.cross(m - c, centre - c)
        if np.linalg.norm(axis) < 1e-12 * r * r:
            return "corner blend: a fillet's medial curve ends at the corner's centre"
        axis /= np.linalg.norm(axis)
        frame = gp_Ax2(pnt(c), gp_Dir(*map(float, axis)), gp_Dir(*map(float, (m - c) / r)))
        arc = GC_MakeArcOfCircle(gp_Circ(frame, r), pnt(m), pnt(centre), True).Value()
        mk = BRepBuilderAPI_MakeEdge(arc)
        if not mk.IsDone():
            return "corner blend: could not build a split arc"
        edges.append(mk.Edge())
    return edges, centre


def corner_sections(
    corner: Any,
    pairs: Sequence[tuple[int, int]],
    planes: dict[int, tuple[Array, float]],
    medial_edges: Sequence[Any],
    tol: float,
) -> tuple[list[Any], Array] | str:
    """Split edges of a corner blend that is no sphere piece (a vertex blend between fillets
    of several radii: a B-spline patch), one per fillet meeting it, and its centre.

    The points of the corner equidistant from the supporting planes ``a`` and ``b`` of a
    fillet lie on their bisector plane ``(n_a - n_b) . (X - V) = 0`` (``V`` the planes'
    common point): the fillet's medial curve lies in it and ends on the corner at ``M``
    (where ``medial_edges[i]`` meets the corner), and the corner's centre ``P``, the point
    of the corner equidistant from all its planes, lies on the line ``V + t u`` with
    ``n_i . u`` equal for all ``i``. Each split edge is the corner's section by the
    fillet's bisector plane from ``M`` to ``P`` (``GeomAPI_IntSS``, to ``tol``, a length).
    ``planes``: the outward unit normal and offset ``n . X`` of each supporting plane.
    Returns the edges and ``P`` (3,), or a one-line reason.
    """
    from OCP.Geom import Geom_Line, Geom_Plane, Geom_TrimmedCurve
    from OCP.GeomAPI import GeomAPI_IntCS, GeomAPI_IntSS, GeomAPI_ProjectPointOnCurve
    from OCP.gp import gp_Lin, gp_Pln, gp_Pnt2d
    from OCP.IntTools import IntTools_FClass2d
    from OCP.TopAbs import TopAbs_OUT

    surf = BRep_Tool.Surface_s(corner)
    faces = sorted({f for pair in pairs for f in pair})
    n = np.array([planes[f][0] for f in faces])
    d = np.array([planes[f][1] for f in faces])
    u = _equidistant_direction(n)
    if u is None:
        return "corner blend: no point equidistant from all its supporting planes"
    vertex, *_ = np.linalg.lstsq(n, d, rcond=None)
    if np.max(np.abs(n @ vertex - d)) > tol:
        return "corner blend: its supporting planes have no common point"
    hits = GeomAPI_IntCS(Geom_Line(gp_Lin(pnt(vertex), gp_Dir(*map(float, u)))), surf)
    inside = IntTools_FClass2d(corner, tol)
    centre = None
    for k in range(1, (hits.NbPoints() if hits.IsDone() else 0) + 1):
        su, sv, _ = hits.Parameters(k)  # on the surface, on the line
        p = xyz(hits.Point(k))
        if inside.Perform(gp_Pnt2d(su, sv)) != TopAbs_OUT and (
            centre is None or np.linalg.norm(p - vertex) < np.linalg.norm(centre - vertex)
        ):
            centre = p
    if centre is None:
        return "corner blend: the line of points equidistant from its planes misses it"
    edges = []
    for (fa, fb), medial in zip(pairs, medial_edges, strict=True):
        w = planes[fa][0] - planes[fb][0]
        if np.linalg.norm(w) < 1e-9:
            return "corner blend: parallel supporting planes"
        plane = Geom_Plane(gp_Pln(pnt(vertex), gp_Dir(*map(float, w / np.linalg.norm(w)))))
        section = GeomAPI_IntSS(surf, plane, tol)
        found = None
        for k in range(1, (section.NbLines() if section.IsDone() else 0) + 1):
            curve = section.Line(k)
            at_p = GeomAPI_ProjectPointOnCurve(pnt(centre), curve)
            if at_p.NbPoints() and at_p.LowerDistance() <= 10.0 * tol:
                found = (curve, at_p.LowerDistanceParameter())
                break
        if found is None:
            return "corner blend: its section by a fillet's bisector plane misses its centre"
        curve, tp = found
        ext = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeEdge(curve).Edge(), medial)
        if not ext.IsDone() or ext.NbSolution() < 1 or ext.Value() > 10.0 * tol:
            return "corner blend: a fillet's medial curve does not meet the corner's section"
        tm = GeomAPI_ProjectPointOnCurve(ext.PointOnShape1(1), curve).LowerDistanceParameter()
        if abs(tm - tp) < 1e-12:
            return "corner blend: a fillet's medial curve ends at the corner's centre"
        mk = BRepBuilderAPI_MakeEdge(Geom_TrimmedCurve(curve, min(tm, tp), max(tm, tp)))
        if not mk.IsDone():
            return "corner blend: could not build a split edge"
        edges.append(mk.Edge())
    return edges, centre
