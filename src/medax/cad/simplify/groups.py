"""Face groups of the split solid and the boundary of each group (the new contours).

Each supporting face and the fillet halves that touch it form a group (one new face); every
other face is a group of its own. A group's boundary is the set of its faces' edges used once
(inner edges and seams are used twice); chained by vertices it gives the new face's loops.
Consecutive boundary edges with the same neighbouring group, meeting at a vertex where only
these two groups meet, form a *run*: one new edge (the paper's joined semi-smooth edges).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.collections import (
    IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as AncestorMap,
)
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import (
    edge_ends,
    edges_of,
    face_inside_point,
    face_normal_at,
    shape_map,
    small_list,
)
from medax.cad.simplify.split import SplitResult
from medax.errors import CadError


class GroupError(CadError):
    """A face group that cannot be formed, with the original ``faces`` (blend faces, or the
    faces the group's pieces come from) that it is traced to."""

    def __init__(self, message: str, faces: Iterable[int]) -> None:
        super().__init__(message)
        self.faces = frozenset(faces)


@dataclass
class Run:
    """Consecutive oriented boundary edges of a group shared with group ``neighbour``.

    ``edges`` are ``TopoDS_Edge`` oriented along the group's loop (material on the left
    seen from outside); ``indices`` their edge indices in the split solid (0-based).
    """

    edges: list[Any]
    indices: list[int]
    neighbour: int
    closed: bool = False


@dataclass
class Group:
    """One new face: result faces ``members`` (0-based, split solid), the original
    ``support`` face index when it is a merged group (else None), ``loops`` of runs."""

    id: int
    members: list[int]
    support: int | None = None
    halves: list[int] = field(default_factory=list)
    loops: list[list[Run]] = field(default_factory=list)

    @property
    def untouched(self) -> bool:
        """True when the face can be kept as it is (no merge, no joined edges)."""
        return (
            self.support is None
            and len(self.members) == 1
            and all(len(r.edges) == 1 for loop in self.loops for r in loop)
        )


def _ancestors(shape: Any, sub: Any, anc: Any) -> Any:
    m = AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, sub, anc, m)
    return m


def build_groups(
    split: SplitResult,
    fillets: dict[int, tuple[int, ...]],
    corners: dict[int, tuple[int, ...]] | None = None,
) -> list[Group]:
    """Groups of the split solid.

    ``fillets`` maps each simplified fillet (original face index) to its two supporting
    faces (original indices), or to the one it merges into whole; a supporting face may
    itself be a simplified fillet (a fillet on a fillet, split by a bridge): each piece then
    joins the one half of it that it touches. ``corners`` maps each split corner blend to its
    supporting faces (each piece goes to the one whose normal is nearest to the piece's
    own). Raises
    :class:`CadError` when a half does not touch exactly one supporting face or a boundary
    cannot be chained.
    """
    shape, fmap = split.shape, split.face_map
    emap = shape_map(shape, TopAbs_EDGE)
    vmap = shape_map(shape, TopAbs_VERTEX)
    e2f = _ancestors(shape, TopAbs_EDGE, TopAbs_FACE)
    nface = fmap.Size()
    parent = list(range(nface))

    def find(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    def face_nbrs(k: int) -> set[int]:
        out: set[int] = set()
        for e in edges_of(fmap.FindKey(k + 1)):
            for f in small_list(e2f.FindFromKey(e)):
                j = fmap.FindIndex(f) - 1
                if j != k:
                    out.add(j)
        return out

    support_of: dict[int, int] = {}
    for blend, supports in fillets.items():
        for k in split.pieces(blend):
            touching = [j for j in face_nbrs(k) if split.origin[j] in supports]
            origins = {split.origin[j] for j in touching}
            if len(origins) != 1:
                raise GroupError(
                    f"fillet face {blend}: a half touches {len(origins)} supporting faces", {blend}
                )
            (o,) = origins
            if o in fillets and len(touching) != 1:  # riding on a fillet: on one of its halves
                raise GroupError(
                    f"fillet face {blend}: a piece touches both halves of fillet {o}", {blend}
                )
            for j in touching:
                parent[find(k)] = find(j)
        for s in supports:
            if s in fillets:  # a simplified fillet: its halves go to its own supports
                continue
            for j in split.pieces(s)[1:]:
                parent[find(j)] = find(split.pieces(s)[0])
            for j in split.pieces(s):
                support_of[j] = s
    for corner, corner_supports in (corners or {}).items():
        for k in split.pieces(corner):
            s = _nearest_support(fmap, split, k, corner_supports, corner)
            root = find(split.pieces(s)[0])
            if not any(find(j) == root for j in face_nbrs(k)):
                raise GroupError(
                    f"corner blend {corner}: a piece does not touch face {s}'s group", {corner}
                )
            parent[find(k)] = find(split.pieces(s)[0])
    roots = sorted({find(k) for k in range(nface)})
    gid = {r: i for i, r in enumerate(roots)}
    group_of = [gid[find(k)] for k in range(nface)]
    groups = [Group(i, []) for i in range(len(roots))]
    for k in range(nface):
        g = groups[group_of[k]]
        g.members.append(k)
        if k in support_of:
            g.support = support_of[k]
    blends = set(fillets) | set(corners or {})
    for k in range(nface):
        if split.origin[k] in blends:
            groups[group_of[k]].halves.append(k)

    # integer adjacency, computed once: edge -> faces, vertex -> edges
    edge_faces = {
        emap.FindIndex(e2f.FindKey(j)) - 1: [
            fmap.FindIndex(f) - 1 for f in small_list(e2f.FindFromIndex(j))
        ]
        for j in range(1, e2f.Size() + 1)
    }
    inter = {i for i, fs in edge_faces.items() if len({group_of[k] for k in fs}) > 1}
    vertex_degree: dict[int, int] = {}
    for i in inter:
        e = TopoDS.Edge(emap.FindKey(i + 1))
        ends = {vmap.FindIndex(v) for v in edge_ends(e)}
        for v in ends:
            vertex_degree[v] = vertex_degree.get(v, 0) + 1

    def inter_group_degree(v: Any) -> int:
        return vertex_degree.get(vmap.FindIndex(v), 0)

    for g in groups:
        try:
            g.loops = _loops(g, group_of, fmap, emap, vmap, edge_faces, inter_group_degree)
        except CadError as err:
            raise GroupError(str(err), {split.origin[k] for k in g.members}) from None
    return groups


def _nearest_support(
    fmap: Any, split: SplitResult, k: int, supports: tuple[int, ...], corner: int
) -> int:
    """The supporting face whose outward normal is nearest to corner piece ``k``'s own."""
    piece = TopoDS.Face(fmap.FindKey(k + 1))
    p = face_inside_point(piece)
    n = None if p is None else face_normal_at(piece, p)
    if p is None or n is None:
        raise GroupError(f"corner blend {corner}: a piece has no inside point", {corner})
    best, pick = -2.0, supports[0]
    for s in supports:
        ns = face_normal_at(TopoDS.Face(fmap.FindKey(split.pieces(s)[0] + 1)), p)
        if ns is not None and float(ns @ n) > best:
            best, pick = float(ns @ n), s
    return pick


def _loops(g, group_of, fmap, emap, vmap, edge_faces, degree) -> list[list[Run]]:  # type: ignore[no-untyped-def]
    counts: dict[int, int] = {}
    oriented: dict[int, Any] = {}
    for k in g.members:
        for e in edges_of(TopoDS.Face(fmap.FindKey(k + 1))):
            if BRep_Tool.Degenerated_s(e):  # a pole of a corner's sphere: not a boundary
                continue
            i = emap.FindIndex(e) - 1
            counts[i] = counts.get(i, 0) + 1
            oriented[i] = e
    free = [i for i, c in counts.items() if c == 1]
    members = set(g.members)
    nbr: dict[int, int] = {}
    for i in free:
        others = [k for k in edge_faces[i] if k not in members]
        if len(others) != 1:
            raise CadError(f"group of face {g.members[0]}: boundary edge with {len(others)} faces")
        nbr[i] = group_of[others[0]]
    starts: dict[int, list[int]] = {}
    for i in free:
        v0, _ = edge_ends(oriented[i])
        starts.setdefault(vmap.FindIndex(v0), []).append(i)
    used: set[int] = set()
    loops: list[list[Run]] = []
    for i0 in free:
        if i0 in used:
            continue
        chain = [i0]
        used.add(i0)
        first_v = vmap.FindIndex(edge_ends(oriented[i0])[0])
        while True:
            end_v = vmap.FindIndex(edge_ends(oriented[chain[-1]])[1])
            if end_v == first_v:
                break
            nxt = [j for j in starts.get(end_v, []) if j not in used]
            if len(nxt) != 1:
                raise CadError(f"group of face {g.members[0]}: boundary does not chain")
            chain.append(nxt[0])
            used.add(nxt[0])
        loops.append(_runs(chain, oriented, nbr, vmap, degree))
    return loops


def _breaks(chain: list[int], oriented: dict[int, Any], nbr: dict[int, int], degree) -> list[bool]:  # type: ignore[no-untyped-def]
    """``out[j]``: a run starts at the start vertex of ``chain[j]``."""
    n = len(chain)
    out = []
    for j in range(n):
        prev, cur = chain[j - 1], chain[j]
        v = edge_ends(oriented[cur])[0]
        out.append(n == 1 or nbr[prev] != nbr[cur] or degree(v) != 2)
    return out


def _runs(chain, oriented, nbr, vmap, degree) -> list[Run]:  # type: ignore[no-untyped-def]
    brk = _breaks(chain, oriented, nbr, degree)
    if not any(brk):
        return [Run([oriented[i] for i in chain], list(chain), nbr[chain[0]], closed=True)]
    s = brk.index(True)
    chain = chain[s:] + chain[:s]
    brk = brk[s:] + brk[:s]
    runs: list[Run] = []
    for i, b in zip(chain, brk, strict=True):
        if b:
            runs.append(Run([], [], nbr[i]))
        runs[-1].edges.append(oriented[i])
        runs[-1].indices.append(i)
    if len(runs) == 1 and len(chain) == 1:
        runs[0].closed = True
    return runs
