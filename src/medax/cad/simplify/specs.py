"""What the simplifier is told about each blend: :class:`FilletSpec`.

Built from the classifier's :class:`~medax.cad.model.Classification` (fillet records), or,
for parts built with OCCT in tests, from the blend faces of the fillet builder's history
(:func:`specs_from_blend_faces`): there the two smooth edges are the blend's edges shared
with a non-blend face that is tangent to it (normals compared at samples).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from OCP.collections import (
    IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as AncestorMap,
)
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import (
    edge_points,
    edges_of,
    max_normal_angle,
    shape_map,
    small_list,
)
from medax.tolerances import TANGENT_ANGLE


@dataclass(frozen=True)
class FilletSpec:
    """An edge fillet to remove: face ``face`` (0-based face index of the solid), its two
    smooth edges ``smooth_edges`` (0-based edge indices) and the supporting faces across
    them, ``supporting`` (same order). ``radius`` where constant (length unit), else None."""

    face: int
    smooth_edges: tuple[int, ...]  # two; one for a fillet merged whole into one face
    supporting: tuple[int, ...]
    radius: float | None = None
    #: Every edge of each constraint side where a side is a chain of several edges
    #: (``smooth_edges`` holds the first of each); None when each side is one edge.
    chains: tuple[tuple[int, ...], tuple[int, ...]] | None = None

    def side_edges(self, k: int) -> tuple[int, ...]:
        """The edge indices of constraint side ``k`` (0 or 1)."""
        return self.chains[k] if self.chains is not None else (self.smooth_edges[k],)


@dataclass(frozen=True)
class CornerSpec:
    """A corner blend where fillets meet: face ``face``, the fillet faces ``fillets`` that end
    on it and the ``supporting`` faces of those fillets (0-based face indices)."""

    face: int
    fillets: tuple[int, ...]
    supporting: tuple[int, ...]


@dataclass(frozen=True)
class BlendInput:
    """Blends of a solid: fillets and corner blends to try, and blends refused up front with
    a reason."""

    fillets: tuple[FilletSpec, ...]
    refused: tuple[tuple[int, str], ...]
    corners: tuple[CornerSpec, ...] = ()

    @property
    def linked(self) -> frozenset[int]:
        """The fillets linked to other blends: meeting a corner blend, ridden on by a
        fillet (its supporting face), or riding on one."""
        fillets = {s.face for s in self.fillets}
        out = {f for cs in self.corners for f in cs.fillets}
        out |= {b for s in self.fillets for b in s.supporting if b in fillets}
        out |= {s.face for s in self.fillets if set(s.supporting) & fillets}
        return frozenset(out)

    @property
    def blend_faces(self) -> tuple[int, ...]:
        """All blend face indices (tried and refused), sorted."""
        return tuple(
            sorted(
                {f.face for f in self.fillets}
                | {c.face for c in self.corners}
                | {i for i, _ in self.refused}
            )
        )


def edge_face_map(shape: Any) -> Any:
    """Edge -> faces ancestor map of ``shape``."""
    m = AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, m)
    return m


def specs_from_blend_faces(shape: Any, blends: Iterable[int]) -> BlendInput:
    """Fillet specs from known blend faces (0-based indices), e.g. the fillet history.

    A blend with exactly two tangent non-blend neighbours, each across one edge, is a
    fillet; any other blend (corner blends, chains of blends) is refused with the reason.
    """
    fmap = shape_map(shape, TopAbs_FACE)
    emap = shape_map(shape, TopAbs_EDGE)
    e2f = edge_face_map(shape)
    blend_set = set(blends)
    fillets: list[FilletSpec] = []
    refused: list[tuple[int, str]] = []
    corner_nbrs: dict[int, set[int]] = {}
    for b in sorted(blend_set):
        face = TopoDS.Face(fmap.FindKey(b + 1))
        smooth: list[tuple[int, int]] = []
        blend_nbrs: set[int] = set()
        seen: set[int] = set()
        for e in edges_of(face):
            ei = emap.FindIndex(e) - 1
            if ei in seen:
                continue
            seen.add(ei)
            for f in small_list(e2f.FindFromKey(e)):
                fi = fmap.FindIndex(f) - 1
                if fi == b:
                    continue
                if fi in blend_set:
                    blend_nbrs.add(fi)
                    continue
                pts = edge_points(e, 7)[1:-1]
                if max_normal_angle(face, TopoDS.Face(f), pts) < TANGENT_ANGLE:
                    smooth.append((ei, fi))
        if len(smooth) == 2 and smooth[0][1] != smooth[1][1]:
            fillets.append(
                FilletSpec(b, (smooth[0][0], smooth[1][0]), (smooth[0][1], smooth[1][1]))
            )
        elif len(smooth) == 2:
            refused.append((b, f"both smooth edges on face {smooth[0][1]}"))
        elif blend_nbrs and not smooth:
            corner_nbrs[b] = blend_nbrs
        elif blend_nbrs:
            refused.append(
                (b, f"blend meeting blends {sorted(blend_nbrs)} and faces: not supported")
            )
        else:
            refused.append((b, f"{len(smooth)} smooth edges (an edge fillet has 2)"))
    return _with_corners(fillets, refused, corner_nbrs)


def _with_corners(
    fillets: list[FilletSpec], refused: list[tuple[int, str]], corner_nbrs: dict[int, set[int]]
) -> BlendInput:
    """Corner blends whose neighbours are all fillets become :class:`CornerSpec`; the rest
    are refused with the reason."""
    by_face = {f.face: f for f in fillets}
    corners: list[CornerSpec] = []
    for c, nbrs in sorted(corner_nbrs.items()):
        if not nbrs <= set(by_face):
            others = sorted(nbrs - set(by_face))
            refused.append((c, f"corner blend next to blends {others} that are not fillets"))
            continue
        sup = sorted({s for f in nbrs for s in by_face[f].supporting})
        corners.append(CornerSpec(c, tuple(sorted(nbrs)), tuple(sup)))
    return BlendInput(tuple(fillets), tuple(refused), tuple(corners))


def specs_from_classification(cls: Any) -> BlendInput:
    """Fillet specs from a :class:`~medax.cad.model.Classification` (no reclassification).

    Fillets with two distinct supporting faces are tried (a constraint side may be a chain
    of edges); corner blends and the rest are refused with the reason.
    """
    fillets: list[FilletSpec] = []
    refused: list[tuple[int, str]] = []
    for rec in cls.fillets:
        a, b = rec.smooth_edges
        if not a or not b:
            refused.append((rec.face, "a constraint side has no edge"))
        elif rec.supporting[0] == rec.supporting[1]:
            refused.append((rec.face, f"both smooth edges on face {rec.supporting[0]}"))
        else:
            chains = (tuple(a), tuple(b)) if len(a) > 1 or len(b) > 1 else None
            fillets.append(
                FilletSpec(rec.face, (a[0], b[0]), tuple(rec.supporting), rec.radius, chains)
            )
    return _with_corners(fillets, refused, {c.face: set(c.fillets) for c in cls.corners})
