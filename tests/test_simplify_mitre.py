"""Fillets meeting in a mitre (a corner whose third edge is sharp): one of each pair is
kept so that the other can be merged (truth: OCCT's checks and BRepExtrema distances)."""

from __future__ import annotations

import pytest
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

import medax.cad.parts as catalogue
from medax.cad.simplify.mitre import mitre_keeps
from medax.cad.simplify.specs import CornerSpec
from truth import assert_same_solid, classified_and_simplified


@pytest.fixture(scope="module")
def mitred():
    """A 30 x 20 x 10 box with its top front (y = 0) and top right (x = 30) edges filleted:
    the two cylinders meet in a mitre above the sharp vertical edge at (30, 0)."""
    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()

    def top_front_right(m):
        return abs(m[2] - 10.0) < 1e-9 and (abs(m[1]) < 1e-9 or abs(m[0] - 30.0) < 1e-9)

    part = catalogue.fillet(box, catalogue._select(box, top_front_right), 2.0, "mitred")
    return (part, *classified_and_simplified(part.shape))


def test_mitre_pair_keeps_one_merges_the_other(mitred):
    part, cls, r = mitred
    assert len(cls.blends) == 2
    assert (r.faces_before, r.faces_after) == (8, 7)
    assert len(r.blends_removed) == 1 and len(r.blends_kept) == 1
    (_, why), other = r.blends_kept[0], r.blends_removed[0]
    assert f"meets fillet {other} in a mitre" in why
    assert {g.surface for g in r.face_groups if g.halves} == {"extrusion"}
    assert_same_solid(part.shape, r, 6, 6, volume_tol=1e-9, deviation_tol=1e-7)


def test_mitre_keeps_covers_every_pair():
    # a chain 1 - 2 - 3: keeping 2 breaks both pairs
    assert list(mitre_keeps([(1, 2), (2, 3)], {})) == [2]
    # two separate pairs: one of each; the one meeting fewer corner blends is kept
    corners = {9: CornerSpec(9, (4, 6, 7), (0, 1, 2))}
    keep = mitre_keeps([(4, 5), (6, 8)], corners)
    assert sorted(keep) == [5, 8]
    assert all("in a mitre" in why for why in keep.values())
    assert mitre_keeps([], corners) == {}
