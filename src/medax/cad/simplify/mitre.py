"""Fillets that meet in a mitre: one of each pair is kept so that the other can be merged.

Where two filleted edges meet at a corner whose third edge is sharp, the two fillet faces
intersect along a crease (a mitre). Their halves on the supporting face they share would
put that crease inside one merged face, which no single tangent-continuous surface
follows (the fitted route measured 1e-2 against a tolerance of 4e-5 on random box edges,
and every fillet on the face was kept). With one fillet of the pair kept as it is, the
crease stays an edge between two faces and the other fillet is merged.
"""

from __future__ import annotations

from typing import Any

from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import edge_points, edges_of, max_normal_angle, small_list
from medax.cad.simplify.specs import CornerSpec, FilletSpec, edge_face_map
from medax.tolerances import TANGENT_ANGLE

#: samples along a shared edge for the normal comparison
EDGE_SAMPLES = 5


def mitre_pairs(shape: Any, fmap: Any, specs: dict[int, FilletSpec]) -> list[tuple[int, int]]:
    """Pairs ``(a, b)`` (``a < b``) of fillet faces of ``shape`` (0-based indices in
    ``fmap``) that share a supporting face and an edge across which they are not tangent
    (normals more than ``TANGENT_ANGLE`` apart at some sample of it)."""
    e2f = edge_face_map(shape)
    pairs: set[tuple[int, int]] = set()
    for a, sa in specs.items():
        face_a = TopoDS.Face(fmap.FindKey(a + 1))
        for e in edges_of(face_a):
            for g in small_list(e2f.FindFromKey(e)):
                b = fmap.FindIndex(g) - 1
                if b <= a or b not in specs or not set(sa.supporting) & set(specs[b].supporting):
                    continue
                face_b = TopoDS.Face(g)
                angle = max_normal_angle(face_a, face_b, edge_points(e, EDGE_SAMPLES))
                if angle > TANGENT_ANGLE:
                    pairs.add((a, b))
    return sorted(pairs)


def mitre_keeps(pairs: list[tuple[int, int]], corners: dict[int, CornerSpec]) -> dict[int, str]:
    """The fillets to keep (with the reason) so that no pair of ``pairs`` is merged whole:
    greedily the fillet in most of the remaining pairs, then the one meeting fewer corner
    blends (a kept fillet keeps its corners, and their other fillets), then the higher
    face index."""
    in_corners: dict[int, int] = {}
    for cs in corners.values():
        for f in cs.fillets:
            in_corners[f] = in_corners.get(f, 0) + 1
    left = list(pairs)
    keep: dict[int, str] = {}
    while left:
        degree: dict[int, int] = {}
        for a, b in left:
            degree[a] = degree.get(a, 0) + 1
            degree[b] = degree.get(b, 0) + 1
        f = max(degree, key=lambda k: (degree[k], -in_corners.get(k, 0), k))
        others = sorted(b if a == f else a for a, b in left if f in (a, b))
        keep[f] = (
            f"meets fillet {others[0]} in a mitre (a crease no single smooth surface follows): "
            "kept so that the other can be merged"
        )
        left = [p for p in left if f not in p]
    return keep
