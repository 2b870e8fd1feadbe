"""Topology maps of a solid and the numerical tangency test along its edges.

Indices are 0-based: face ``i`` is entry ``i + 1`` of ``face_map`` (an OCCT
``TopTools_IndexedMapOfShape``), likewise edges and vertices. Stored continuity flags are
not trusted: two faces are tangent along an edge when their outward normals, evaluated on
both faces at samples along the edge (through each face's pcurve), differ by less than a
named angle (:data:`medax.tolerances.TANGENT_ANGLE`, radians).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
from OCP.collections import IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher
from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as IMap
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec, gp_Vec2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS

from medax import tolerances
from medax.geometry._types import FloatArray

#: samples per edge for the tangency test (interior points, ends excluded)
TANGENCY_SAMPLES = 5


@dataclass(frozen=True)
class Topology:
    """Indexed maps of a solid and its incidence, all as 0-based index tuples.

    ``edge_faces[j]`` the distinct faces containing edge ``j`` (1 for a seam or free edge);
    ``edge_vertices[j]`` its vertices; ``face_edges[i]`` the distinct edges of face ``i``;
    ``degenerate[j]`` whether edge ``j`` is degenerate (a pole: no 3-D curve).
    """

    shape: Any
    face_map: Any
    edge_map: Any
    vertex_map: Any
    edge_faces: tuple[tuple[int, ...], ...]
    edge_vertices: tuple[tuple[int, ...], ...]
    face_edges: tuple[tuple[int, ...], ...]
    degenerate: tuple[bool, ...]

    @property
    def n_faces(self) -> int:
        return int(self.face_map.Extent())

    @property
    def n_edges(self) -> int:
        return int(self.edge_map.Extent())

    def face(self, i: int) -> Any:
        return TopoDS.Face(self.face_map.FindKey(i + 1))

    def edge(self, j: int) -> Any:
        return TopoDS.Edge(self.edge_map.FindKey(j + 1))

    def edge_index(self, edge: Any) -> int:
        return int(self.edge_map.FindIndex(edge)) - 1

    def face_index(self, face: Any) -> int:
        return int(self.face_map.FindIndex(face)) - 1


def build_topology(shape: Any) -> Topology:
    """Face, edge and vertex maps of ``shape`` and their incidence."""
    fmap, emap, vmap = IMap(), IMap(), IMap()
    TopExp.MapShapes_s(shape, TopAbs_FACE, fmap)
    TopExp.MapShapes_s(shape, TopAbs_EDGE, emap)
    TopExp.MapShapes_s(shape, TopAbs_VERTEX, vmap)
    ef = IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher()
    TopExp.MapShapesAndUniqueAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ef)
    n_e = emap.Extent()
    edge_faces: list[tuple[int, ...]] = []
    edge_vertices: list[tuple[int, ...]] = []
    degenerate: list[bool] = []
    face_edges: list[list[int]] = [[] for _ in range(fmap.Extent())]
    for j in range(n_e):
        e = TopoDS.Edge(emap.FindKey(j + 1))
        faces: list[int] = []
        if ef.Contains(e):
            for f in _shapes(ef.FindFromKey(e)):
                i = fmap.FindIndex(f) - 1
                if i >= 0 and i not in faces:
                    faces.append(i)
        edge_faces.append(tuple(sorted(faces)))
        for i in faces:
            face_edges[i].append(j)
        v0, v1 = TopExp.FirstVertex_s(e), TopExp.LastVertex_s(e)
        vs = []
        for v in (v0, v1):
            if not v.IsNull():
                k = vmap.FindIndex(v) - 1
                if k >= 0 and k not in vs:
                    vs.append(k)
        edge_vertices.append(tuple(vs))
        degenerate.append(bool(BRep_Tool.Degenerated_s(e)))
    return Topology(
        shape,
        fmap,
        emap,
        vmap,
        tuple(edge_faces),
        tuple(edge_vertices),
        tuple(tuple(sorted(x)) for x in face_edges),
        tuple(degenerate),
    )


def _shapes(lst: Any) -> list[Any]:
    """The shapes of a ``TopTools_ListOfShape`` (Python iteration over OCP lists is slow:
    about 0.7 ms per list; ``First``/``Last`` cover the usual one or two entries)."""
    n = lst.Size()
    if n == 0:
        return []
    if n == 1:
        return [lst.First()]
    if n == 2:
        return [lst.First(), lst.Last()]
    return list(lst)


# ---- sampling helpers ---------------------------------------------------------------------
def edge_params(edge: Any, n: int) -> FloatArray:
    """``n`` interior parameters of ``edge``, uniformly spaced, ends excluded, shape (n,)."""
    c = BRepAdaptor_Curve(edge)
    a, b = c.FirstParameter(), c.LastParameter()
    s = (np.arange(n) + 0.5) / n
    return a + s * (b - a)


def edge_points(edge: Any, t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Points (n, 3) and first derivatives (n, 3) of ``edge`` at its parameters ``t`` (n,)."""
    c = BRepAdaptor_Curve(edge)
    pts = np.empty((len(t), 3))
    der = np.empty((len(t), 3))
    p, v = gp_Pnt(), gp_Vec()
    for k, tk in enumerate(t):
        c.D1(float(tk), p, v)
        pts[k] = (p.X(), p.Y(), p.Z())
        der[k] = (v.X(), v.Y(), v.Z())
    return pts, der


def edge_uv(edge: Any, face: Any, t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Parameters (n, 2) and their derivatives (n, 2) of ``edge`` on ``face`` (its pcurve,
    for the edge's orientation in the face) at edge parameters ``t`` (n,)."""
    c = BRepAdaptor_Curve2d(edge, face)
    uv = np.empty((len(t), 2))
    duv = np.empty((len(t), 2))
    p, v = gp_Pnt2d(), gp_Vec2d()
    for k, tk in enumerate(t):
        c.D1(float(tk), p, v)
        uv[k] = (p.X(), p.Y())
        duv[k] = (v.X(), v.Y())
    return uv, duv


def face_normals(face: Any, uv: FloatArray, surf: Any = None) -> FloatArray:
    """Outward unit normals (n, 3) of ``face`` at parameters ``uv`` (n, 2); rows are NaN
    where the normal is undefined (poles, apexes)."""
    s = surf if surf is not None else BRepAdaptor_Surface(face, False)
    d = np.empty((len(uv), 2, 3))
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    for k, (u, v) in enumerate(uv):
        s.D1(float(u), float(v), p, du, dv)
        d[k, 0] = (du.X(), du.Y(), du.Z())
        d[k, 1] = (dv.X(), dv.Y(), dv.Z())
    a, b = d[:, 0], d[:, 1]
    n = np.column_stack(
        (
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        )
    )
    norm = np.linalg.norm(n, axis=1)
    scale = np.linalg.norm(d[:, 0], axis=1) * np.linalg.norm(d[:, 1], axis=1)
    good = norm > 1e-14 * np.maximum(scale, 1e-300)
    out = np.full((len(uv), 3), np.nan)
    out[good] = n[good] / norm[good, None]
    if face.Orientation() == TopAbs_REVERSED:
        out = -out
    return out


def edge_angles(
    topo: Topology,
    j: int,
    samples: int = TANGENCY_SAMPLES,
    plane_normals: dict[int, FloatArray] | None = None,
    adaptors: dict[int, Any] | None = None,
) -> float:
    """Largest angle (radians) between the outward normals of the two faces of edge ``j``
    over ``samples`` interior points; 0 for a seam or degenerate edge, pi for a free edge.
    ``plane_normals`` (face index -> outward unit normal (3,)) short-cuts planar faces."""
    faces = topo.edge_faces[j]
    if topo.degenerate[j]:
        return 0.0
    if len(faces) == 1:
        f = topo.face(faces[0])
        return 0.0 if BRep_Tool.IsClosed_s(topo.edge(j), f) else float(np.pi)
    if len(faces) != 2:
        return float(np.pi)  # non-manifold edge: never tangent
    pn = plane_normals or {}
    if faces[0] in pn and faces[1] in pn:
        cos = float(pn[faces[0]] @ pn[faces[1]])
        return float(np.arccos(np.clip(cos, -1.0, 1.0)))
    e = topo.edge(j)
    t = edge_params(e, samples)
    normals = []
    for i in faces:
        if i in pn:
            normals.append(np.broadcast_to(pn[i], (samples, 3)))
            continue
        f = topo.face(i)
        uv, _ = edge_uv(e, f, t)
        normals.append(face_normals(f, uv, None if adaptors is None else adaptors.get(i)))
    cosv = np.sum(normals[0] * normals[1], axis=1)
    ok = np.isfinite(cosv)
    if not np.any(ok):
        return float(np.pi)
    return float(np.max(np.arccos(np.clip(cosv[ok], -1.0, 1.0))))


def tangency(
    topo: Topology, angle_tol: float = tolerances.TANGENT_ANGLE
) -> tuple[np.ndarray, FloatArray]:
    """Tangency flags (n_edges,) bool and largest normal angles (n_edges,) in radians."""
    from OCP.GeomAbs import GeomAbs_Plane

    planes: dict[int, FloatArray] = {}
    adaptors: dict[int, Any] = {}
    for i in range(topo.n_faces):
        f = topo.face(i)
        s = BRepAdaptor_Surface(f, False)
        adaptors[i] = s
        if s.GetType() == GeomAbs_Plane:
            n = face_normals(f, np.zeros((1, 2)), s)[0]
            if np.all(np.isfinite(n)):
                planes[i] = n
    angles = np.array(
        [edge_angles(topo, j, plane_normals=planes, adaptors=adaptors) for j in range(topo.n_edges)]
    )
    return angles < angle_tol, angles
