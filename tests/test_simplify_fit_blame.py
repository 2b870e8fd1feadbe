"""A merged face whose fit fails is traced to the blend pieces that hold its misfit: those
blends are kept and the others on the same face still go (truth: a part built with OCCT in
which one fillet ends in a step that no smooth surface follows; OCCT's checks and
BRepExtrema distances against the input)."""

from __future__ import annotations

import pytest
from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
from OCP.gp import gp_Pnt

import medax.cad.parts as catalogue
from medax.cad.classify import classify_solid
from medax.cad.reader import heal
from medax.cad.simplify import simplify, specs_from_classification
from medax.cad.simplify.occ import faces_of
from truth import assert_same_solid


def _near(m, p) -> bool:  # type: ignore[no-untyped-def]
    return bool(sum((a - b) ** 2 for a, b in zip(m, p, strict=True)) < 1e-12)


def _filleted_union(a, b, mids, name: str):  # type: ignore[no-untyped-def]
    """The union of solids ``a`` and ``b`` with the edges whose midpoints are ``mids``
    filleted (r 1), classified, and simplified."""
    fused = heal(BRepAlgoAPI_Fuse(a, b).Shape())
    edges = catalogue._select(fused, lambda m: any(_near(m, p) for p in mids))
    assert len(edges) == len(mids)
    part = catalogue.fillet(fused, edges, 1.0, name)
    cls = classify_solid(heal(part.shape))
    return part, cls, simplify(cls.shape, specs_from_classification(cls))


@pytest.fixture(scope="module")
def stepped():
    """A box 10^3 on the corner of a box 10 x 10 x 10 below it (overlap 5 x 5): the concave
    edge between the upper box's bottom and the lower box's side y = 5 ends at the upper
    box's side x = 0, where the lower side continues past it (a step); the lower box's
    vertical edge at x = -5, y = 5 lies on the same side face, far from the step. Both
    filleted, r 1."""
    upper = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10.0, 10.0, 10.0).Shape()
    lower = BRepPrimAPI_MakeBox(gp_Pnt(-5, -5, -10), 10.0, 10.0, 10.0).Shape()
    return _filleted_union(upper, lower, [(2.5, 5.0, 0.0), (-5.0, 5.0, -5.0)], "stepped")


@pytest.mark.slow
def test_the_step_fillet_is_kept_and_its_neighbour_goes(stepped):
    part, cls, r = stepped
    specs = specs_from_classification(cls)
    assert len(specs.fillets) == 2
    faces = list(faces_of(cls.shape))
    from OCP.BRepAdaptor import BRepAdaptor_Surface

    axis = {
        s.face: BRepAdaptor_Surface(faces[s.face]).Cylinder().Axis().Direction()
        for s in specs.fillets
    }
    step = next(f for f, d in axis.items() if abs(d.X()) > 0.99)  # along x: the concave one
    convex = next(f for f in axis if f != step)
    assert r.blends_removed == [convex]
    ((kept, why),) = r.blends_kept
    assert kept == step
    assert "on this blend's piece" in why and "fitted surface error" in why
    assert r.valid and r.faces_after == r.faces_before - 1
    assert_same_solid(part.shape, r, 6, 6)


def test_a_fit_too_large_leaves_out_the_pieces_that_set_its_spacing():
    """The knot spacing is a quarter of the smallest curvature radius: the pieces of that
    radius are left out; when every curved piece has it, none is singled out."""
    import numpy as np
    from matplotlib.path import Path

    from medax.cad.simplify.fitted import _finest, _Member

    def member(kind: str, radius: float, x: float) -> _Member:
        sq = np.array([[x - 1, -1], [x + 1, -1], [x + 1, 1], [x - 1, 1]], float)
        return _Member(kind, np.zeros(3), np.zeros(3), radius, Path(sq), (), (sq,))

    pieces = [member("plane", 0.0, 0.0)] + [member("cylinder", 2.0, x) for x in range(1, 5)]
    assert _finest(pieces) == frozenset()
    pieces[2] = member("torus", 0.5, 2.0)
    pieces[4] = member("cylinder", 0.502, 4.0)  # within 1 %
    assert _finest(pieces) == {2, 4}
    assert _finest(pieces[:2]) == frozenset()  # one curved piece: nothing to single out


@pytest.fixture(scope="module")
def rib():
    """A plate 40 x 30 x 5 with a rib 20 x 2 x 10 on top (x 10 - 30, y 14 - 16): the rib's
    foot on its side y = 14 filleted (r 1) ends at the rib's end faces, where the plate
    continues past it (a step on the plate's side); the plate's top edge at y = 0 filleted
    too (r 1), on the same top face."""
    plate = BRepPrimAPI_MakeBox(40.0, 30.0, 5.0).Shape()
    rib_box = BRepPrimAPI_MakeBox(gp_Pnt(10, 14, 5), 20.0, 2.0, 10.0).Shape()
    return _filleted_union(plate, rib_box, [(20.0, 14.0, 5.0), (20.0, 0.0, 5.0)], "rib")


@pytest.mark.slow
def test_a_fillet_ending_at_a_step_goes_whole_into_its_other_face(rib):
    """The rib's foot fillet cannot share the plate's merged face (the step at its ends),
    but its own piece holds that misfit: the plate is fitted with the edge fillet's half
    alone, and the foot fillet goes whole into the rib's side, an exact extrusion."""
    part, cls, r = rib
    specs = specs_from_classification(cls)
    assert len(specs.fillets) == 2
    assert sorted(r.blends_removed) == sorted(s.face for s in specs.fillets)
    assert r.blends_kept == []
    assert any("merged whole" in n for n in r.notes)
    assert r.valid and r.faces_after == r.faces_before - 2
    assert_same_solid(part.shape, r, 6, 6)


def test_medial_cross_parameters_are_those_of_the_smooth_edges(rib):
    """The cross parameters a medial curve records (the whole-fillet route's profile runs
    to the far one) are the iso-lines of the smooth edges: the surface there lies on them
    (BRepExtrema), on a fillet surface bounded along its length (a cylinder)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopoDS import TopoDS

    from medax.cad.simplify.medial import medial_curve
    from medax.cad.simplify.occ import shape_map

    _, cls, _ = rib
    faces, emap = list(faces_of(cls.shape)), shape_map(cls.shape, TopAbs_EDGE)
    for spec in specs_from_classification(cls).fillets:
        edges = [TopoDS.Edge(emap.FindKey(i + 1)) for i in spec.smooth_edges]
        m = medial_curve(faces[spec.face], *edges)
        assert not isinstance(m, str), m
        surf = BRep_Tool.Surface_s(faces[spec.face])
        for c, edge in zip(m.cross, edges, strict=True):
            for v in (2.0, 9.0):  # along the cylinder, inside both fillets' lengths
                p = surf.Value(c, v) if m.iso == "u" else surf.Value(v, c)
                dist = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(p).Vertex(), edge)
                assert dist.Value() < 1e-9
