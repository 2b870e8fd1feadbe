"""Quad meshes of the faces that are not structured, by gmsh, on the part's edge nodes.

Each face is written alone to a BRep file and meshed in its own gmsh model (so a failure
names its face), each attempt from a fresh gmsh state in a forked worker process that
serves the part's faces one after another (:class:`GmshFaces`: a hang or a crash costs one
attempt, not the run): every curve is made transfinite with the part's division count of its
edge, then Frontal-Delaunay for quads and blossom recombination (``Mesh.Algorithm = 8``,
``Mesh.RecombineAll``). The counts are even, so each face has an even number of boundary
edges; where blossom still leaves triangles, or the caller's check refuses the quads (one
inverted or flat against the face normal), the face is meshed again (:data:`ATTEMPTS`):
quasi-structured quads, Frontal-Delaunay, and both Frontal-Delaunays with half the counts
and every element split into quads (``Mesh.SubdivisionAlgorithm = 1``), which doubles the
boundary divisions back to the part's counts (quasi-structured splits by itself). Faces
with a seam edge skip the quasi-structured attempt: it leaves the seam curve without nodes
or with counts not asked for, or aborts (never a usable mesh on the 56 seam faces of the
benchmark parts), and it is the costliest attempt.
Triangles the recombination leaves in neighbouring pairs (where the pair's one quad would
have a flat or reflex corner, or gmsh's two triangles overlap in a narrow gap) become five
quads each (:func:`pair_triangles`); such a mesh is kept only when no attempt gives quads
alone.

Node sharing is exact by construction: gmsh's nodes on a curve are matched, in order along
it, to the part's nodes of that edge (:mod:`medax.cad.edge_nodes`, equal arc length) and
replaced by them (ids and coordinates; gmsh's own transfinite nodes differ from them by its
arc-length quadrature only, checked against a fraction of the spacing). Curves are matched
to the part's edges by their points at the middle parameter (gmsh keeps OCCT's curve
parameters); nodes on gmsh points to the part's vertex nodes by position.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from OCP.BRepTools import BRepTools

from medax.cad.face_region import has_seam
from medax.cad.shared_nodes import SharedNodes
from medax.errors import MeshError
from medax.geometry._types import FloatArray, IntArray

#: gmsh element types
_QUAD, _TRIANGLE = 3, 2
#: gmsh's tries, in order: (2-D algorithm, half the counts then every element split into
#: quads, inside size / size): Frontal-Delaunay for quads recombined, quasi-structured quads
#: (11, which splits itself), Frontal-Delaunay recombined, then both Frontal-Delaunays split;
#: then finer inside than on the boundary (room to turn where edges are coarse)
ATTEMPTS = (
    (8, False, 1.0),
    (11, True, 1.0),
    (6, False, 1.0),
    (8, True, 1.0),
    (6, True, 1.0),
    (8, False, 0.5),
    (6, False, 0.5),
    (8, True, 0.5),
    (8, False, 0.25),
)
#: the quasi-structured algorithm, skipped on faces with a seam edge
_QUASI_STRUCTURED = 11
#: least distance (x the 4-gon's diameter) from the point the 5 quads of a triangle pair
#: are built about to the 4-gon's edges (:func:`pair_triangles`)
_KERNEL_MARGIN = 0.02
#: least sine of the inner quad's corners when it is the 4-gon scaled by half (else its
#: nodes go on a circle, which makes it convex)
_INNER_SINE = 0.2
#: seconds one gmsh attempt on one face may take (run in a forked child, killed after)
ATTEMPT_TIMEOUT = 60.0
#: a gmsh node on a curve may be this share of the local spacing away from the part's node
_MATCH_SHARE = 0.3


@dataclass(frozen=True)
class GmshFace:
    """A face's gmsh mesh: ``points`` (k, 3), surface parameters ``uv`` (k, 2), local quads
    (m, 4) and ``node_id`` (k,): the part's node id of each boundary node, -1 inside;
    ``subdivided``: whether the all-quad subdivision was needed; ``paired``: the triangle
    pairs the recombination left that became 5 quads each (:func:`pair_triangles`)."""

    points: FloatArray
    uv: FloatArray
    quads: IntArray
    node_id: IntArray
    subdivided: bool
    paired: int = 0


@dataclass(frozen=True)
class FaceJob:
    """One face for :class:`GmshFaces`: the CAD ``face``, its ``edges`` that have nodes,
    its ``vertices`` (indices into the shared nodes) and ``check``, which returns the mesh
    as it is to be used (e.g. its quads turned to the face's outward normal) or what is
    wrong with it (e.g. a quad inverted against that normal)."""

    face: Any
    edges: Sequence[int]
    vertices: Sequence[int]
    check: Callable[[GmshFace], GmshFace | str] | None = None


def attempts_for(face: Any) -> list[tuple[int, bool, float]]:
    """The attempts (:data:`ATTEMPTS`) for ``face``: without the quasi-structured one on a
    face with a seam edge."""
    seam = has_seam(face)
    return [a for a in ATTEMPTS if not (seam and a[0] == _QUASI_STRUCTURED)]


class GmshFaces:
    """Faces of a part meshed by gmsh on the part's shared ``nodes`` (face ``i`` described
    by ``job(i)``), in a forked worker process that serves one face after another.

    Each attempt starts from a fresh gmsh state. An attempt that takes longer than
    :data:`ATTEMPT_TIMEOUT` or ends the process (gmsh's quasi-structured quads were seen to
    hang and to abort) counts as failed, with a message; a new worker goes on with the
    next attempt. One worker for many attempts: forking the part's process for each cost
    30 - 40 ms (page tables and teardown), more than most attempts take. Without ``fork``
    (not POSIX) the attempts run in this process, unbounded. Use as a context manager (the
    worker is stopped at the end)."""

    def __init__(self, nodes: SharedNodes, job: Callable[[int], FaceJob]) -> None:
        self.nodes = nodes
        self.job = job
        self._tmp = tempfile.TemporaryDirectory(prefix="medax-")
        self._proc: Any = None
        self._requests: Any = None
        self._results: Any = None

    def __enter__(self) -> GmshFaces:
        return self

    def __exit__(self, kind: object, *exc: object) -> None:
        self.close(polite=kind is None)  # (on an error or an interrupt: at once)

    def close(self, polite: bool = True) -> None:
        """Stop the worker (asked to finish, or killed when not ``polite``), remove the face
        files."""
        self._stop(polite=polite)
        self._tmp.cleanup()

    def mesh(self, index: int) -> GmshFace:
        """Face ``index`` meshed with quads whose boundary nodes are the shared nodes of its
        edges and vertices, at the size ``nodes.size``; tried again
        (:data:`ATTEMPTS`) while triangles remain or the job's check refuses the quads.
        Raises :class:`MeshError` naming the face."""
        job = self.job(index)
        tries = attempts_for(job.face)
        path = Path(self._tmp.name) / f"face{index}.brep"
        if not BRepTools.Write_s(job.face, str(path)):
            raise MeshError(f"face {index}: could not write it for gmsh")
        last = "triangles left by the recombination"
        fallback: GmshFace | None = None  # the first valid mesh with triangle pairs replaced
        k = 0
        while k < len(tries):
            for result in self._run(index, str(path), tries, k):
                k += 1
                if isinstance(result, GmshFace) and not result.paired:
                    return result
                if isinstance(result, GmshFace):
                    fallback = fallback or result
                else:
                    last = result
        if fallback is not None:
            return fallback
        raise MeshError(f"face {index}: gmsh could not mesh it with valid quads only ({last})")

    def _run(
        self, index: int, path: str, tries: list[tuple[int, bool, float]], start: int
    ) -> Iterator[GmshFace | str]:
        """The results of attempts ``tries[start:]`` on face ``index`` (stored at ``path``)
        in order, up to the first mesh of quads alone; after a timeout or a crash the
        message, and nothing more (the worker is gone)."""
        import multiprocessing as mp  # noqa: PLC0415

        if "fork" not in mp.get_all_start_methods():  # pragma: no cover
            yield from _serve_face(self.nodes, self.job(index), index, path, tries, start)
            return
        if self._proc is None:
            self._start()
        self._requests.send((index, path, tries, start))
        for _ in range(start, len(tries)):
            try:
                if not self._results.poll(ATTEMPT_TIMEOUT):
                    self._stop()
                    yield f"gmsh took more than {ATTEMPT_TIMEOUT:g} s"
                    return
                result = self._results.recv()
            except EOFError:
                code = self._stop()
                yield f"gmsh's process ended without a result (exit code {code})"
                return
            yield result
            if isinstance(result, GmshFace) and not result.paired:
                return

    def _start(self) -> None:
        import multiprocessing as mp  # noqa: PLC0415

        ctx = mp.get_context("fork")
        req_recv, self._requests = ctx.Pipe(duplex=False)
        self._results, res_send = ctx.Pipe(duplex=False)
        nodes, job, ours = self.nodes, self.job, (self._requests, self._results)

        def serve() -> None:
            for end in ours:  # (so that the worker sees the end of the requests if we die)
                end.close()
            try:
                while True:
                    request = req_recv.recv()
                    if request is None:
                        return
                    index, path, tries, start = request
                    for result in _serve_face(nodes, job(index), index, path, tries, start):
                        res_send.send(result)
            except (EOFError, BrokenPipeError, KeyboardInterrupt):
                return  # (we are gone or stopping: quietly, the run reports it)

        self._proc = ctx.Process(target=serve, daemon=True)
        self._proc.start()
        req_recv.close()
        res_send.close()

    def _stop(self, polite: bool = False) -> int | None:
        """End the worker (asked to, when ``polite``, else killed); its exit code."""
        proc, self._proc = self._proc, None
        if proc is None:
            return None
        try:
            if polite and proc.is_alive():
                self._requests.send(None)
                proc.join(5.0)
        except OSError:  # pragma: no cover (the worker is gone already)
            pass
        if proc.is_alive():
            proc.kill()
        proc.join()
        self._requests.close()
        self._results.close()
        return proc.exitcode


def _serve_face(
    nodes: SharedNodes,
    job: FaceJob,
    index: int,
    path: str,
    tries: list[tuple[int, bool, float]],
    start: int,
) -> Iterator[GmshFace | str]:
    """Attempts ``tries[start:]`` on face ``index`` (its BRep file at ``path``), each on a
    fresh gmsh state: each one's mesh or what was wrong, up to the first mesh of quads
    alone."""
    import gmsh  # noqa: PLC0415

    vs = list(job.vertices)
    for algorithm, subdivide, inner in tries[start:]:
        if gmsh.isInitialized():
            gmsh.finalize()
        gmsh.initialize(readConfigFiles=False, interruptible=False)
        gmsh.option.setNumber("General.Terminal", 0)
        result: GmshFace | str
        gmsh.model.add(f"medax-face-{index}-{algorithm}-{int(subdivide)}-{inner}")
        try:
            out = _mesh(gmsh, Path(path), index, nodes, job.edges, inner, algorithm, subdivide)
            if out is None:
                result = "triangles left by the recombination"
            else:
                _vertices(gmsh, out, nodes.vert_pts[vs], nodes.vert_ids[vs], nodes.tol, index)
                result = out if job.check is None else job.check(out)
        except MeshError as err:  # (counts not kept, nodes off the edge: try again)
            result = str(err).removeprefix(f"face {index}: ")
        except Exception as err:  # gmsh raises plain Exceptions
            result = f"gmsh: {err}"
        finally:
            gmsh.model.remove()
        yield result
        if isinstance(result, GmshFace) and not result.paired:
            return


def _mesh(
    gmsh: Any,
    path: Path,
    index: int,
    nodes: SharedNodes,
    edges: Sequence[int],
    inner: float,
    algorithm: int,
    subdivide: bool,
) -> GmshFace | None:
    """One attempt, inside size ``inner`` x ``nodes.size``, on the nodes of ``edges``; None
    when triangles remain."""
    edge_ids, edge_pts, tol = nodes.edge_ids, nodes.edge_pts, nodes.tol
    size = inner * nodes.size
    gmsh.model.occ.importShapes(str(path), highestDimOnly=True)
    gmsh.model.occ.synchronize()
    surfaces = gmsh.model.getEntities(2)
    if len(surfaces) != 1:
        raise MeshError(f"face {index}: gmsh read {len(surfaces)} surfaces from it")
    tag = surfaces[0][1]
    curve_edge: dict[int, int] = {}
    mids = {j: np.asarray(nodes.edge_mid[j]) for j in edges}
    for _, c in gmsh.model.getEntities(1):
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        ends = np.asarray(gmsh.model.getValue(1, c, [lo[0], 0.5 * (lo[0] + hi[0]), hi[0]]))
        p = ends.reshape(3, 3)[1]
        if np.ptp(ends.reshape(3, 3), axis=0).max() <= tol:
            continue  # a degenerate edge (a pole): its one node is the vertex's
        j, d = min(((j, float(np.linalg.norm(m - p))) for j, m in mids.items()), key=lambda x: x[1])
        if d > tol:
            raise MeshError(f"face {index}: a gmsh curve matches none of its edges ({d:.3g} off)")
        curve_edge[c] = j
        n = len(edge_ids[j]) - 1
        if n < 1:
            continue
        gmsh.model.mesh.setTransfiniteCurve(c, (n // 2 if subdivide else n) + 1)
    gmsh.option.setNumber("Mesh.Algorithm", algorithm)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
    # (quasi-structured, 11, splits every element itself)
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1 if subdivide and algorithm != 11 else 0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", (2.0 if subdivide else 1.0) * size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.model.mesh.generate(2)
    types, _, conn = gmsh.model.mesh.getElements(2, tag)
    by_type = {int(t): np.asarray(c, dtype=np.int64) for t, c in zip(types, conn, strict=True)}
    if set(by_type) - {_QUAD, _TRIANGLE} or _QUAD not in by_type:
        return None
    quads_tags = by_type[_QUAD].reshape(-1, 4)
    tris_tags = by_type.get(_TRIANGLE, np.zeros(0, dtype=np.int64)).reshape(-1, 3)
    tags, coord, _ = gmsh.model.mesh.getNodes(2, tag, True, False)
    # (nodes on a seam are listed twice)
    tags, first = np.unique(np.asarray(tags, dtype=np.int64), return_index=True)
    pts = np.asarray(coord, dtype=np.float64).reshape(-1, 3)[first]
    local = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    local[tags] = np.arange(tags.size)
    # surface parameters of every node (gmsh does not keep them on all inner nodes)
    par = gmsh.model.getParametrization(2, tag, pts.ravel().tolist())
    uv = np.asarray(par, dtype=np.float64).reshape(-1, 2)
    quads = local[quads_tags]
    n_pairs = len(tris_tags) // 2
    if len(tris_tags):  # triangles blossom left: pairs of neighbours become 5 quads each
        paired = pair_triangles(local[tris_tags], uv, _turn(uv, quads))
        if paired is None:
            return None
        new_uv, new_quads = paired
        new_pts = gmsh.model.getValue(2, tag, new_uv.ravel().tolist())
        pts = np.vstack((pts, np.asarray(new_pts, dtype=np.float64).reshape(-1, 3)))
        uv = np.vstack((uv, new_uv))
        quads = np.vstack((quads, new_quads))
    node_id = np.full(len(pts), -1, dtype=np.int64)
    for c, j in curve_edge.items():
        ids, ours = edge_ids[j], edge_pts[j]
        ctags, ccoord, cpar = gmsh.model.mesh.getNodes(1, c, False, True)
        if len(ids) < 3 and len(ctags) == 0:
            continue
        order = np.argsort(np.asarray(cpar))
        ct = np.asarray(ctags, dtype=np.int64)[order]
        cp = np.asarray(ccoord, dtype=np.float64).reshape(-1, 3)[order]
        inner_ids, inner_pts = ids[1:-1], ours[1:-1]
        if len(ct) != len(inner_ids):
            raise MeshError(
                f"face {index}: gmsh put {len(ct)} nodes inside edge {j}, not {len(inner_ids)}"
            )
        if np.linalg.norm(cp[0] - inner_pts[-1]) < np.linalg.norm(cp[0] - inner_pts[0]):
            inner_ids, inner_pts = inner_ids[::-1], inner_pts[::-1]
        spacing = float(np.min(np.linalg.norm(np.diff(ours, axis=0), axis=1)))
        off = float(np.max(np.linalg.norm(cp - inner_pts, axis=1)))
        if off > _MATCH_SHARE * spacing:
            raise MeshError(
                f"face {index}: gmsh's nodes on edge {j} are {off:.3g} from the part's "
                f"(spacing {spacing:.3g})"
            )
        rows = local[ct]
        node_id[rows] = inner_ids
        pts[rows] = inner_pts
    return GmshFace(pts, uv, quads, node_id, subdivide, n_pairs)


def pair_triangles(
    tris: IntArray, uv: FloatArray, turn: float
) -> tuple[FloatArray, IntArray] | None:
    """Quads in place of the triangles ``tris`` (t, 3) (node rows into ``uv`` (k, 2)) that
    a recombination left, when they pair off into neighbours (sharing an edge): each pair's
    4-gon (its four outer nodes, turned the way ``turn`` (+1 / -1) says the face's quads
    turn in ``uv``) becomes 5 quads, an inner quad and four trapezoids, with the inner
    nodes on the rays from the middle of one of its diagonals (one that sees the whole
    4-gon) to its corners. This stays valid where the one quad of the pair would have a
    flat or reflex corner (why the recombination left them), and where gmsh's two triangles
    overlap (split along the outer diagonal of a reflex 4-gon). Returns the new nodes'
    parameters (4 per pair) and the quads (5 per pair; new node rows from ``len(uv)``), or
    None when some triangle has no partner or a 4-gon has no such point."""
    t = len(tris)
    if t % 2:
        return None
    edge_of: dict[tuple[int, int], list[int]] = {}
    for k, tri in enumerate(tris.tolist()):
        for a in range(3):
            key = (min(tri[a], tri[a - 2]), max(tri[a], tri[a - 2]))
            edge_of.setdefault(key, []).append(k)
    partners: list[set[int]] = [set() for _ in range(t)]
    for ks in edge_of.values():
        if len(ks) == 2:
            partners[ks[0]].add(ks[1])
            partners[ks[1]].add(ks[0])
    mate = _match(partners)
    if mate is None:
        return None
    new_uv: list[FloatArray] = []
    quads: list[list[int]] = []
    nxt = len(uv)
    for k in range(t):
        m = mate[k]
        if m < k:
            continue
        a, b = tris[k].tolist(), tris[m].tolist()
        shared = set(a) & set(b)
        # rotate a to (p, q, r) with (q, r) shared; b runs r -> q -> s
        while a[0] in shared:
            a = a[1:] + a[:1]
        p, q, r = a
        (s,) = set(b) - shared
        ring = [p, q, s, r]
        if _area(uv[ring]) * turn < 0.0:
            ring = ring[::-1]
        corner = uv[ring]
        mids = 0.5 * (corner[:2] + corner[2:])
        margin = [_margin(corner, c, turn) for c in mids]
        if max(margin) < _KERNEL_MARGIN:
            return None
        mid = mids[int(np.argmax(margin))]
        inner = mid + 0.5 * (corner - mid)
        if _least_sine(inner, turn) < _INNER_SINE:  # (a flat or reflex 4-gon): on a circle
            d = np.linalg.norm(corner - mid, axis=1)
            inner = mid + (corner - mid) * (0.5 * d.min() / d)[:, None]
        ids = list(range(nxt, nxt + 4))
        nxt += 4
        new_uv.append(inner)
        quads.append(ids)
        for i in range(4):
            quads.append([ring[i], ring[(i + 1) % 4], ids[(i + 1) % 4], ids[i]])
    return np.concatenate(new_uv), np.asarray(quads, dtype=np.int64)


def _match(partners: list[set[int]]) -> list[int] | None:
    """A perfect matching of the triangles' neighbour graph (few triangles: greedy on the
    fewest partners first, then augmenting paths), or None."""
    t = len(partners)
    mate = [-1] * t
    for k in sorted(range(t), key=lambda k: len(partners[k])):
        if mate[k] < 0:
            free = [m for m in partners[k] if mate[m] < 0]
            if free:
                m = min(free, key=lambda m: len(partners[m]))
                mate[k], mate[m] = m, k
    for k in range(t):
        if mate[k] < 0 and not _augment(k, partners, mate, set()):
            return None
    return mate


def _augment(k: int, partners: list[set[int]], mate: list[int], seen: set[int]) -> bool:
    """An alternating path from free triangle ``k`` to another free one (bipartite-style
    search; enough for the few, mostly paired triangles a recombination leaves)."""
    seen.add(k)
    for m in partners[k]:
        if m in seen:
            continue
        seen.add(m)
        if mate[m] < 0 or (mate[m] not in seen and _augment(mate[m], partners, mate, seen)):
            mate[k], mate[m] = m, k
            return True
    return False


def _area(poly: FloatArray) -> float:
    """Signed area of the polygon ``poly`` (n, 2)."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _turn(uv: FloatArray, quads: IntArray) -> float:
    """+1 when the quads mostly turn counter-clockwise in ``uv``, else -1."""
    if not len(quads):
        return 1.0
    x, y = uv[quads, 0], uv[quads, 1]
    area = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y)
    return 1.0 if area >= 0.0 else -1.0


def _margin(poly: FloatArray, c: FloatArray, turn: float) -> float:
    """The least distance from ``c`` (2,) to the lines of the edges of ``poly`` (n, 2),
    signed (positive on the inner side of every edge for a polygon turning the way ``turn``
    says: ``c`` then sees the whole polygon), over the polygon's diameter."""
    e = np.roll(poly, -1, axis=0) - poly
    w = c - poly
    dist = turn * (e[:, 0] * w[:, 1] - e[:, 1] * w[:, 0]) / np.linalg.norm(e, axis=1)
    diameter = float(np.max(np.linalg.norm(poly[:, None] - poly[None], axis=2)))
    return float(dist.min()) / diameter


def _least_sine(poly: FloatArray, turn: float) -> float:
    """The least sine of the corner angles of ``poly`` (n, 2), negative at a corner that
    turns against ``turn``."""
    e = np.roll(poly, -1, axis=0) - poly
    b = np.roll(e, 1, axis=0)
    cross = turn * (b[:, 0] * e[:, 1] - b[:, 1] * e[:, 0])
    return float(np.min(cross / (np.linalg.norm(b, axis=1) * np.linalg.norm(e, axis=1))))


def _vertices(
    gmsh: Any, m: GmshFace, vertex_pts: FloatArray, vertex_ids: IntArray, tol: float, index: int
) -> None:
    """The nodes on gmsh's points (the face's corners) take the part's vertex nodes."""
    tags, coord, _ = gmsh.model.mesh.getNodes(2, gmsh.model.getEntities(2)[0][1], True, False)
    row = {int(t): k for k, t in enumerate(np.unique(np.asarray(tags, dtype=np.int64)))}
    for _, ptag in gmsh.model.getEntities(0):
        ptags, pcoord, _ = gmsh.model.mesh.getNodes(0, ptag)
        if len(ptags) == 0 or int(ptags[0]) not in row:
            continue
        p = np.asarray(pcoord[:3], dtype=np.float64)
        d = np.linalg.norm(vertex_pts - p, axis=1)
        k = int(np.argmin(d)) if len(d) else -1
        if k < 0 or d[k] > tol:
            raise MeshError(f"face {index}: a gmsh point matches none of its vertices")
        r = row[int(ptags[0])]
        m.node_id[r] = vertex_ids[k]
        m.points[r] = vertex_pts[k]
