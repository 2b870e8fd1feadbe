"""Triangles of each face of a solid, as numpy arrays, for plots (no OCP outside cad/)."""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import Array, diagonal, shape_map


def face_triangles(shape: Any, rel_deflection: float = 2e-3) -> list[Array]:
    """Per face (face-map order), its triangles ``(m, 3, 3)`` in space (length unit)."""
    BRepMesh_IncrementalMesh(shape, rel_deflection * diagonal(shape), False, 0.3, False)
    fmap = shape_map(shape, TopAbs_FACE)
    out: list[Array] = []
    for i in range(1, fmap.Size() + 1):
        face = TopoDS.Face(fmap.FindKey(i))
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, loc)
        if tri is None:
            out.append(np.zeros((0, 3, 3)))
            continue
        trsf = loc.Transformation()
        nodes = np.array(
            [
                [p.X(), p.Y(), p.Z()]
                for p in (tri.Node(k).Transformed(trsf) for k in range(1, tri.NbNodes() + 1))
            ]
        )
        idx = np.array([tri.Triangle(k).Get() for k in range(1, tri.NbTriangles() + 1)]) - 1
        if face.Orientation() == TopAbs_REVERSED:
            idx = idx[:, ::-1]
        out.append(nodes[idx])
    return out
