"""Failures stay local: a fillet that cannot be merged is kept alone and its neighbours
still go; tidying steps never decide (truth: the search's own bookkeeping against a known
set of failing fillets, OCCT's checks and BRepExtrema distances on a part built with OCCT)."""

from __future__ import annotations

import math

import pytest
from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_FACE, TopAbs_INTERNAL

import medax.cad.parts as catalogue
from medax.cad.classify import classify_solid
from medax.cad.reader import heal
from medax.cad.simplify import simplify, specs_from_classification
from medax.cad.simplify.occ import count, edges_of, faces_of
from medax.cad.simplify.search import Failure, isolate, volume_blame
from medax.cad.simplify.specs import BlendInput, FilletSpec
from medax.cad.simplify.split import split_along
from truth import assert_same_solid


def _chain(n: int) -> dict[int, FilletSpec]:
    """``n`` fillets in one cluster: fillet ``f`` between faces ``100 + f`` and ``101 + f``
    (each neighbour shares a supporting face)."""
    return {f: FilletSpec(f, (2 * f, 2 * f + 1), (100 + f, 101 + f), 1.0) for f in range(n)}


@pytest.mark.parametrize("bad", [{3}, {0, 11}, {2, 3, 4}, set()])
def test_isolation_keeps_exactly_the_failing_fillets(bad):
    specs = _chain(12)
    calls: list[set[int]] = []

    def attempt(sel):
        calls.append(set(sel))
        hit = sorted(set(sel) & bad)
        return f"fillet {hit[0]} fails" if hit else ("ok", frozenset(sel))

    kept: dict[int, str] = {}
    best, accepted = isolate(specs, attempt, kept, lambda m: None, math.inf, "first failed")
    assert set(kept) == bad
    assert all(kept[f] == f"rebuild failed: fillet {f} fails" for f in bad)
    assert set(accepted) == set(specs) - bad
    # the result is an attempt that passed with exactly the accepted fillets
    assert best == ("ok", frozenset(accepted))
    # about 2 log2(n) rebuilds per failing fillet, not one per fillet
    assert len(calls) <= 2 + 2 * max(len(bad), 1) * math.ceil(math.log2(12))


def test_isolation_says_what_each_attempt_did():
    """Each attempt of several fillets is reported: how many went, or why they failed."""
    specs = _chain(8)

    def attempt(sel):
        return "fillet 5 fails" if 5 in sel else ("ok", frozenset(sel))

    said: list[str] = []
    isolate(specs, attempt, {}, said.append, math.inf, "fillet 5 fails")
    assert said[0].startswith("4 more fillets go (4 of 8 so far)")
    assert "4 fillets tried with the 4 accepted failed: fillet 5 fails" in said
    assert "fillet 5 kept: fillet 5 fails" in said and said[-1].endswith("(7 of 8 so far)")


def test_isolation_traced_failures_are_not_bisected():
    """A failure traced to its fillets (a new face that failed its own check): the others
    go in one attempt, the traced ones are tried on their own."""
    specs, bad = _chain(12), {2, 7, 9}
    calls: list[set[int]] = []

    def attempt(sel):
        calls.append(set(sel))
        hit = set(sel) & bad
        return Failure("their faces fail", hit) if hit else ("ok", frozenset(sel))

    kept: dict[int, str] = {}
    first = Failure("their faces fail", bad)
    best, accepted = isolate(specs, attempt, kept, lambda m: None, math.inf, first)
    assert set(kept) == bad and set(accepted) == set(specs) - bad
    assert best == ("ok", frozenset(accepted))
    # the 9 others at once, then the 3 traced ones halved (together they would repeat the
    # first attempt): 5 attempts; bisection alone took 16
    assert len(calls) == 5
    assert set(range(12)) not in calls  # the failed first attempt is not made again


@pytest.mark.parametrize(
    ("shares", "blamed"),
    [
        ([1e-8] * 10 + [1.2e-6], [10]),  # one group holds the change
        ([1.2e-7] * 15, list(range(11))),  # spread thinly: leave out enough for tol / 2
        ([-3e-6, 2e-7, -1e-8], [0]),  # a loss
        ([2e-6, -1e-6, 3e-7], []),  # removing what has the change's sign overshoots
        ([1.5e-6], []),  # all of them: nothing to tell apart, bisect
    ],
)
def test_volume_blame_leaves_out_the_groups_that_account_for_the_change(shares, blamed):
    change = sum(shares)
    got = volume_blame(shares, change, 1e-6)
    assert sorted(got) == blamed
    if got:  # what remains is within half the tolerance
        assert abs(change - sum(shares[i] for i in got)) <= 0.5e-6


def test_volume_blame_needs_shares_that_account_for_the_change():
    """Per-group shares far from the measured change (another integrator's verdict) blame
    nothing: the search bisects instead."""
    assert volume_blame([1e-8] * 10 + [2e-7], 1.5e-6, 1e-6) == []
    assert volume_blame([float("nan"), 2e-6], 2e-6, 1e-6) == []


def test_isolation_out_of_time_keeps_the_rest_with_the_reason():
    specs = _chain(6)
    kept: dict[int, str] = {}
    best, accepted = isolate(specs, lambda sel: "fails", kept, lambda m: None, -1.0, "x")
    assert best is None and accepted == {}
    assert set(kept) == set(specs)
    assert all("time for finding the failing fillets ran out" in why for why in kept.values())


def test_split_drops_a_tool_overshoot_embedded_in_a_neighbour():
    """A tool edge across one face that runs on 1 mm into the coplanar face beside it: the
    splitter embeds the overshoot in that face as an INTERNAL edge; it bounds nothing and
    is removed, the crossed face is split in two."""
    a = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10.0, 10.0, 5.0).Shape()
    b = BRepPrimAPI_MakeBox(gp_Pnt(10, 0, 0), 10.0, 10.0, 5.0).Shape()
    solid = BRepAlgoAPI_Fuse(a, b).Shape()  # the top is two coplanar faces
    tool = BRepBuilderAPI_MakeEdge(gp_Pnt(-1, 5, 5), gp_Pnt(11, 5, 5)).Edge()
    r = split_along(solid, [tool])
    assert r.face_map.Size() == count(solid, TopAbs_FACE) + 1
    assert not [
        e for f in faces_of(r.shape) for e in edges_of(f) if e.Orientation() == TopAbs_INTERNAL
    ]
    assert sorted(set(r.origin)) == list(range(count(solid, TopAbs_FACE)))


@pytest.fixture(scope="module")
def corner_kept():
    """A 30 x 20 x 10 box with the three edges at its corner (0, 0, 10) filleted (r 2): three
    fillets and a sphere corner blend, the corner kept by the caller."""
    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()

    def at_corner(m):
        top = abs(m[2] - 10.0) < 1e-9 and (abs(m[0]) < 1e-9 or abs(m[1]) < 1e-9)
        return top or (abs(m[0]) < 1e-9 and abs(m[1]) < 1e-9)

    part = catalogue.fillet(box, catalogue._select(box, at_corner), 2.0, "corner")
    cls = classify_solid(heal(part.shape))
    specs = specs_from_classification(cls)
    (corner,) = specs.corners
    kept_by_caller = (*specs.refused, (corner.face, "kept by the caller"))
    blends = BlendInput(specs.fillets, kept_by_caller, ())
    return part, corner, simplify(cls.shape, blends)


@pytest.mark.slow
def test_fillets_meeting_a_kept_blend_still_go(corner_kept):
    part, corner, r = corner_kept
    assert sorted(r.blends_removed) == sorted(corner.fillets)
    assert r.blends_kept == [(corner.face, "kept by the caller")]
    assert (r.faces_before, r.faces_after) == (10, 7)
    # the kept corner blend is a face of the result as it was
    assert any(g.whole == (corner.face,) and not g.halves for g in r.face_groups)
    assert_same_solid(part.shape, r, 6, 6)


def test_report_names_each_kept_blend_and_the_picture_marks_it(corner_kept):
    from medax.cli.simplify import colour_keys

    _, corner, r = corner_kept
    rep = r.report()
    assert rep["blends_found"] == 4
    assert rep["blends_kept"] == [
        {"face": corner.face, "radius": None, "reason": "kept by the caller"}
    ]
    assert rep["kept_reasons"] == {"kept by the caller": 1}
    before, after = colour_keys(rep, r.faces_before)
    assert before[corner.face] == -3 and after.count(-3) == 1
    assert all(before[f] == -2 for f in corner.fillets)


def test_reason_kinds_group_numbers():
    from medax.cad.simplify.reasons import reason_counts

    reasons = ["supporting face 4: fitted error 1.2e-02 above 4e-06", "meets fillet 7 in a mitre"]
    reasons.append("supporting face 12: fitted error 3.77e-02 above 4.12e-06")
    reasons.append("volume changed by 1.3e-06 (> 1e-06); 8.0e-07 of it on the faces of fillets 4")
    reasons.append("volume changed by 2e-06 (> 1e-06); 1e-06 of it on the faces of fillets 2, 9")
    assert reason_counts(reasons) == {
        "supporting face N: fitted error N above N": 2,
        "volume changed by N (> N); N of it on the faces of fillets N": 2,
        "meets fillet N in a mitre": 1,
    }


def test_fillet_merged_whole_where_one_face_has_no_surface_for_its_half():
    """A corpus part (Analysis Situs blend corpus, 3boxesblend_01): the fillet's half on one
    supporting plane cannot merge (that plane continues past the fillet's end beside it: no
    smooth surface follows the step), so the whole fillet goes into the other plane, on an
    exact extrusion of a line and the whole quarter circle; the shape is the same."""
    from pathlib import Path

    from medax.cad.classify import classify_file

    (cls,) = classify_file(str(Path(__file__).parent / "data" / "3boxesblend_01.brep"))
    specs = specs_from_classification(cls)
    (fillet,) = specs.fillets
    r = simplify(cls.shape, specs)
    assert r.blends_removed == [fillet.face] and r.blends_kept == []
    assert (r.faces_before, r.faces_after) == (19, 18)
    (group,) = [g for g in r.face_groups if g.halves]
    assert group.halves == (fillet.face,) and group.surface == "extrusion"
    assert any(f"fillet {fillet.face} merged whole" in n for n in r.notes)
    assert_same_solid(cls.shape, r, 6, 6, volume_tol=1e-9, deviation_tol=1e-9)


def _rect(x0: float, y0: float, x1: float, y1: float):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.gp import gp_Pln

    return BRepBuilderAPI_MakeFace(gp_Pln(), x0, x1, y0, y1).Face()


def test_an_area_refusal_is_traced_to_the_group_that_changed_it():
    """Two merged groups: one new face covers exactly its two pieces, the other 1e-3 more
    than its piece (a face trimmed past its edge). The refusal names the second group's
    fillets only (truth: the rectangles' areas)."""
    from types import SimpleNamespace

    from medax.cad.simplify.attempt_checks import _area_refused
    from medax.cad.simplify.groups import Group
    from medax.cad.simplify.job import AREA_TOL

    pieces = {0: _rect(0, 0, 0.5, 1), 1: _rect(0.5, 0, 1, 1), 2: _rect(2, 0, 3, 1)}
    changed = [
        (Group(0, [0, 1], support=7, halves=[0, 1]), _rect(0, 0, 1, 1)),
        (Group(1, [2], support=8, halves=[2]), _rect(2, 0, 3, 1.001)),
    ]
    job = SimpleNamespace(area0=100.0, measures=None)
    split = SimpleNamespace(origin={0: 40, 1: 41, 2: 42})
    sel = {f: FilletSpec(f, (0, 1), (7, 8), 1.0) for f in (40, 41, 42)}
    da = 1e-3 / 100.0
    assert da > AREA_TOL
    got = _area_refused("area changed", da, AREA_TOL, changed, pieces, job, split, sel)  # type: ignore[arg-type]
    assert isinstance(got, Failure)
    assert got.blamed == {42}
    assert "fillets 42" in got
    # shares that do not account for the measured change blame nothing: bisect instead
    got = _area_refused("area changed", 10 * da, AREA_TOL, changed, pieces, job, split, sel)  # type: ignore[arg-type]
    assert got.blamed == frozenset()
