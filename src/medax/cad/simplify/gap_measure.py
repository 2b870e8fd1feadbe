"""The volume between a new face and the old faces it replaces, measured from the gap.

OCCT's integrators measure a face's share of the volume from a point, a large number from
which the change is a difference; on fitted bicubic faces with hundreds of knot spans
the adaptive and the default integrators were both 9.4e-7 of the part's volume off a
change that the fit's own measure put at -7.6e-10 (tail_wheel_lg_bracket), so fillets
were refused on volume. Here the change itself is integrated: the signed distance from
each point of the new face to the nearest old face, along the new face's outward normal,
over the new face's area (a quadrature on OCCT's triangulation of a copy, the points on
the surface itself). Its error is second order in the gap (at most the deviation
tolerance), not a share of the whole volume.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.GeomAbs import GeomAbs_BSplineSurface
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

from medax.cad.face_region import exact_embedding
from medax.cad.simplify.face_classifier import FaceClassifier
from medax.cad.simplify.occ import Array, uv_bounds, xyz
from medax.cad.simplify.validate import _edge_tolerance, _project
from medax.errors import CadError

#: Linear deflection of the quadrature's triangulation, relative to the face's extent.
DEFLECTION = 5e-3
#: Largest share of the new face's area whose points may have no foot on an old face.
MISSED_SHARE = 1e-3
#: An old face is searched for the points within this share of the new face's extent of
#: its bounding box (the gap is at most the deviation tolerance, far less).
NEAR_SHARE = 1e-2


def _box(face: Any, margin: float) -> tuple[Array, Array]:
    """Corners (3,) and (3,) of ``face``'s bounding box enlarged by ``margin``."""
    box = Bnd_Box()
    BRepBndLib.Add_s(face, box)
    return xyz(box.CornerMin()) - margin, xyz(box.CornerMax()) + margin


def gap_volume(new: Any, old: Sequence[Any]) -> tuple[float, float] | None:
    """(volume, area): the volume (length cubed) between face ``new`` and the faces ``old``
    it replaces, positive where ``new`` lies outside them (along its outward normal, as
    oriented in its solid), and the area of ``new`` (length squared, the quadrature's);
    None when more than ``MISSED_SHARE`` of its area finds no foot on their surfaces."""
    try:
        pts, normals, weights = _quadrature(new)
    except CadError:  # a surface with no numpy copy in OCCT's parameters: not measured
        return None
    foot = np.full_like(pts, np.nan)
    best = np.full(len(pts), np.inf)
    near = np.full_like(pts, np.nan)  # the nearest foot on any old surface, inside or not
    nearest = np.full(len(pts), np.inf)
    margin = NEAR_SHARE * float(np.ptp(pts, axis=0).max()) if len(pts) else 0.0
    for face in old:
        lo, hi = _box(face, margin)
        rows = np.flatnonzero(np.all((pts >= lo) & (pts <= hi), axis=1))
        if rows.size == 0:
            continue
        uv, dist = _project(face, pts[rows])
        keep = (dist < best[rows]) | (dist < nearest[rows])
        rows, uv, dist = rows[keep], uv[keep], dist[keep]
        if rows.size == 0:
            continue
        q = _surface_points(face, uv)
        closer = dist < nearest[rows]
        nearest[rows[closer]], near[rows[closer]] = dist[closer], q[closer]
        better = np.flatnonzero(dist < best[rows])
        if better.size:
            better = better[FaceClassifier(face, _edge_tolerance(face)).inside(uv[better])]
            best[rows[better]], foot[rows[better]] = dist[better], q[better]
    # a point whose feet fall outside the old faces along their boundary (where the new
    # face runs a little past them) takes the nearest old surface, continued, when no foot
    # inside is as near (seen: 2.2 mm away on a far piece, against 1e-5 just outside)
    outside = np.isfinite(nearest) & ~(best <= 2.0 * nearest)
    foot[outside] = near[outside]
    found = np.isfinite(best) | outside
    if weights[~found].sum() > MISSED_SHARE * weights.sum():
        return None
    gap = np.einsum("ij,ij->i", pts[found] - foot[found], normals[found])
    return float(gap @ weights[found]), float(weights.sum())


def _surface_points(face: Any, uv: Array) -> Array:
    """Points (n, 3) of ``face``'s surface at ``uv`` (n, 2): by its numpy copy in OCCT's
    parameters (:func:`.face_region.exact_embedding`), else by OCCT point by point. The
    parameters are OCCT's projections', which on periodic surfaces may lie outside the
    first period: the analytic copies are periodic themselves, a periodic B-spline's copy
    is not (OCCT evaluates it)."""
    surf = BRepAdaptor_Surface(face)
    if surf.GetType() != GeomAbs_BSplineSurface or not (surf.IsUPeriodic() or surf.IsVPeriodic()):
        try:
            return exact_embedding(face).evaluate(uv)
        except CadError:
            pass
    return np.array([surf.Value(u, v).XYZ().Coord() for u, v in uv.tolist()]).reshape(-1, 3)


def _quadrature(face: Any) -> tuple[Array, Array, Array]:
    """Points on ``face`` (n, 3), its outward unit normals there (n, 3) and area weights
    (n,): the three edge midpoints of each triangle of a triangulation in the face's
    parameters (exact for quadratics in the parameters), weighted by the surface's area
    element."""
    u0, u1, v0, v1 = uv_bounds(face)
    surf = BRepAdaptor_Surface(face)
    extent = max(
        surf.Value(u0, v0).Distance(surf.Value(u1, v1)),
        surf.Value(u0, v1).Distance(surf.Value(u1, v0)),
    )
    copy = TopoDS.Face(BRepBuilderAPI_Copy(face, True, False).Shape())
    BRepMesh_IncrementalMesh(copy, max(DEFLECTION * extent, 1e-9), False, 0.1, True)
    tri = BRep_Tool.Triangulation_s(copy, TopLoc_Location())
    if tri is None:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    uv = np.array([tri.UVNode(i).Coord() for i in range(1, tri.NbNodes() + 1)])
    idx = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)]) - 1
    a, b, c = uv[idx[:, 0]], uv[idx[:, 1]], uv[idx[:, 2]]
    area_uv = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (c - a)[:, 0] * (b - a)[:, 1])
    mids = np.concatenate([0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)])
    share = np.tile(area_uv / 3.0, 3)
    emb = exact_embedding(face)  # (OCCT's parameters, so the triangulation's apply)
    pts = emb.evaluate(mids)
    d = emb.jacobian(mids)
    cross = np.cross(d[:, :, 0], d[:, :, 1])
    jac = np.linalg.norm(cross, axis=1)
    normals = cross / np.where(jac > 0.0, jac, 1.0)[:, None]
    if face.Orientation() == TopAbs_REVERSED:
        normals = -normals
    return pts, normals, share * jac
