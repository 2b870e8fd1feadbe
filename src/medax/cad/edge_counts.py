"""Division counts of the edges of a part mesh, equal on opposite sides of structured faces.

A structured face needs the same number of divisions on its sides 0 and 2 and on 1 and 3,
where a side is a chain of CAD edges and its count the sum of theirs. Counts start from the
target size (``2 ceil(L / 2H)``: even, so that every face, whatever its number of sides, has
an even number of boundary edges and can be meshed with quads only). Edges that are whole
opposite sides of a structured face are joined into classes (union-find over those pairs,
as gmsh's automatic transfinite propagation does) and each class takes its members' largest
count. Sides made of several edges are then evened on the shorter side, two divisions at
a time on its coarsest edge (fewest divisions per length: the extra divisions go where the
side is least resolved, which also keeps the nodes of a chain level with those of the
opposite chain, as a thin curved strip needs); counts only grow, and stay even. A face
whose sides still differ after :data:`ROUNDS` passes is a conflict: it is reported, treated
as unstructured, and the counts are made again without it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from medax.errors import InputError
from medax.geometry._types import FloatArray, IntArray

#: passes of the chain evening before the faces still uneven are conflicts
ROUNDS = 32
#: largest count accepted on one edge
MAX_COUNT = 100_000

Sides = Sequence[Sequence[int]]  # a face's four sides, each a chain of edge indices


@dataclass(frozen=True)
class EdgeCounts:
    """``counts[j]`` divisions of edge ``j`` (0 for edges not meshed); ``structured``: the
    faces whose opposite sides agree; ``conflicts``: face -> why it was left unstructured."""

    counts: IntArray
    structured: tuple[int, ...]
    conflicts: dict[int, str] = field(default_factory=dict)


def size_count(length: float, size: float) -> int:
    """The even count ``2 ceil(L / 2H)`` (at least 2) of an edge of ``length``."""
    return max(2, 2 * math.ceil(length / (2.0 * size) * (1.0 - 1e-12)))


class _Classes:
    """Union-find over edge indices."""

    def __init__(self, n: int) -> None:
        self.parent = list(range(n))

    def find(self, a: int) -> int:
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a

    def union(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


def division_counts(
    lengths: FloatArray,
    meshed: Sequence[int],
    four_sided: Mapping[int, Sides],
    size: float,
    minimum: IntArray | None = None,
) -> EdgeCounts:
    """Counts for the edges ``meshed`` of lengths ``lengths`` (n_edges,), for faces
    ``four_sided`` (face -> its four sides as edge chains, in order) meant to be
    structured, at target edge length ``size``; ``minimum`` (n_edges,) even lower bounds
    (e.g. for closed edges, which one or two segments would collapse)."""
    if not (math.isfinite(size) and size > 0.0):
        raise InputError(f"size must be positive, got {size}")
    n = len(lengths)
    base = np.zeros(n, dtype=np.int64)
    for j in meshed:
        base[j] = size_count(float(lengths[j]), size)
    if minimum is not None:
        base = np.where(base > 0, np.maximum(base, minimum), 0)
    if base.max(initial=0) > MAX_COUNT:
        raise InputError(
            f"size {size:g} gives {int(base.max())} divisions on one edge (limit {MAX_COUNT})"
        )
    active = dict(four_sided)
    conflicts: dict[int, str] = {}
    while True:
        counts, uneven = _propagate(base, active, lengths)
        if not uneven:
            return EdgeCounts(counts, tuple(sorted(active)), conflicts)
        for f, why in uneven.items():
            conflicts[f] = why
            del active[f]


def _propagate(
    base: IntArray, faces: Mapping[int, Sides], lengths: FloatArray
) -> tuple[IntArray, dict[int, str]]:
    """Counts with every face of ``faces`` even, or the faces that stay uneven."""
    classes = _Classes(len(base))
    for sides in faces.values():
        for a, b in ((0, 2), (1, 3)):
            if len(sides[a]) == 1 and len(sides[b]) == 1:
                classes.union(sides[a][0], sides[b][0])
    root = np.array([classes.find(j) for j in range(len(base))], dtype=np.int64)
    value = np.zeros(len(base), dtype=np.int64)
    np.maximum.at(value, root, base)
    for _ in range(ROUNDS):
        changed = False
        for sides in faces.values():
            for a, b in ((0, 2), (1, 3)):
                sa = int(value[root[list(sides[a])]].sum())
                sb = int(value[root[list(sides[b])]].sum())
                if sa == sb:
                    continue
                short = list(sides[a] if sa < sb else sides[b])
                need = abs(sa - sb)
                while need > 0:  # two more divisions on the coarsest edge of the short side
                    j = min(
                        short,
                        key=lambda e: (int(value[root[e]]) / max(float(lengths[e]), 1e-300), e),
                    )
                    value[root[j]] += 2
                    need -= 2 * sum(1 for e in short if root[e] == root[j])
                changed = True
        if not changed:
            return value[root], {}
    uneven = {}
    for f, sides in faces.items():
        for a, b in ((0, 2), (1, 3)):
            sa = int(value[root[list(sides[a])]].sum())
            sb = int(value[root[list(sides[b])]].sum())
            if sa != sb:
                uneven[f] = f"opposite sides {a} and {b} need {sa} and {sb} divisions"
                break
    if not uneven:  # (the last pass changed nothing that is still uneven)
        return value[root], {}
    return value[root], uneven
