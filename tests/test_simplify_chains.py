"""Chains of tangent fillets: slabs whose end is a row of tangent arcs, each a fillet whose
supporting face is the next arc (the corpus's isolated_blends_test_16 and GrabCAD part 19
have them), built here with OCCT from a profile of lines and arcs extruded along y.

Truth: the profile's own geometry. Every arc is removed, the solid is valid, its volume
within 1e-6 of the input's (measured by OCCT on the input) and its boundary within the
tolerance of the input's both ways (BRepExtrema on the whole solids); the merged faces are
exact extrusions, so the distances are at the rounding level; the new edge of the
three-arc end lies on the middle arc's medial line (its mid angle, from the profile's
centres), and the two-arc corner's new edge is the arcs' tangency line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeWire,
)
from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
from OCP.GC import GC_MakeArcOfCircle, GC_MakeSegment
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import edge_points, shape_map
from truth import assert_same_solid, classified_and_simplified

pytestmark = pytest.mark.slow  # OCCT-heavy: module fixtures build and simplify parts

WIDTH = 10.0  # extrusion along y


def _p(x: float, z: float) -> gp_Pnt:
    return gp_Pnt(x, 0.0, z)


def _arc(c: np.ndarray, r: float, a0: float, a1: float):  # type: ignore[no-untyped-def]
    """Arc of centre ``c`` (x, z), radius ``r`` from angle ``a0`` to ``a1`` (rad)."""
    pts = [c + r * np.array([math.cos(a), math.sin(a)]) for a in (a0, 0.5 * (a0 + a1), a1)]
    return GC_MakeArcOfCircle(*(_p(*q) for q in pts)).Value()


def _slab(pieces: list) -> object:  # type: ignore[type-arg]
    wire = BRepBuilderAPI_MakeWire()
    for c in pieces:
        wire.Add(BRepBuilderAPI_MakeEdge(c).Edge())
    face = BRepBuilderAPI_MakeFace(wire.Wire()).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(0.0, WIDTH, 0.0)).Shape()


#: three-arc end: r 10, 33, 10 between the bottom (z = 0) and top (z = 56) planes
A, H, R1, R2 = 96.0, 56.0, 10.0, 33.0
C1 = np.array([A, R1])
C2 = np.array([A - math.sqrt((R2 - R1) ** 2 - (H / 2 - R1) ** 2), H / 2])
C3 = np.array([A, H - R1])


def three_arc_slab() -> object:
    phi = math.atan2(C1[1] - C2[1], C1[0] - C2[0])  # direction c2 -> c1 (below the x-axis)
    return _slab(
        [
            GC_MakeSegment(_p(0, 0), _p(A, 0)).Value(),
            _arc(C1, R1, -math.pi / 2, phi),
            _arc(C2, R2, phi, -phi),
            _arc(C3, R1, -phi, math.pi / 2),
            GC_MakeSegment(_p(A, H), _p(0, H)).Value(),
            GC_MakeSegment(_p(0, H), _p(0, 0)).Value(),
        ]
    )


#: two-arc corner between the bottom (z = 0) and the right side (x = W): r 4 then r 10,
#: tangent at the angle -45 degrees
W, HT, S1, S2 = 40.0, 30.0, 4.0, 10.0
U = np.array([math.cos(-math.pi / 4), math.sin(-math.pi / 4)])
D2 = np.array([W - S2, S1 - (S2 - S1) * U[1]])  # the r 10 centre
D1 = D2 + (S2 - S1) * U  # the r 4 centre, at height S1
TANGENCY = D2 + S2 * U


def two_arc_slab() -> object:
    return _slab(
        [
            GC_MakeSegment(_p(0, 0), _p(D1[0], 0)).Value(),
            _arc(D1, S1, -math.pi / 2, -math.pi / 4),
            _arc(D2, S2, -math.pi / 4, 0.0),
            GC_MakeSegment(_p(W, D2[1]), _p(W, HT)).Value(),
            GC_MakeSegment(_p(W, HT), _p(0, HT)).Value(),
            GC_MakeSegment(_p(0, HT), _p(0, 0)).Value(),
        ]
    )


#: a two-arc chain (r 4 from the bottom plane, then r 10) ending on a convex cylinder of
#: radius 30 (tangent to the r 10 arc, sharp against the top plane): no fillet itself
Q1 = np.array([60.0, 4.0])
QU = np.array([math.cos(-math.pi / 4), math.sin(-math.pi / 4)])
Q2 = Q1 - 6.0 * QU
Q3 = Q2 - np.array([20.0, 0.0])
QTOP = Q3 + 30.0 * np.array([math.cos(0.7), math.sin(0.7)])


def cylinder_end_slab() -> object:
    return _slab(
        [
            GC_MakeSegment(_p(0, 0), _p(Q1[0], 0)).Value(),
            _arc(Q1, 4.0, -math.pi / 2, -math.pi / 4),
            _arc(Q2, 10.0, -math.pi / 4, 0.0),
            _arc(Q3, 30.0, 0.0, 0.7),
            GC_MakeSegment(_p(*QTOP), _p(0, QTOP[1])).Value(),
            GC_MakeSegment(_p(0, QTOP[1]), _p(0, 0)).Value(),
        ]
    )


@pytest.fixture(scope="module")
def three():
    return classified_and_simplified(three_arc_slab())


@pytest.fixture(scope="module")
def two():
    return classified_and_simplified(two_arc_slab())


def _inner_edges(shape) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    """Sample points of the edges along y (the profile's joints) of ``shape``."""
    out = []
    emap = shape_map(shape, TopAbs_EDGE)
    for i in range(1, emap.Size() + 1):
        pts = edge_points(TopoDS.Edge(emap.FindKey(i)), 9)
        if np.ptp(pts[:, 1]) > 0.9 * WIDTH and np.ptp(pts[:, 0]) < 1e-9:
            out.append(pts)
    return out


def test_three_arc_chain_removed(three):
    cls, r = three
    assert len(cls.fillets) == 3
    assert not r.blends_kept and len(r.blends_removed) == 3
    assert (r.faces_before, r.faces_after) == (8, 5)
    assert_same_solid(cls.shape, r, 9, 16, volume_tol=1e-10, deviation_tol=1e-9)
    assert {g.surface for g in r.face_groups if g.halves} == {"extrusion"}


def test_three_arc_chain_split_on_the_middle_arcs_medial_line(three):
    """The one new edge along y is the middle arc's point at angle 0 (the profile is
    symmetric about z = H / 2); the other joints along y are the slab's sharp corners."""
    _, r = three
    joints = _inner_edges(r.shape)
    want = C2 + R2 * np.array([1.0, 0.0])
    d = [np.abs(j[:, [0, 2]] - want).max() for j in joints]
    assert min(d) <= 1e-9 * r.diagonal
    assert len(joints) == 3  # and the two sharp corners on the left: none at the arcs' ends


def test_two_arc_chain_removed_at_the_tangency_line(two):
    cls, r = two
    assert len(cls.fillets) == 2
    assert not r.blends_kept and len(r.blends_removed) == 2
    assert (r.faces_before, r.faces_after) == (8, 6)
    assert_same_solid(cls.shape, r, 9, 16, volume_tol=1e-10, deviation_tol=1e-9)
    joints = _inner_edges(r.shape)
    d = [np.abs(j[:, [0, 2]] - TANGENCY).max() for j in joints]
    assert min(d) <= 1e-9 * r.diagonal
    assert len(joints) == 4  # and the three sharp corners


def test_chain_ending_on_a_cylinder():
    """The r 10 arc merges whole into the radius-30 cylinder it is tangent to: an arc -
    arc profile extruded (the end face's section is an arc, not a line)."""
    cls, r = classified_and_simplified(cylinder_end_slab())
    assert len(cls.fillets) == 2
    assert not r.blends_kept and len(r.blends_removed) == 2
    assert (r.faces_before, r.faces_after) == (8, 6)
    assert_same_solid(cls.shape, r, 9, 16, volume_tol=1e-10, deviation_tol=1e-9)
    assert {g.surface for g in r.face_groups if g.halves} == {"extrusion"}


@pytest.mark.parametrize("bad", [{4}, {0}, set()])
def test_isolation_never_splits_a_chain(bad):
    """A chain is one unit of the search: every attempt holds all of its fillets or none,
    and a failing member keeps the whole chain (truth: the attempts' own selections)."""
    import math as m

    from medax.cad.simplify.search import isolate
    from medax.cad.simplify.specs import FilletSpec

    specs = {f: FilletSpec(f, (2 * f, 2 * f + 1), (100 + f, 101 + f), 1.0) for f in range(12)}
    chain = {3, 4, 5}
    calls: list[set[int]] = []

    def attempt(sel):  # type: ignore[no-untyped-def]
        calls.append(set(sel))
        hit = sorted(set(sel) & bad)
        return f"fillet {hit[0]} fails" if hit else ("ok", frozenset(sel))

    kept: dict[int, str] = {}
    _, accepted = isolate(specs, attempt, kept, lambda s: None, m.inf, "first", [chain])
    assert all(chain <= c or not chain & c for c in calls)
    lost = chain | bad if bad & chain else bad
    assert set(kept) == lost and set(accepted) == set(specs) - lost
