"""A variable-radius fillet (a B-spline blend, radius growing linearly 1 -> 3 along a box
edge): split along its mid iso-line, merged by fitted surfaces into both planes.

Truth: OCCT's validity check, the box's symmetry (the new edge between the two planes lies
in their bisector plane x = y), and distances between old and new boundaries measured on the
whole solids both ways.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import edge_points, shape_map
from truth import assert_same_solid, classified_and_simplified

pytestmark = pytest.mark.slow  # OCCT-heavy: module fixtures build and simplify parts


@pytest.fixture(scope="module")
def variable():
    from medax.cad.parts import variable_radius_box

    return classified_and_simplified(variable_radius_box().shape)


def test_variable_fillet_removed(variable):
    cls, r = variable
    assert len(cls.blends) == 1
    assert (r.faces_before, r.faces_after) == (7, 6) and not r.blends_kept
    assert_same_solid(cls.shape, r, 9, 16)
    assert {g.surface for g in r.face_groups if g.halves} == {"fitted"}
    assert 0 < r.fit_error <= 1e-6 * r.diagonal


def test_new_edge_on_the_bisector_plane(variable):
    """The filleted edge is the box's z edge at x = y = 0 between the planes x = 0 and
    y = 0: the new edge between them (the medial curve) lies on x = y, inside the old
    rounded corner (0 < x < 3)."""
    _, r = variable
    emap = shape_map(r.shape, TopAbs_EDGE)
    found = []
    for i in range(1, emap.Size() + 1):
        p = edge_points(TopoDS.Edge(emap.FindKey(i)), 21)
        if np.all(p[:, :2].max(axis=1) < 3.0) and np.ptp(p[:, 2]) > 9.0:
            found.append(p)
    assert len(found) == 1
    (p,) = found
    assert np.abs(p[:, 0] - p[:, 1]).max() <= 1e-9 * r.diagonal
    assert p[:, 0].min() > 0.2  # r = 1 at the bottom: 1 - 1/sqrt(2) = 0.29 from the edge
