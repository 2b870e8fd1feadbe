"""Elementary surfaces written as other representations (truth: the elementary surfaces the
part was built with, before OCCT's ShapeCustom rewrote them; OCCT's checks and BRepExtrema
distances on the simplified solids)."""

from __future__ import annotations

import pytest
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import (
    GeomAbs_Cylinder,
    GeomAbs_Plane,
    GeomAbs_SurfaceOfRevolution,
    GeomAbs_Torus,
)
from OCP.ShapeCustom import ShapeCustom

from medax.cad.simplify import parts as P
from medax.cad.simplify import simplify, specs_from_blend_faces
from medax.cad.simplify.canonical import canonical_adaptor
from medax.cad.simplify.occ import faces_of
from truth import assert_same_solid


def _as_revolutions(part: P.BuiltPart) -> P.BuiltPart:
    """The part with its cylinders, tori and spheres rewritten as surfaces of revolution
    (lines and circles revolved), as some CAD systems write them; faces in the same order."""
    shape = ShapeCustom.ConvertToRevolution_s(part.shape)
    return P.BuiltPart(part.name + "_revolved", shape, part.blends)


def _radii(ad) -> tuple[float, ...]:  # type: ignore[no-untyped-def]
    kind = ad.GetType()
    if kind == GeomAbs_Cylinder:
        return (ad.Cylinder().Radius(),)
    if kind == GeomAbs_Torus:
        return (ad.Torus().MajorRadius(), ad.Torus().MinorRadius())
    return ()


@pytest.mark.parametrize("build", [P.box_vertical_fillets, P.plate_with_boss])
def test_revolved_faces_are_seen_as_what_they_were(build):  # type: ignore[no-untyped-def]
    part = build() if build is P.plate_with_boss else build(40.0, 30.0, 20.0, 5.0)
    revolved = _as_revolutions(part)
    seen = 0
    for old, new in zip(faces_of(part.shape), faces_of(revolved.shape), strict=True):
        kind = BRepAdaptor_Surface(old).GetType()
        if kind not in (GeomAbs_Cylinder, GeomAbs_Torus):
            continue
        assert BRepAdaptor_Surface(new).GetType() == GeomAbs_SurfaceOfRevolution
        ad = canonical_adaptor(new, 1e-7)
        assert ad.GetType() == kind
        assert _radii(ad) == pytest.approx(_radii(BRepAdaptor_Surface(old)), abs=1e-12)
        seen += 1
    assert seen >= 3  # every cylinder and torus of the part


def test_bspline_cylinder_is_seen_as_a_cylinder():
    part = P.box_vertical_fillets(40.0, 30.0, 20.0, 5.0)
    shape = ShapeCustom.ConvertToBSpline_s(
        ShapeCustom.ConvertToRevolution_s(part.shape), True, True, True, True
    )
    fillets = [f for i, f in enumerate(faces_of(shape)) if i in part.blends]
    for f in fillets:
        ad = canonical_adaptor(f, 1e-7)
        assert ad.GetType() == GeomAbs_Cylinder
        assert ad.Cylinder().Radius() == pytest.approx(5.0, abs=1e-7)
    planes = [f for i, f in enumerate(faces_of(shape)) if i not in part.blends]
    assert all(canonical_adaptor(f, 1e-7).GetType() == GeomAbs_Plane for f in planes)


@pytest.mark.parametrize(
    ("build", "faces", "kind"),
    [
        (lambda: P.box_vertical_fillets(40.0, 30.0, 20.0, 5.0), (10, 6), "extrusion"),
        (lambda: P.plate_with_boss(3.0), (10, 9), "revolution"),
    ],
)
def test_fillets_written_as_revolutions_merge_exactly(build, faces, kind):  # type: ignore[no-untyped-def]
    """The same exact merged surfaces as from the part as built (before: no exact surface
    for a fillet that is a revolved line or circle)."""
    part = _as_revolutions(build())
    r = simplify(part.shape, specs_from_blend_faces(part.shape, part.blends))
    assert (r.faces_before, r.faces_after) == faces and not r.blends_kept
    assert {g.surface for g in r.face_groups if g.halves} == {kind}
    assert_same_solid(part.shape, r, 6, 6, volume_tol=1e-9, deviation_tol=1e-7)
