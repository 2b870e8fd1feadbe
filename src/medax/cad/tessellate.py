"""Triangles and edge polylines of a solid as numpy arrays, for the 3D view.

``BRepMesh_IncrementalMesh`` meshes every face; each face's triangulation is read back with
its location applied and its triangles oriented outward.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location

from medax.cad.model import Classification
from medax.cad.topology import edge_points
from medax.errors import CadError
from medax.geometry._types import FloatArray


@dataclass(frozen=True)
class FaceMesh:
    """Triangles of face ``index``: ``points`` (n, 3), ``triangles`` (m, 3) int (outward)."""

    index: int
    points: FloatArray
    triangles: np.ndarray


def mesh_faces(c: Classification, rel_deflection: float = 2e-3) -> list[FaceMesh]:
    """Triangulate every face of ``c`` (deflection relative to the part's size)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(c.shape, box)
    lo, hi = box.CornerMin(), box.CornerMax()
    diag = float(np.linalg.norm([hi.X() - lo.X(), hi.Y() - lo.Y(), hi.Z() - lo.Z()]))
    try:
        BRepMesh_IncrementalMesh(c.shape, rel_deflection * diag, False, 0.3, False)
    except Exception as err:
        raise CadError(f"{c.source or 'shape'}: meshing for the view failed ({err})") from err
    out = []
    for f in c.faces:
        face = c.face(f.index)
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, loc)
        if tri is None or tri.NbTriangles() == 0:
            continue
        trsf = loc.Transformation()
        pts = np.empty((tri.NbNodes(), 3))
        for k in range(tri.NbNodes()):
            p = tri.Node(k + 1).Transformed(trsf)
            pts[k] = (p.X(), p.Y(), p.Z())
        tris = np.empty((tri.NbTriangles(), 3), dtype=np.int64)
        for k in range(tri.NbTriangles()):
            a, b, d = tri.Triangle(k + 1).Get()
            tris[k] = (a - 1, b - 1, d - 1)
        if face.Orientation() == TopAbs_REVERSED:
            tris = tris[:, ::-1]
        out.append(FaceMesh(f.index, pts, tris))
    return out


def edge_polylines(c: Classification, n: int = 24) -> list[FloatArray]:
    """Each non-degenerate edge sampled at ``n`` points, (n, 3) each (ends included)."""
    out = []
    for e in c.edges:
        edge = c.edge(e.index)
        if BRep_Tool.Degenerated_s(edge):
            continue
        ad = BRepAdaptor_Curve(edge)
        t = np.linspace(ad.FirstParameter(), ad.LastParameter(), n)
        pts, _ = edge_points(edge, t)
        out.append(pts)
    return out
