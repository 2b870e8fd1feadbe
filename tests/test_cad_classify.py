"""Fillet classification checked against the fillet builder's own history.

Parts are built with OCCT here (``medax.cad.parts``); ``BRepFilletAPI_MakeFillet.Generated``
says exactly which faces are blends. Classification never sees that history.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")

from medax.cad import parts  # noqa: E402
from medax.cad.classify import classify_solid  # noqa: E402
from medax.cad.face_geometry import area_centroid  # noqa: E402
from medax.cad.model import EdgeClass, FaceClass  # noqa: E402
from medax.cad.reader import heal  # noqa: E402


def truth_indices(c, built) -> set[int]:
    """Indices (in ``c``) of the builder's blend faces, matched by area and centroid so
    that healed solids (new TopoDS objects) can be checked too."""
    info = np.array([[f.area, *f.centroid] for f in c.faces])
    out = set()
    for f in built.blends:
        area, cen = area_centroid(f)
        err = np.abs(info[:, 0] - area) + np.linalg.norm(info[:, 1:] - cen, axis=1)
        k = int(np.argmin(err))
        assert err[k] < 1e-6 * max(area, 1.0), "truth face not found in the classified solid"
        out.add(k)
    assert len(out) == len(built.blends)
    return out


def check_exact(built, unify: bool) -> None:
    solid = heal(built.shape, unify=unify) if unify else built.shape
    c = classify_solid(solid)
    truth = truth_indices(c, built)
    found = set(c.blends)
    assert found == truth, f"{built.name}: missed {truth - found}, false {found - truth}"
    # every blend face and every fillet record is consistent
    for rec in c.fillets:
        assert c.faces[rec.face].cls is FaceClass.FILLET
        for side, sup in zip(rec.smooth_edges, rec.supporting, strict=True):
            sup_is_blend = sup in c.blends  # a fillet on a fillet (rounded_box_chain)
            for j in side:
                e = c.edges[j]
                assert e.tangent
                assert set(e.faces) == {rec.face, sup}
                assert (e.cls is EdgeClass.SMOOTH) != sup_is_blend
            if not sup_is_blend:
                assert c.faces[sup].cls is FaceClass.SUPPORTING
        for j in rec.cross_edges:
            assert rec.face in c.edges[j].faces
        if built.radii:
            exact = c.faces[rec.face].surface in ("cylinder", "torus")
            rel = 1e-9 if exact else 1e-2  # freeform blends approximate the rolling ball
            assert any(rec.radius == pytest.approx(r, rel=rel) for r in built.radii)
        else:
            assert rec.radius is None  # a variable-radius blend


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(parts.CATALOGUE))
@pytest.mark.parametrize("unify", [False, True])
def test_catalogue_parts_blends_exact(name, unify):
    check_exact(parts.CATALOGUE[name](), unify)


@pytest.mark.parametrize("seed", range(8))
def test_boxes_with_random_fillets(seed):
    built = parts.box_random(seed)
    check_exact(built, unify=False)


def test_corner_blends_where_three_fillets_meet():
    built = parts.box_random(0)  # seed 0 fillets 11 of 12 edges
    c = classify_solid(built.shape)
    assert len(c.corners) >= 1
    for rec in c.corners:
        assert c.faces[rec.face].surface == "sphere"
        assert rec.radius == pytest.approx(built.radius, rel=1e-12)
        assert len(rec.fillets) >= 2
        assert all(
            c.faces[f].cls in (FaceClass.FILLET, FaceClass.CORNER_BLEND) for f in rec.fillets
        )


def test_slot_end_is_not_a_fillet():
    built = parts.slotted_plate()
    c = classify_solid(built.shape)
    ends = [f for f in c.faces if f.surface == "cylinder" and f.index not in c.blends]
    assert len(ends) == 2
    doubts = {d.face for d in c.doubts}
    for f in ends:
        assert f.cls is FaceClass.PROTECTION
        assert f.index in doubts
        # tangent to both slot walls, exactly as a fillet would be
        tangent_nbrs = {
            g for j in f.edges if c.edges[j].tangent for g in c.edges[j].faces if g != f.index
        }
        assert len(tangent_nbrs) == 2


def test_edge_classes_of_a_supporting_face():
    """Paper Fig. 8: one smooth edge, two semi-smooth, one non-smooth."""
    box = parts.BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
    built = parts.fillet(box, [parts._edges(box)[0]], 2.0, "one_edge")
    c = classify_solid(built.shape)
    assert c.counts()["fillet"] == 1 and c.counts()["supporting"] == 2
    for i in c.indices(FaceClass.SUPPORTING):
        got = sorted(cls.value for cls in c.edge_classes(i).values())
        assert got == ["non_smooth", "semi_smooth", "semi_smooth", "smooth"]


def test_closed_fillet_ring_uses_the_seam_as_cross_edges():
    c = classify_solid(parts.stepped_shaft().shape)
    assert len(c.fillets) == 2
    for rec in c.fillets:
        assert rec.closed and rec.cross_edges[0] == rec.cross_edges[1]
        assert c.edges[rec.cross_edges[0]].is_seam
        assert c.faces[rec.face].surface == "torus"


def test_tangency_tolerance_is_used():
    """A 1-degree crease is not tangent at the default tolerance, tangent at 2 degrees."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Pnt, gp_Vec

    a = np.radians(1.0)
    pts = [(0, 0), (10, 0), (10 + 10 * np.cos(a), 10 * np.sin(a)), (20, 8), (0, 8)]
    poly = BRepBuilderAPI_MakePolygon()
    for x, y in pts:
        poly.Add(gp_Pnt(float(x), float(y), 0.0))
    poly.Close()
    solid = BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(poly.Wire()).Face(), gp_Vec(0, 0, 5))
    c1 = classify_solid(solid.Shape())
    c2 = classify_solid(solid.Shape(), angle_tol=np.radians(2.0))
    crease = [e for e in c1.edges if abs(e.max_angle - a) < 1e-9]
    assert len(crease) == 1
    assert not crease[0].tangent
    assert c2.edges[crease[0].index].tangent


@pytest.mark.parametrize("radii", [(2.0, 3.0, 4.0), (2.0, 2.0, 4.0), (1.0, 3.0, 3.0)])
def test_corner_of_unequal_radii(radii):
    """Three edges at one vertex with different radii: OCCT's vertex patch is 4-sided (a
    torus or B-spline); it must be found as a blend (it is classified as a fillet)."""
    box = parts.BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
    at_origin = [
        e for e in parts._edges(box) if np.count_nonzero(np.abs(parts._edge_mid(e)) < 1e-9) == 2
    ]
    assert len(at_origin) == 3
    mk = parts.BRepFilletAPI_MakeFillet(box)
    for e, r in zip(at_origin, radii, strict=True):
        mk.Add(r, e)
    mk.Build()
    blends = []
    for s in at_origin + [parts.TopoDS.Vertex(v) for v in _vertices(box)]:
        blends.extend(f for f in mk.Generated(s) if not any(f.IsSame(b) for b in blends))
    built = parts.BuiltPart("corner", mk.Shape(), tuple(blends), tuple(sorted(set(radii))))
    c = classify_solid(built.shape)
    assert set(c.blends) == truth_indices(c, built)


def _vertices(shape):
    from OCP.TopAbs import TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer

    out, exp = [], TopExp_Explorer(shape, TopAbs_VERTEX)
    while exp.More():
        out.append(exp.Current())
        exp.Next()
    return out
