"""The changed groups' measures kept from one attempt to the next (truth: the same
integrals computed again without the cache, closed-form volumes of a scaled box, and a
search forced on a part built with OCCT whose result must not depend on the cache)."""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy, BRepBuilderAPI_Transform
from OCP.gp import gp_Pnt, gp_Trsf

from medax.cad.simplify import local_measure as L
from medax.cad.simplify import parts as P
from medax.cad.simplify import pipeline, simplify, specs_from_blend_faces
from medax.cad.simplify.occ import faces_of
from medax.cad.simplify.search import Failure
from medax.cad.simplify.validate import volumes


@pytest.fixture(scope="module")
def box4():
    part = P.box_vertical_fillets(40.0, 30.0, 20.0, 5.0)
    return part, simplify(part.shape, specs_from_blend_faces(part.shape, part.blends))


def _scaled(shape, s: float):
    t = gp_Trsf()
    t.SetScale(gp_Pnt(0.0, 0.0, 0.0), s)
    return BRepBuilderAPI_Transform(shape, t, True).Shape()


def test_group_origins_and_cached_integrals(box4):
    """A closed set of faces measured from any one point gives the same change (here the
    box scaled by 1.001: 1.001^3 - 1); points that differ within it do not (the origins
    are used); a second measure through the cache computes nothing and returns the same
    bits."""
    part, r = box4
    old = list(faces_of(part.shape))
    big = list(faces_of(_scaled(r.shape, 1.001)))
    v_old = volumes(part.shape)[0]
    true = 1.001**3 - 1.0
    faces = [*big, *old]
    far = np.tile([100.0, -50.0, 30.0], (len(faces), 1))
    assert L.group_origins([faces]).shape == (len(faces), 3)
    assert np.allclose(L.group_origins([faces]), L._centre(faces))
    shares = L.contributions(big, old, v_old, 1e-6, far)
    assert abs(shares.sum() - true) <= 1e-9
    split = far.copy()
    split[: len(big) // 2] = 0.0  # half the new faces from another point: no closed set
    assert abs(L.contributions(big, old, v_old, 1e-6, split).sum() - true) > 1e-3
    cache = L.Measures()
    d1 = L.local_volume_change(big, old, v_old, 1e-6, None, None, far, cache)
    assert d1 is not None and abs(d1 - true) <= 1e-9
    stored, hits = len(cache.values), cache.hits
    d2 = L.local_volume_change(big, old, v_old, 1e-6, None, None, far, cache)
    assert d2 == d1 and len(cache.values) == stored and cache.hits > hits
    assert d1 == L.local_volume_change(big, old, v_old, 1e-6, None, None, far)


def test_face_key_is_the_geometry(box4):
    """A copy of a face has its key; the face scaled, or measured from another point, does
    not."""
    _, r = box4
    face = next(iter(faces_of(r.shape)))
    o = np.array([1.0, 2.0, 3.0])
    same = next(iter(faces_of(BRepBuilderAPI_Copy(face).Shape())))
    moved = next(iter(faces_of(_scaled(face, 1.000001))))
    assert L.face_key(face, o) == L.face_key(same, o)
    assert L.face_key(face, o) != L.face_key(moved, o)
    assert L.face_key(face, o) != L.face_key(face, o + 1e-9)


def test_search_reuses_the_measures_without_changing_the_result(box4, monkeypatch):
    """A search after a refused first attempt (forced here: the first validation's result
    replaced by a failure traced to one fillet) measures the groups the next attempt
    rebuilds as before from the cache, and gives the same solid and numbers as without it."""
    part, _ = box4
    specs = specs_from_blend_faces(part.shape, part.blends)
    real = pipeline._validated
    jobs: list = []

    def first_refused(job, *args):  # type: ignore[no-untyped-def]
        out = real(job, *args)
        jobs.append(job)
        return Failure("refused (test)", {part.blends[0]}) if len(jobs) == 1 else out

    monkeypatch.setattr(pipeline, "_validated", first_refused)
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
