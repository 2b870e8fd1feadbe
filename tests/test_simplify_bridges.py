"""A fillet riding on a fillet: the box with rounded vertical edges (r = 4) whose top loop of
cylinders and tori (r = 1.5) was filleted after them (the classifier's ``rounded_box_chain``).

Truth: OCCT's validity check, distances between the old and new boundaries measured with
BRepExtrema on the whole solids, and the box's symmetry: the new edge between two side faces
(the vertical fillet's medial line continued by the bridge over the torus) lies in the
bisector plane of the two side planes, checked against the planes' coordinates.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import edge_points, shape_map
from medax.cad.simplify.specs import edge_face_map
from medax.cad.simplify.validate import face_samples
from truth import assert_same_solid, classified_and_simplified

pytestmark = pytest.mark.slow  # OCCT-heavy: module fixtures build and simplify parts

#: the box: x in [0, 30], y in [0, 20], z in [0, 10]; the side planes by coordinate
SIDES = {("x", 0.0), ("x", 30.0), ("y", 0.0), ("y", 20.0)}


@pytest.fixture(scope="module")
def chain():
    from medax.cad.parts import rounded_box_chain

    return classified_and_simplified(rounded_box_chain().shape)


def test_every_fillet_removed(chain):
    cls, r = chain
    assert len(cls.blends) == 12
    assert (r.faces_before, r.faces_after) == (18, 6) and not r.blends_kept
    assert_same_solid(cls.shape, r, 9, 24)


def test_each_torus_is_shared_by_both_side_faces(chain):
    """The lower half of each corner torus is split by its bridge: the torus is absorbed by
    the top face and by both side faces next to its vertical fillet."""
    _, r = chain
    tori = [g for g in r.face_groups if 5 in g.halves]  # a torus of the top loop
    assert len(tori) == 3  # the top face and two side faces
    assert all(g.surface == "fitted" for g in tori)


def _side(face) -> tuple[str, float] | None:
    """The side plane a result face lies on (its samples away from the fillets)."""
    pts = face_samples(face, 9)
    for axis, value in SIDES:
        k = "xyz".index(axis)
        if np.sum(np.abs(pts[:, k] - value) < 1e-4) >= 0.25 * len(pts):
            return axis, value
    return None


def test_side_faces_meet_on_the_bisector_planes(chain):
    """Every point of an edge between two side faces is equidistant from their planes
    (to 1e-9 x diagonal): the medial line of the vertical fillet, then the bridge."""
    _, r = chain
    emap = shape_map(r.shape, TopAbs_EDGE)
    e2f = edge_face_map(r.shape)
    assert shape_map(r.shape, TopAbs_FACE).Size() == 6
    top: dict[tuple[tuple[str, float], ...], float] = {}
    for i in range(1, emap.Size() + 1):
        e = TopoDS.Edge(emap.FindKey(i))
        sides = [_side(TopoDS.Face(f)) for f in e2f.FindFromKey(e)]
        if None in sides or len(sides) != 2:
            continue
        (a1, v1), (a2, v2) = sides  # type: ignore[misc]
        assert a1 != a2
        pts = edge_points(e, 41)
        d1 = np.abs(pts[:, "xyz".index(a1)] - v1)
        d2 = np.abs(pts[:, "xyz".index(a2)] - v2)
        assert np.max(np.abs(d1 - d2)) <= 1e-9 * r.diagonal
        pair = tuple(sorted(sides))  # type: ignore[type-var]
        top[pair] = max(top.get(pair, -np.inf), float(pts[:, 2].max()))
    assert len(top) == 4
    # the edges between two side faces (medial line, then bridge) climb over the torus
    assert min(top.values()) > 10.0 - 1.5 + 0.1


def test_bridge_distances_to_curved_supports():
    """A bridge's equidistance is measured from curved supporting faces too: distances from
    a cylinder's surface by projection equal the closed form |dist to axis - R|, and from
    a plane the closed form."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
    from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane

    from medax.cad.simplify.bridge import _distances
    from medax.cad.simplify.occ import faces_of

    rng = np.random.default_rng(7)
    pts = rng.uniform(-9.0, 9.0, (20, 3))
    cyl = next(
        f
        for f in faces_of(BRepPrimAPI_MakeCylinder(3.0, 5.0).Shape())
        if BRepAdaptor_Surface(f).GetType() == GeomAbs_Cylinder
    )
    want = np.abs(np.hypot(pts[:, 0], pts[:, 1]) - 3.0)  # the axis is z, R = 3
    assert np.max(np.abs(_distances(pts, cyl) - want)) <= 1e-9
    box = BRepPrimAPI_MakeBox(2.0, 3.0, 4.0).Shape()
    planes = [f for f in faces_of(box) if BRepAdaptor_Surface(f).GetType() == GeomAbs_Plane]
    top = next(
        f for f in planes if abs(BRepAdaptor_Surface(f).Plane().Location().Z() - 4.0) < 1e-12
    )
    assert np.max(np.abs(_distances(pts, top) - np.abs(pts[:, 2] - 4.0))) <= 1e-12


def test_a_loose_smooth_edge_lets_the_medial_curve_end_within_its_tolerance():
    """The base's medial curve may end as far from a rider's smooth edge as the edge's own
    tolerance says its curve is known (a loose input: 0028's medial curves end 1.2e-5 -
    3.0e-5 from edges of tolerance 2e-4 - 4e-3), but never farther than 10x the build
    tolerance, and never nearer than the build tolerance on a tight edge."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.gp import gp_Pnt

    from medax.cad.simplify.bridge import LOOSE_REACH, _reach

    tol = 2.6e-5
    edge = BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 0, 0)).Edge()  # 1e-7 tight
    assert _reach(edge, tol) == tol
    BRep_Builder().UpdateEdge(edge, 7e-5)
    assert _reach(edge, tol) == 7e-5
    BRep_Builder().UpdateEdge(edge, 4e-3)
    assert _reach(edge, tol) == LOOSE_REACH * tol


def test_a_bridge_is_taken_within_the_build_tolerance_and_refused_beyond():
    """A bridge off the bisector of its base's supports by less than twice the build
    tolerance is taken, as a medial curve is (a loose input: customblend_04's riders were
    2e-7 - 1.9e-6 off, build tolerance 2.6e-6); farther off it is refused. One support of
    the rounded box's base fillet is moved by ``delta`` along its normal, so every point of
    the bridge (on the bisector of the unmoved pair) is ``delta`` nearer one than the other:
    the measured error is ``delta``."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf, gp_Vec

    from medax.cad.classify import classify_solid
    from medax.cad.parts import rounded_box_chain
    from medax.cad.reader import heal
    from medax.cad.simplify.bridge import bridge_edge
    from medax.cad.simplify.corner import plane_normal
    from medax.cad.simplify.medial import medial_curve
    from medax.cad.simplify.occ import diagonal
    from medax.cad.simplify.specs import specs_from_classification
    from medax.tolerances import BUILD_TOL

    cls = classify_solid(heal(rounded_box_chain().shape))
    faces = shape_map(cls.shape, TopAbs_FACE)
    edges = shape_map(cls.shape, TopAbs_EDGE)
    face = lambda i: TopoDS.Face(faces.FindKey(i + 1))  # noqa: E731
    by_face = {s.face: s for s in specs_from_classification(cls).fillets}

    def medial(spec):
        sides = ([TopoDS.Edge(edges.FindKey(i + 1)) for i in spec.side_edges(k)] for k in (0, 1))
        return medial_curve(face(spec.face), *sides, tol=tol)

    tol = BUILD_TOL * diagonal(cls.shape)
    rider, base, edge = next(
        (s, by_face[b], e)
        for s in by_face.values()
        for b, e in zip(s.supporting, s.smooth_edges, strict=True)
        if b in by_face
    )
    supports = [face(i) for i in base.supporting]
    normal = plane_normal(supports[0])

    def bridge(delta):
        move = gp_Trsf()
        move.SetTranslation(gp_Vec(*map(float, delta * normal)))
        moved = TopoDS.Face(BRepBuilderAPI_Transform(supports[0], move, True).Shape())
        return bridge_edge(
            face(rider.face),
            medial(rider),
            medial(base),
            TopoDS.Edge(edges.FindKey(edge + 1)),
            (moved, supports[1]),
            tol,
        )

    _, err = bridge(0.0)
    assert err <= 1e-12
    for delta in (0.5 * tol, 1.5 * tol):
        r = bridge(delta)
        assert not isinstance(r, str), r
        assert r[1] == pytest.approx(delta, abs=1e-12)
    r = bridge(3.0 * tol)
    assert isinstance(r, str) and "not equidistant" in r
    assert f"{3.0 * tol:.2e}" in r
