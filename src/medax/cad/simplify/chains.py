"""Chains of fillets: blends in a row across one section, each tangent to the next.

A profile such as plane - arc r10 - arc r33 - arc r10 - plane (a rounded end made of three
tangent arcs), or the arcs of a cam's flank, is recognised as fillets each of whose
supporting faces is the next fillet: the smooth edge a fillet ``F`` shares with fillet ``G``
is also ``G``'s smooth edge towards ``F``. That is no fillet riding on another (a torus
round a filleted vertical edge, split by a bridge, :mod:`.bridge`): ``G``'s medial curve
runs parallel to ``F``'s edge and never meets it. Such a *chain* ``F1 .. Fk`` between two
faces ``A`` (next to ``F1``) and ``B`` (next to ``Fk``) that are no blends is one compound
blend: it is split once, at the medial curve of its middle fillet (``k`` odd) or at the
edge between its two middle fillets (``k`` even, no split), and each part joins the end
face it touches, whole fillets and the middle half together. When the fillets are
cylinders on parallel axes and the end face a plane along them or a cylinder on a parallel
axis, the merged face is an exact extrusion of the line (or arc) - arcs profile
(:func:`chain_arcs`, :func:`.surfaces.merged_surface`); otherwise the fitted routes take it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool

from medax.cad.simplify.medial import Medial
from medax.cad.simplify.occ import Array, uv_bounds, xyz
from medax.cad.simplify.specs import FilletSpec

#: The free end of a chain's last arc is continued past its edge by this angle (rad) when the
#: chain ends there (``k`` even), as a half's arc is continued past its medial curve.
OVERSHOOT = 0.05


@dataclass(frozen=True)
class Chain:
    """Fillets ``members`` (face indices, in order from end face ``ends[0]`` to
    ``ends[1]``), their original specs (same order)."""

    members: tuple[int, ...]
    ends: tuple[int, int]
    specs: tuple[FilletSpec, ...]

    @property
    def middle(self) -> int | None:
        """Index into ``members`` of the fillet split by its medial curve (``k`` odd), or
        None (``k`` even: split at the edge between the two middle fillets)."""
        k = len(self.members)
        return k // 2 if k % 2 else None

    def side(self, i: int) -> int:
        """0 when ``members[i]`` goes (whole or its half) to ``ends[0]``, else 1."""
        return 0 if i < len(self.members) // 2 else 1

    def toward(self, i: int, end: int) -> int:
        """The face next to ``members[i]`` on the side of end face ``ends[end]``."""
        if end == 0:
            return self.ends[0] if i == 0 else self.members[i - 1]
        return self.ends[1] if i == len(self.members) - 1 else self.members[i + 1]


def links(fillets: dict[int, FilletSpec]) -> set[tuple[int, int]]:
    """Ordered pairs ``(f, g)`` of fillets of ``fillets`` that are neighbours in a chain:
    ``g`` supports ``f`` and ``f`` supports ``g`` across one shared smooth edge."""
    out: set[tuple[int, int]] = set()
    for f, s in fillets.items():
        for k, g in enumerate(s.supporting):
            other = fillets.get(g)
            if other is None or f not in other.supporting:
                continue
            j = other.supporting.index(f)
            if set(s.side_edges(k)) & set(other.side_edges(j)):
                out.add((f, g))
    return out


def find_chains(
    fillets: dict[int, FilletSpec],
) -> tuple[list[Chain], dict[int, str]]:
    """Chains of ``fillets`` (each with at least two members) and the fillets of the
    linked sets that are no open chain between two non-blend faces, with the reason."""
    pairs = links(fillets)
    nbrs: dict[int, set[int]] = {}
    for f, g in pairs:
        if (g, f) in pairs:
            nbrs.setdefault(f, set()).add(g)
    chains: list[Chain] = []
    refused: dict[int, str] = {}
    seen: set[int] = set()
    for f0 in sorted(nbrs):
        if f0 in seen:
            continue
        comp, stack = set(), [f0]
        while stack:
            x = stack.pop()
            if x not in comp:
                comp.add(x)
                stack.extend(nbrs[x] - comp)
        seen |= comp
        ends = [f for f in comp if len(nbrs[f]) == 1]
        if any(len(nbrs[f]) > 2 for f in comp) or len(ends) != 2:
            why = "a chain of tangent fillets that is closed or branches (no two end faces)"
            refused.update({f: why for f in comp})
            continue
        order = [min(ends)]
        while len(order) < len(comp):
            order.append(next(iter(nbrs[order[-1]] - set(order))))
        end_faces = []
        for f, inner in ((order[0], order[1]), (order[-1], order[-2])):
            outer = [s for s in fillets[f].supporting if s != inner]
            end_faces.append(outer[0] if len(outer) == 1 else -1)
        a, b = end_faces
        if a < 0 or b < 0 or a == b or a in fillets or b in fillets:
            why = "a chain of tangent fillets whose end faces are blends or the same face"
            refused.update({f: why for f in comp})
            continue
        chains.append(Chain(tuple(order), (a, b), tuple(fillets[f] for f in order)))
    return chains, refused


def sub_chains(chain: Chain, present: set[int]) -> list[Chain]:
    """The runs of two or more of ``chain``'s members in ``present`` as chains of their own,
    between the others, which are faces like any other once kept (their end faces the kept
    members or the chain's ends; a run of one is a plain fillet)."""
    runs: list[list[int]] = [[]]
    for i, f in enumerate(chain.members):
        if f in present:
            runs[-1].append(i)
        elif runs[-1]:
            runs.append([])
    chains = []
    for run in (r for r in runs if len(r) > 1):
        i, j = run[0], run[-1]
        ends = (chain.toward(i, 0), chain.toward(j, 1))
        members = tuple(chain.members[k] for k in run)
        chains.append(Chain(members, ends, tuple(chain.specs[k] for k in run)))
    return chains


def chain_specs(chain: Chain) -> dict[int, FilletSpec]:
    """The specs the split and the face groups use: a fillet merged whole has one smooth
    edge and one supporting face (the previous member, or the end face, on its side); the
    middle one keeps both."""
    out: dict[int, FilletSpec] = {}
    for i, spec in enumerate(chain.specs):
        if i == chain.middle:
            out[spec.face] = spec
            continue
        prev = chain.toward(i, chain.side(i))
        k = spec.supporting.index(prev)
        out[spec.face] = replace(
            spec,
            smooth_edges=(spec.smooth_edges[k],),
            supporting=(prev,),
            chains=None if spec.chains is None else (spec.chains[k], spec.chains[k]),
        )
    return out


def chain_arcs(
    chain: Chain, end: int, faces: list[Any], medials: dict[int, Medial]
) -> list[Array] | str:
    """The section arcs of the part of ``chain`` that joins end face ``chain.ends[end]``,
    from that face outwards: each (3, 3), three points across one member (from its edge
    towards the end face to its edge towards the middle; the middle half to past its
    medial curve, a last whole member to past its far edge). ``faces[i]`` is the face of
    ``chain.members[i]`` and ``medials`` their medial curves. A reason (str) when a member
    is not an iso-line fillet."""
    idx = range(len(chain.members)) if end == 0 else range(len(chain.members) - 1, -1, -1)
    out: list[Array] = []
    for i in idx:
        if chain.side(i) != end and i != chain.middle:
            break
        f, spec = chain.members[i], chain.specs[i]
        med = medials[f]
        if med.iso not in ("u", "v") or not all(np.isfinite(med.cross)):
            return f"fillet {f} of the chain has no iso-line medial curve"
        k = spec.supporting.index(chain.toward(i, end))
        c0, c1 = med.cross[k], med.cross[1 - k]
        if i == chain.middle:
            stop = med.mid + np.sign(med.mid - c0) * OVERSHOOT
        elif _last_of_side(chain, i, end):
            stop = c1 + np.sign(c1 - c0) * OVERSHOOT
        else:
            stop = c1
        out.append(_arc(faces[i], med, c0, float(stop)))
    return out


def _last_of_side(chain: Chain, i: int, end: int) -> bool:
    """``members[i]`` is the last whole member of side ``end`` and no middle follows."""
    if chain.middle is not None:
        return False
    k = len(chain.members)
    return i == (k // 2 - 1 if end == 0 else k // 2)


def _arc(face: Any, med: Medial, c0: float, c1: float) -> Array:
    """Three points (3, 3) of the iso cross-section of ``face`` from cross parameter ``c0``
    to ``c1`` (at the middle of its along range)."""
    surf = BRep_Tool.Surface_s(face)
    u0, u1, v0, v1 = uv_bounds(face)
    along = 0.5 * (v0 + v1) if med.iso == "u" else 0.5 * (u0 + u1)
    pts = []
    for c in np.linspace(c0, c1, 3):
        uv = (c, along) if med.iso == "u" else (along, c)
        pts.append(xyz(surf.Value(float(uv[0]), float(uv[1]))))
    return np.array(pts)
