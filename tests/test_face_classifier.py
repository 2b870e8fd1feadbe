"""Point-in-face tests in a face's parameters, many points at once
(:class:`medax.cad.simplify.face_classifier.FaceClassifier`).

Truth: OCCT's own classifier (``IntTools_FClass2d``, one point at a time) on the same
points: random points over each face's parameter box and a tenth beyond it, points on the
boundary (the pcurves' own points) and points just inside and outside it, on planar faces
with holes, a cylinder's periodic face with its seam, a sphere's faces with degenerate
edges at the poles and the fitted B-spline faces of a simplified part.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRepAdaptor import BRepAdaptor_Curve2d
from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
from OCP.BRepPrimAPI import (
    BRepPrimAPI_MakeBox,
    BRepPrimAPI_MakeCylinder,
    BRepPrimAPI_MakeSphere,
)
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Pnt2d
from OCP.IntTools import IntTools_FClass2d
from OCP.TopAbs import TopAbs_OUT

from medax.cad.simplify.face_classifier import FaceClassifier
from medax.cad.simplify.occ import edges_of, faces_of, uv_bounds

TOL = 1e-7


def _plate_with_holes():
    box = BRepPrimAPI_MakeBox(40.0, 30.0, 5.0).Shape()
    for x, y, r in ((10.0, 10.0, 4.0), (28.0, 18.0, 6.5)):
        hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x, y, -1.0), gp_Dir(0, 0, 1)), r, 7.0)
        box = BRepAlgoAPI_Cut(box, hole.Shape()).Shape()
    return box


def _fitted_faces():
    from medax.cad.classify import classify_file
    from medax.cad.simplify import simplify, specs_from_classification
    from medax.cad.simplify.local_measure import _bspline
    from medax.samples import sample_path

    cls = classify_file(str(sample_path("box-12-edges.step")))[0]
    r = simplify(cls.shape, specs_from_classification(cls))
    faces = [f for f in faces_of(r.shape) if _bspline(f)]
    assert faces
    return faces


def _points(face, rng):
    """Random points over the face's parameter box (and a tenth beyond), the boundary's
    own points and points 1e-9 and 1e-5 of the box off them both ways."""
    u0, u1, v0, v1 = uv_bounds(face)
    du, dv = u1 - u0, v1 - v0
    pts = [
        np.column_stack(
            [rng.uniform(u0 - 0.1 * du, u1 + 0.1 * du, 2000),
             rng.uniform(v0 - 0.1 * dv, v1 + 0.1 * dv, 2000)]
        )
    ]  # fmt: skip
    for e in edges_of(face):
        c = BRepAdaptor_Curve2d(e, face)
        t = np.linspace(c.FirstParameter(), c.LastParameter(), 25)
        on = np.array([c.Value(x).Coord() for x in t.tolist()])
        pts.append(on)
        for off in (1e-9, 1e-5):
            step = off * np.array([du, dv])
            pts += [on + step, on - step, on + step * [1, -1], on - step * [1, -1]]
    return np.vstack(pts)


@pytest.mark.parametrize(
    "shape",
    [
        pytest.param(_plate_with_holes, id="plate with holes"),
        pytest.param(lambda: BRepPrimAPI_MakeCylinder(3.0, 8.0).Shape(), id="cylinder"),
        pytest.param(lambda: BRepPrimAPI_MakeSphere(5.0).Shape(), id="sphere"),
        pytest.param(lambda: _fitted_faces(), id="fitted faces"),
    ],
)
def test_classifier_answers_as_occt(shape):
    rng = np.random.default_rng(3)
    made = shape()
    faces = made if isinstance(made, list) else list(faces_of(made))
    for face in faces:
        uv = _points(face, rng)
        occ = IntTools_FClass2d(face, TOL)
        want = np.array([occ.Perform(gp_Pnt2d(u, v)) != TopAbs_OUT for u, v in uv.tolist()])
        got = FaceClassifier(face, TOL).inside(uv)
        assert np.array_equal(got, want), np.flatnonzero(got != want)[:10]
        assert want.any() and not want.all()
