"""The changed groups' measures kept from one attempt to the next (truth: the same
measures computed again without the cache, copies and scaled copies of faces, and a
search forced on a part built with OCCT whose result must not depend on the cache)."""

from __future__ import annotations

import pytest
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy, BRepBuilderAPI_Transform
from OCP.gp import gp_Pnt, gp_Trsf

from medax.cad.simplify import local_measure as L
from medax.cad.simplify import parts as P
from medax.cad.simplify import pipeline, simplify, specs_from_blend_faces
from medax.cad.simplify.occ import faces_of
from medax.cad.simplify.search import Failure


@pytest.fixture(scope="module")
def box4():
    part = P.box_vertical_fillets(40.0, 30.0, 20.0, 5.0)
    return part, simplify(part.shape, specs_from_blend_faces(part.shape, part.blends))


def _scaled(shape, s: float):
    t = gp_Trsf()
    t.SetScale(gp_Pnt(0.0, 0.0, 0.0), s)
    return BRepBuilderAPI_Transform(shape, t, True).Shape()


def test_group_key_is_the_geometry(box4):
    """A copy of a group of faces has its key; the group with one face scaled by 1e-6, or
    in another order, does not."""
    _, r = box4
    faces = list(faces_of(r.shape))[:3]
    copies = [next(iter(faces_of(BRepBuilderAPI_Copy(f).Shape()))) for f in faces]
    moved = next(iter(faces_of(_scaled(faces[1], 1.000001))))
    key = L.group_key(faces)
    assert len(key) == 3 and key == L.group_key(copies)
    assert key != L.group_key([faces[0], moved, faces[2]])
    assert key != L.group_key([faces[1], faces[0], faces[2]])
    o = L._centre(faces)
    assert L.face_key(faces[0], o) == key[0] and L.face_key(faces[0], o + 1e-9) != key[0]


def test_measures_compute_once():
    cache, calls = L.Measures(), []

    def compute() -> float:
        calls.append(1)
        return 2.5

    assert cache.get(("a", 1), compute) == 2.5 and cache.get(("a", 1), compute) == 2.5
    assert cache.get(("a", 2), compute) == 2.5
    assert len(calls) == 2 and cache.hits == 1


def test_search_reuses_the_measures_without_changing_the_result(box4, monkeypatch):
    """A search after a refused first attempt (forced here: the first validation's result
    replaced by a failure traced to one fillet) measures the groups the next attempt
    rebuilds as before from the cache, and gives the same solid and numbers as without it."""
    part, _ = box4
    specs = specs_from_blend_faces(part.shape, part.blends)
    real = pipeline.validated
    jobs: list = []

    def first_refused(job, *args):  # type: ignore[no-untyped-def]
        out = real(job, *args)
        jobs.append(job)
        return Failure("refused (test)", {part.blends[0]}) if len(jobs) == 1 else out

    monkeypatch.setattr(pipeline, "validated", first_refused)
    r = simplify(part.shape, specs)
    assert sorted(r.blends_removed) == sorted(part.blends[1:]) and r.valid
    assert jobs[-1].measures.hits > 0
    jobs.clear()
    monkeypatch.setattr(L.Measures, "get", lambda self, key, compute: compute())
    plain = simplify(part.shape, specs)
    assert sorted(plain.blends_removed) == sorted(r.blends_removed)
    assert (plain.faces_after, plain.volume_after, plain.max_deviation) == (
        r.faces_after,
        r.volume_after,
        r.max_deviation,
    )


def test_areas_through_the_cache_are_the_same_bits(box4):
    """The area change summed face by face through the cache equals OCCT's sum over the
    compound to the bit, and a second measure computes nothing."""
    part, r = box4
    old, new = list(faces_of(part.shape)), list(faces_of(r.shape))
    plain = L.area_delta(new, old, 1e-8)
    cache = L.Measures()
    assert L.area_delta(new, old, 1e-8, cache) == plain
    stored, hits = len(cache.values), cache.hits
    assert L.area_delta(new, old, 1e-8, cache) == plain
    assert len(cache.values) == stored and cache.hits == hits + len(new) + len(old)
    assert abs(plain - (L._area(new, 1e-8) - L._area(old, 1e-8))) == 0.0


def test_component_origins_are_the_centres_of_connected_sets():
    """Faces that share edges get one point, the centre of their set; a separate set gets
    its own. A closed set's contributions from its point sum to its volume (the point
    cancels), and measured again through the cache they cost nothing and keep their bits
    (after a new round, the keys' default integrals only)."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    a = list(faces_of(BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 2.0, 3.0, 4.0).Shape()))
    b = list(faces_of(BRepPrimAPI_MakeBox(gp_Pnt(10, 0, 0), 1.0, 1.0, 1.0).Shape()))
    new = a + b
    o = L.component_origins(new, [[] for _ in new])
    assert o.shape == (12, 3)
    assert (o[:6] == [1.0, 1.5, 2.0]).all() and (o[6:] == [10.5, 0.5, 0.5]).all()
    cache = L.Measures()
    shares = L.contributions(new, [], 1.0, 1e-6, o, cache)
    assert shares[:6].sum() == pytest.approx(24.0, rel=1e-12)
    assert shares[6:].sum() == pytest.approx(1.0, rel=1e-12)
    calls: list[float | None] = []
    real = L._contribution

    def counted(face, origin, eps, gk=False):  # type: ignore[no-untyped-def]
        calls.append(eps)
        return real(face, origin, eps, gk)

    L._contribution, saved = counted, L._contribution
    try:
        again = L.contributions(new, [], 1.0, 1e-6, o, cache)
        assert calls == []  # the same faces: their keys are kept too
        cache.new_round()  # (a new attempt: the faces are looked up by their geometry)
        third = L.contributions(new, [], 1.0, 1e-6, o, cache)
    finally:
        L._contribution = saved
    assert (again == shares).all() and (third == shares).all()
    assert calls == [None] * 12  # the keys' default integrals only, no adaptive integral


def test_tolerance_band_is_tolerance_times_length_over_distinct_edges():
    """The band of a box's faces: each distinct edge's tolerance x length once, also where
    two faces share it (truth: the box's edge lengths)."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.TopoDS import TopoDS

    from medax.cad.simplify.occ import edges_of

    box = BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape()
    builder = BRep_Builder()
    for e in edges_of(box):
        builder.UpdateEdge(TopoDS.Edge(e), 2e-3)
    faces = list(faces_of(box))
    assert L.tolerance_band(faces) == pytest.approx(4 * (10 + 20 + 30) * 2e-3, rel=1e-12)
    one = min(faces, key=lambda f: L._area([f], 1e-9))  # the 10 x 20 face
    assert L.tolerance_band([one]) == pytest.approx(2 * (10 + 20) * 2e-3, rel=1e-12)
