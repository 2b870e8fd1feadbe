"""One conforming quad surface mesh of a CAD solid: the medial grid on its 4-sided faces,
gmsh's quads on the others, the part's edge nodes shared by both.

Steps ([mesh_part][medax.cad.part_mesh.mesh_part]):

1. Each face is 4-sided or not (``medax.cad.face_region.face_sides``; the wire's two
   runs along a seam count as two sides); 4-sided ones become Regions on their surfaces
   (``medax.cad.face_region.side_region``), those with a seam planar Regions of their
   pcurves scaled to lengths, mapped onto the surface after meshing
   (``medax.cad.face_region.seam_region``: in space the seam's two sides are one curve,
   so distances to them cannot tell them apart).
2. Division counts per edge from the size, equal on opposite sides of every structured face
   across the part (``medax.cad.edge_counts``); faces where they conflict are meshed by
   gmsh instead.
3. Nodes of every edge at equal arc length on its exact curve, one node per vertex
   (``medax.cad.edge_nodes``; ``medax.cad.shared_nodes.SharedNodes``): the only
   nodes any face puts on an edge.
4. Structured faces: [mesh_region][medax.mesh_region] with those counts (and, on sides made
   of several edges, boundary fractions that put nodes on the vertices inside them);
   its boundary nodes are replaced by the edge nodes (they agree to the mesher's tolerance,
   checked). A face the medial grid cannot mesh is handed to gmsh, with the reason kept.
5. Other faces: gmsh, on the same edge nodes (``medax.cad.gmsh_faces``).
6. Every face's quads are turned to the outward normal of the face and checked corner by
   corner against it (``medax.cad.quad_orientation``).
7. A face nothing meshes (e.g. its fixed boundary nodes too coarse for a narrow gap between
   two of its edges) has its edges' counts doubled, as lower bounds propagated like the
   others, and the part is meshed again; faces whose edges keep their counts keep their
   meshes. After ``REFINE_ROUNDS`` such rounds the run fails with the face's index.

The result holds the quads with their CAD face, and each edge's nodes as line elements
with their CAD edge, for the named groups of the writers (``medax.mesh.grouped_export``).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.TopAbs import TopAbs_FORWARD, TopAbs_REVERSED
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS

from medax._progress import log_progress
from medax.cad.edge_counts import division_counts
from medax.cad.edge_nodes import edge_curve, equal_arc_nodes
from medax.cad.face_region import (
    Development,
    face_sides,
    has_seam,
    seam_region,
    side_region,
)
from medax.cad.gmsh_faces import FaceJob, GmshFace, GmshFaces
from medax.cad.quad_orientation import orient
from medax.cad.shared_nodes import SharedNodes
from medax.cad.topology import build_topology
from medax.errors import CadError, InputError, MedaxError, MeshError
from medax.geometry._types import FloatArray, IntArray
from medax.geometry.embedded_curve import EmbeddedCurve
from medax.geometry.region import Region
from medax.mesh.arclength import arclength_at
from medax.mesh.gmsh_session import gmsh_session
from medax.mesh.grid import boundary_indices, structured_quads
from medax.mesh.mesher import mesh_region

log = logging.getLogger(__name__)

#: structured boundary nodes may differ from the edge nodes by this much (x diagonal)
BOUNDARY_MATCH = 1e-5
#: fewest divisions of a closed edge (a full circle): halved for gmsh's subdivision it still
#: has 3 segments
MIN_CLOSED_COUNT = 6
#: points closer than this (x diagonal) are the same point when matching gmsh's entities
MATCH_TOL = 1e-6
#: rounds in which a face nothing meshes (e.g. fixed boundary nodes too coarse for a narrow
#: gap between its edges) has its edges' counts doubled, as lower bounds propagated like the
#: others, before the run fails
REFINE_ROUNDS = 3

#: a 4-sided face's region, its sides' oriented edges, and for a face with a seam the map of
#: the (planar) region onto the surface (None: the region is on the surface)
_FaceRegion = tuple[Region, list[list[Any]], Development | None]


@dataclass(frozen=True)
class FaceMeshInfo:
    """How one face of the part was meshed.

    Attributes
    ----------
    face : int
        The CAD face index (OCCT's face map order, 0-based).
    kind : str
        ``"structured"`` (the medial grid) or ``"gmsh"``.
    start, stop : int
        The face's quads are ``quads[start:stop]`` of the part mesh.
    time_s : float
        Time spent on the face (s).
    divisions : tuple of int or None
        ``(n1, n2)`` of a structured face, else None.
    why : str
        For a gmsh face, the reason it is not structured.
    """

    face: int
    kind: str
    start: int
    stop: int
    time_s: float
    divisions: tuple[int, int] | None = None
    why: str = ""


@dataclass(frozen=True)
class PartMesh:
    """A conforming quad mesh of a part's faces.

    Faces share the nodes of their common edges. Lengths are in the part's unit.

    Attributes
    ----------
    points : ndarray
        Nodes (n, 3).
    quads : ndarray
        Node indices (m, 4), counter-clockwise about the outward normal.
    quad_face : ndarray
        The CAD face of each quad (m,).
    lines : ndarray
        The edge segments (k, 2), node indices.
    line_edge : ndarray
        The CAD edge of each segment (k,).
    edge_counts : ndarray
        Divisions per CAD edge (0: not meshed).
    faces : tuple of FaceMeshInfo
        How each face was meshed ([FaceMeshInfo][medax.cad.part_mesh.FaceMeshInfo]).
    diagonal : float
        The part's bounding-box diagonal.
    conflicts : dict of int to str
        Face -> why its counts did not allow the structured grid.
    time_s : float
        Wall time of the meshing (s).
    """

    points: FloatArray
    quads: IntArray
    quad_face: IntArray
    lines: IntArray
    line_edge: IntArray
    edge_counts: IntArray
    faces: tuple[FaceMeshInfo, ...]
    diagonal: float
    conflicts: dict[int, str] = field(default_factory=dict)
    time_s: float = 0.0

    @property
    def structured_faces(self) -> tuple[int, ...]:
        """The faces meshed by the medial grid."""
        return tuple(f.face for f in self.faces if f.kind == "structured")

    @property
    def gmsh_faces(self) -> tuple[int, ...]:
        """The faces meshed by gmsh."""
        return tuple(f.face for f in self.faces if f.kind == "gmsh")

    def __repr__(self) -> str:
        return (
            f"PartMesh({len(self.quads)} quads, {len(self.points)} nodes, "
            f"{len(self.structured_faces)}/{len(self.faces)} faces structured, {self.time_s:.2f} s)"
        )


class _Nodes:
    """The growing node table."""

    def __init__(self) -> None:
        self.blocks: list[FloatArray] = []
        self.n = 0

    def add(self, pts: FloatArray) -> IntArray:
        ids = np.arange(self.n, self.n + len(pts), dtype=np.int64)
        self.blocks.append(np.asarray(pts, dtype=np.float64).reshape(-1, 3))
        self.n += len(pts)
        return ids

    def array(self) -> FloatArray:
        return np.concatenate(self.blocks) if self.blocks else np.zeros((0, 3))


def surface_area(shape: Any) -> float:
    """The boundary area of ``shape`` (length unit squared), by OCCT's default integrator:
    enough to size a mesh."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, props)
    return float(props.Mass())


def part_diagonal(shape: Any) -> float:
    """The diagonal of ``shape``'s bounding box (model units)."""
    from OCP.Bnd import Bnd_Box  # noqa: PLC0415
    from OCP.BRepBndLib import BRepBndLib  # noqa: PLC0415

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    lo, hi = box.CornerMin(), box.CornerMax()
    return float(np.linalg.norm([hi.X() - lo.X(), hi.Y() - lo.Y(), hi.Z() - lo.Z()]))


def mesh_part(
    shape: Any,
    size: float,
    faces: Sequence[int] | None = None,
    structured: bool = True,
    progress: Callable[[str], None] | None = None,
) -> PartMesh:
    """Mesh the faces of a solid with conforming quads.

    The medial grid meshes the 4-sided faces, gmsh the others, on shared edge nodes (the
    steps are in [medax.cad.part_mesh][medax.cad.part_mesh]). Never returns a partial mesh.

    Parameters
    ----------
    shape : TopoDS_Shape
        The solid (not modified).
    size : float
        Target quad edge length (model units), at least 1e-6 x the part's diagonal.
    faces : sequence of int, optional
        The face indices to mesh, in OCCT's face map order (default: all).
    structured : bool
        ``False`` meshes every face with gmsh (for comparison).
    progress : callable, optional
        Called with one message per stage.

    Returns
    -------
    PartMesh
        The mesh ([PartMesh][medax.cad.part_mesh.PartMesh]).

    Raises
    ------
    InputError
        ``size`` not positive or too small, or a face index that does not exist.
    MeshError
        A face cannot be meshed (named), even with its edges divided finer.
    """
    t0 = time.perf_counter()
    say = progress or (lambda msg: log.info(msg))
    topo = build_topology(shape)
    diag = part_diagonal(shape)
    if not (np.isfinite(size) and size > 0.0):
        raise InputError(f"size must be positive, got {size}")
    sel = list(range(topo.n_faces)) if faces is None else sorted(set(faces))
    bad = [i for i in sel if not 0 <= i < topo.n_faces]
    if bad:
        raise InputError(f"face {bad[0]} does not exist (the part has {topo.n_faces} faces)")
    if size < 1e-6 * diag:
        raise InputError(f"size {size:g} is below 1e-6 x the part's diagonal ({diag:.4g})")

    # 1. 4-sided faces and their regions
    regions: dict[int, _FaceRegion] = {}
    why: dict[int, str] = {}
    for k, i in enumerate(sel):
        log_progress(log, "faces examined for 4 sides", k + 1, len(sel))
        f = topo.face(i)
        if not structured:
            why[i] = "structured grid not asked for"
            continue
        try:
            sides = face_sides(f, seams=True)
            if len(sides) != 4:
                why[i] = f"{len(sides)} sides"
                continue
            if has_seam(f):
                regions[i] = seam_region(f, sides, f"face {i}")
            else:
                regions[i] = (*side_region(f, sides, f"face {i}"), None)
        except CadError as err:
            why[i] = str(err)
    say(f"{len(sel)} faces, {len(regions)} 4-sided")

    # 2-5, in rounds: a face nothing meshes gets its edges divided twice finer, and the part
    # is meshed again (the faces whose edges kept their counts keep their meshes)
    edges = sorted({j for i in sel for j in topo.face_edges[i]})
    curves = {j: edge_curve(topo.edge(j)) for j in edges if not topo.degenerate[j]}
    lengths = np.zeros(topo.n_edges)
    for j, c in curves.items():
        lengths[j] = c.length()
    closed = np.array([len(v) == 1 for v in topo.edge_vertices], dtype=bool)
    floor = np.where(closed, MIN_CLOSED_COUNT, 2).astype(np.int64)
    part = _Part(topo, sel, edges, curves, lengths, size, diag, say)
    cache: dict[int, _FaceResult] = {}
    for rnd in range(REFINE_ROUNDS + 1):
        try:
            mesh = part.mesh(dict(regions), dict(why), floor, cache, t0)
            break
        except _FaceFailed as err:
            if rnd == REFINE_ROUNDS:
                raise MeshError(
                    f"{err}; also with its edges divided {2**rnd} times finer" if rnd else str(err)
                ) from None
            counts = err.counts
            for j in topo.face_edges[err.face]:
                if j in curves:
                    floor[j] = max(int(floor[j]), 2 * int(counts[j]))
            say(f"{err}; its edges divided twice finer, meshing again")
    _check(mesh)
    s = len(mesh.structured_faces)
    say(f"{len(mesh.quads)} quads, {len(mesh.points)} nodes; {s} faces structured, "
        f"{len(sel) - s} by gmsh; {mesh.time_s:.2f} s")  # fmt: skip
    return mesh


class _FaceFailed(MeshError):
    """Nothing meshed face ``face`` at the edge counts ``counts``."""

    def __init__(self, face: int, message: str, counts: IntArray) -> None:
        super().__init__(message)
        self.face = face
        self.counts = counts


@dataclass(frozen=True)
class _FaceResult:
    """A face's mesh, kept across rounds while its edges keep their counts ``key``: local
    quads (oriented), points, and for each local node the edge ``edge`` it lies on (-1: a
    vertex, -2: inside) and its ``pos``ition on that edge (or the vertex index)."""

    key: tuple[int, ...]
    quads: IntArray
    points: FloatArray
    edge: IntArray
    pos: IntArray
    kind: str
    divisions: tuple[int, int] | None
    why: str
    time_s: float


@dataclass
class _Part:
    """What stays the same across the rounds of [mesh_part][medax.cad.part_mesh.mesh_part]."""

    topo: Any
    sel: list[int]
    edges: list[int]
    curves: dict[int, Any]
    lengths: FloatArray
    size: float
    diag: float
    say: Callable[[str], None]

    def mesh(
        self,
        regions: dict[int, _FaceRegion],
        why: dict[int, str],
        floor: IntArray,
        cache: dict[int, _FaceResult],
        t0: float,
    ) -> PartMesh:
        """One round: counts with lower bounds ``floor``, edge nodes, faces (from ``cache``
        where their edges' counts are the same); ``_FaceFailed`` for a face nothing
        meshes."""
        topo, sel, curves, diag, say = self.topo, self.sel, self.curves, self.diag, self.say
        # 2. counts
        four = {
            i: [[topo.edge_index(e) for e in side] for side in sides]
            for i, (_, sides, _) in regions.items()
        }
        counts = division_counts(self.lengths, list(curves), four, self.size, floor)
        for i, reason in counts.conflicts.items():
            why[i] = f"division counts conflict: {reason}"
            regions.pop(i)
        if counts.conflicts:
            say(f"{len(counts.conflicts)} faces with conflicting counts meshed by gmsh")

        # 3. vertex and edge nodes
        nodes = _Nodes()
        shared = self._shared_nodes(counts.counts, nodes)
        say(f"{len(curves)} edges, {int(counts.counts.sum())} divisions")

        # 4-5. faces
        quads: list[IntArray] = []
        quad_face: list[IntArray] = []
        infos: list[FaceMeshInfo] = []
        n_quads = 0
        with gmsh_session(), GmshFaces(shared, self._job(shared)) as by_gmsh:
            for k, i in enumerate(sel):
                key = tuple(int(counts.counts[j]) for j in topo.face_edges[i])
                res = cache.get(i)
                if res is None or res.key != key:
                    res = self._face(i, key, regions, why, counts.counts, shared, by_gmsh)
                    cache[i] = res
                    if k % 10 == 9 or res.time_s > 2.0:
                        say(f"face {k + 1}/{len(sel)} ({i}: {res.kind}, {len(res.quads)} quads, "
                            f"{res.time_s:.2f} s)")  # fmt: skip
                gid = np.full(len(res.points), -1, dtype=np.int64)
                on_v, on_e = res.edge == -1, res.edge >= 0
                gid[on_v] = shared.vert_ids[res.pos[on_v]]
                for j in np.unique(res.edge[on_e]).tolist():
                    at = res.edge == j
                    gid[at] = shared.edge_ids[j][res.pos[at]]
                inner = res.edge == -2
                gid[inner] = nodes.add(res.points[inner])
                gq = gid[res.quads]
                quads.append(gq)
                quad_face.append(np.full(len(gq), i, dtype=np.int64))
                infos.append(FaceMeshInfo(i, res.kind, n_quads, n_quads + len(gq), res.time_s,
                                          res.divisions, res.why))  # fmt: skip
                n_quads += len(gq)

        points = nodes.array()
        ids_of = shared.edge_ids
        lines = [np.column_stack((ids[:-1], ids[1:])) for ids in ids_of.values()]
        line_edge = [np.full(len(ids) - 1, j, dtype=np.int64) for j, ids in ids_of.items()]
        return PartMesh(
            points,
            np.concatenate(quads) if quads else np.zeros((0, 4), dtype=np.int64),
            np.concatenate(quad_face) if quad_face else np.zeros(0, dtype=np.int64),
            np.concatenate(lines) if lines else np.zeros((0, 2), dtype=np.int64),
            np.concatenate(line_edge) if line_edge else np.zeros(0, dtype=np.int64),
            counts.counts,
            tuple(infos),
            diag,
            dict(counts.conflicts),
            time.perf_counter() - t0,
        )

    def _shared_nodes(self, counts: IntArray, nodes: _Nodes) -> SharedNodes:
        """The round's vertex and edge nodes (edge ``j`` in ``counts[j]`` equal arc lengths),
        added to ``nodes``."""
        topo = self.topo
        vmap = topo.vertex_map
        vert_ids = np.full(vmap.Extent(), -1, dtype=np.int64)
        vert_pts = np.zeros((vmap.Extent(), 3))
        used_v = sorted({k for j in self.edges for k in topo.edge_vertices[j]})
        for k in used_v:
            p = BRep_Tool.Pnt_s(TopoDS.Vertex(vmap.FindKey(k + 1)))
            vert_pts[k] = (p.X(), p.Y(), p.Z())
        vert_ids[used_v] = nodes.add(vert_pts[used_v])
        edge_ids: dict[int, IntArray] = {}
        edge_pts: dict[int, FloatArray] = {}
        edge_mid: dict[int, FloatArray] = {}
        for j, c in self.curves.items():
            e = TopoDS.Edge(topo.edge(j).Oriented(TopAbs_FORWARD))
            v0 = vmap.FindIndex(TopExp.FirstVertex_s(e, True)) - 1
            v1 = vmap.FindIndex(TopExp.LastVertex_s(e, True)) - 1
            pts = equal_arc_nodes(c, int(counts[j]))
            pts[0], pts[-1] = vert_pts[v0], vert_pts[v1]
            edge_pts[j] = pts
            edge_ids[j] = np.concatenate(([vert_ids[v0]], nodes.add(pts[1:-1]), [vert_ids[v1]]))
            edge_mid[j] = np.asarray(c.evaluate(np.array([0.5])))[0]
        # which edge (-1: vertex) and position each boundary node has
        owner = np.full(nodes.n, -2, dtype=np.int64)
        where = np.zeros(nodes.n, dtype=np.int64)
        owner[vert_ids[used_v]] = -1
        where[vert_ids[used_v]] = used_v
        for j, ids in edge_ids.items():
            owner[ids[1:-1]] = j
            where[ids[1:-1]] = np.arange(1, len(ids) - 1)
        return SharedNodes(
            edge_ids, edge_pts, edge_mid, vert_ids, vert_pts, owner, where, self.size,
            MATCH_TOL * self.diag,
        )  # fmt: skip

    def _job(self, shared: SharedNodes) -> Callable[[int], FaceJob]:
        """What gmsh needs to mesh face ``i`` on the shared nodes: the face, its edges with
        nodes, its vertices, and the check of its quads against the face normal."""
        topo = self.topo

        def job(i: int) -> FaceJob:
            face = topo.face(i)

            def check(m: GmshFace) -> GmshFace | str:
                q, problem = orient(face, m.quads, m.uv, m.points)
                return problem if problem is not None else replace(m, quads=q)

            own = [j for j in topo.face_edges[i] if j in shared.edge_ids]
            vs = sorted({k for j in topo.face_edges[i] for k in topo.edge_vertices[j]})
            return FaceJob(face, own, vs, check)

        return job

    def _face(
        self,
        i: int,
        key: tuple[int, ...],
        regions: dict[int, _FaceRegion],
        why: dict[int, str],
        counts: IntArray,
        shared: SharedNodes,
        by_gmsh: GmshFaces,
    ) -> _FaceResult:
        """Face ``i`` meshed: the medial grid if it is 4-sided (gmsh if that fails), else
        gmsh; ``_FaceFailed`` when nothing meshes it."""
        topo, diag = self.topo, self.diag
        tf = time.perf_counter()
        f = topo.face(i)
        q: IntArray | None = None
        divisions = None
        if i in regions:
            region, _, flat = regions[i]
            try:
                q, uv, pts, gid, divisions = _structured(
                    regions[i], topo, shared, self.lengths, diag
                )
                # (turned to the outward normal and checked once, on the region's surface)
                surface = region.embedding if flat is None else flat.surface
                q, problem = orient(f, q, uv, pts, surface)
                if problem is not None:
                    raise MeshError(problem)
            except MedaxError as err:
                q, divisions = None, None
                why[i] = f"structured grid failed: {err}"
                self.say(f"face {i}: {why[i]}; meshed by gmsh")
        try:
            if q is None:  # (its quads turned to the outward normal and checked by the job)
                gm = by_gmsh.mesh(i)
                q, uv, pts, gid = gm.quads, gm.uv, gm.points, gm.node_id
        except MeshError as err:
            raise _FaceFailed(i, str(err), counts) from None
        edge = np.full(len(pts), -2, dtype=np.int64)
        pos = np.zeros(len(pts), dtype=np.int64)
        on = gid >= 0
        edge[on], pos[on] = shared.owner[gid[on]], shared.where[gid[on]]
        kind = "structured" if divisions is not None else "gmsh"
        dt = time.perf_counter() - tf
        return _FaceResult(key, q, pts, edge, pos, kind, divisions, why.get(i, ""), dt)


def _side_ids(
    side: list[Any], topo: Any, shared: SharedNodes, lengths: FloatArray
) -> tuple[IntArray, FloatArray, FloatArray]:
    """Node ids and points along a side (its edges in the side's direction, joints once),
    and the arc-length fractions of its nodes (each edge in equal arc lengths)."""
    ids: list[IntArray] = []
    pts: list[FloatArray] = []
    lens: list[FloatArray] = []
    for e in side:
        j = topo.edge_index(e)
        a, p = shared.edge_ids[j], shared.edge_pts[j]
        if e.Orientation() == TopAbs_REVERSED:
            a, p = a[::-1], p[::-1]
        lens.append(np.full(len(a) - 1, lengths[j] / (len(a) - 1)))
        ids.append(a if not ids else a[1:])
        pts.append(p if not pts else p[1:])
    step = np.concatenate(lens)
    fr = np.concatenate(([0.0], np.cumsum(step)))
    fr /= fr[-1]
    fr[-1] = 1.0
    return np.concatenate(ids), np.concatenate(pts), fr


def _structured(
    rs: _FaceRegion,
    topo: Any,
    shared: SharedNodes,
    lengths: FloatArray,
    diag: float,
) -> tuple[IntArray, FloatArray, FloatArray, IntArray, tuple[int, int]]:
    """The medial grid of a 4-sided face on the part's edge nodes: local quads, parameters,
    points, part node ids of the boundary nodes (-1 inside) and the divisions."""
    region, sides, flat = rs
    per_side = [_side_ids(s, topo, shared, lengths) for s in sides]
    n1, n2 = len(per_side[0][0]) - 1, len(per_side[1][0]) - 1
    if (len(per_side[2][0]) - 1, len(per_side[3][0]) - 1) != (n1, n2):
        raise MeshError(f"{region.name}: opposite sides have different counts")  # pragma: no cover
    if flat is not None:
        fractions: list[FloatArray] | None = [
            _flat_fractions(region, k, flat, per_side[k][1]) for k in range(4)
        ]
    else:
        chained = any(len(s) > 1 for s in sides)
        fractions = [p[2] for p in per_side] if chained else None
    mesh = mesh_region(region, divisions=(n1, n2), fractions=fractions, smooth=False)
    uv = mesh.params if flat is None else flat.uv(mesh.params)
    pts = np.array(mesh.points if flat is None else flat.points(mesh.params), dtype=np.float64)
    gid = np.full(len(pts), -1, dtype=np.int64)
    for k, idx in enumerate(boundary_indices(n1, n2)):
        ids, ours, _ = per_side[k]
        off = float(np.max(np.linalg.norm(pts[idx] - ours, axis=1)))
        if off > BOUNDARY_MATCH * diag:
            raise MeshError(
                f"{region.name}: its grid's nodes on side {k} are {off:.3g} from the edge nodes"
            )
        gid[idx] = ids
        pts[idx] = ours
    return structured_quads(n1, n2), uv, pts, gid, (n1, n2)


def _flat_fractions(region: Region, k: int, flat: Development, nodes: FloatArray) -> FloatArray:
    """Arc-length fractions (n + 1,) along side ``k`` of the planar ``region`` of a seam
    face at which its points map onto the edge ``nodes`` (n + 1, 3): the planar lengths are
    not those in space where the surface stretches along the side (a revolved B-spline or
    ellipse), so the side's nodes are found on the side by their points in space."""
    side = region.sides[k]
    t = EmbeddedCurve(side, flat).closest(nodes[1:-1]).t
    fr = np.concatenate(([0.0], arclength_at(side, t) / arclength_at(side, np.ones(1))[0], [1.0]))
    if not np.all(np.diff(fr) > 0.0):
        raise MeshError(f"{region.name}: the edge nodes of side {k} do not run along it")
    return fr


def _check(mesh: PartMesh) -> None:
    """No NaN, no two nodes within 1e-9 x diagonal, no node left out."""
    from scipy.spatial import cKDTree  # noqa: PLC0415

    if not np.all(np.isfinite(mesh.points)):
        raise MeshError("part mesh: a node is not finite")  # pragma: no cover
    pairs = cKDTree(mesh.points).query_pairs(1e-9 * mesh.diagonal, output_type="ndarray")
    if len(pairs):
        a = mesh.points[pairs[0, 0]]
        raise MeshError(f"part mesh: {len(pairs)} pairs of duplicate nodes (first at {a.tolist()})")
    used = np.zeros(len(mesh.points), dtype=bool)
    used[mesh.quads.ravel()] = True
    if not used.all():
        raise MeshError(f"part mesh: {int((~used).sum())} nodes in no quad")  # pragma: no cover
