"""The volume between a new face and the faces it replaces, measured from their gap
(truth: closed-form volumes of offset planes and cylinders; the fit's own measure)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_Cylinder, GeomAbs_Plane
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

from medax.cad.simplify import attempt_checks as P
from medax.cad.simplify.gap_measure import gap_volume
from medax.cad.simplify.occ import faces_of


def _top(shape, z: float):  # type: ignore[no-untyped-def]
    return next(
        f
        for f in faces_of(shape)
        if BRepAdaptor_Surface(f).GetType() == GeomAbs_Plane
        and abs(BRepAdaptor_Surface(f).Plane().Location().Z() - z) < 1e-9
    )


@pytest.mark.parametrize("delta", [1e-3, -2e-3])
def test_offset_top_face_encloses_delta_times_area(delta):
    """A box's top face moved up by ``delta``: the volume between is delta x 10 x 20 (its
    outward normal is +z, so moving it out adds volume)."""
    old = _top(BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape(), 30.0)
    new = _top(BRepPrimAPI_MakeBox(10.0, 20.0, 30.0 + delta).Shape(), 30.0 + delta)
    v, area = gap_volume(new, [old])
    assert v == pytest.approx(delta * 200.0, rel=1e-9) and area == pytest.approx(200.0, rel=1e-9)


def test_points_past_the_old_faces_take_the_nearest_surface():
    """The new top face runs 1e-3 past the old one's edge, where a far old face (10 below,
    wider) has a foot inside: those points measure from the old top's plane, continued."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox as Box

    delta = 1e-3
    old = _top(Box(10.0, 20.0, 30.0).Shape(), 30.0)
    far = _top(Box(gp_Pnt(-5.0, -5.0, 10.0), 30.0, 30.0, 10.0).Shape(), 20.0)
    new = _top(Box(10.001, 20.0, 30.0 + delta).Shape(), 30.0 + delta)
    assert gap_volume(new, [old, far])[0] == pytest.approx(delta * 10.001 * 20.0, rel=1e-9)


def test_grown_cylinder_encloses_the_annulus():
    """A cylinder's side grown from r = 10 to 10.001: the annulus pi (r1^2 - r0^2) h, to
    the gap's second order (delta / 2r relative)."""

    def side(r: float):  # type: ignore[no-untyped-def]
        cyl = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), r, 5.0)
        return next(
            f for f in faces_of(cyl.Shape()) if BRepAdaptor_Surface(f).GetType() == GeomAbs_Cylinder
        )

    r0, r1, h = 10.0, 10.001, 5.0
    exact = math.pi * (r1**2 - r0**2) * h
    got = gap_volume(side(r1), [side(r0)])[0]
    assert got == pytest.approx(exact, rel=(r1 - r0) / r0)
    # and shrunk: the same volume taken away
    assert gap_volume(side(r0), [side(r1)])[0] == pytest.approx(-exact, rel=(r1 - r0) / r0)


def test_fitted_faces_measured_from_the_gap_when_the_integrators_are_off(monkeypatch):
    """OCCT's integrators put 9.4e-7 of a part's volume on a fitted face whose change the
    fit and the gap both put near 1e-9 (tail_wheel_lg_bracket), and fillets were refused.
    Here the integrators are made off by 3e-6 on each fitted face: the fillet still goes,
    with the gap's value, which agrees with the fit's own measure."""
    from medax.cad.parts import variable_radius_box
    from truth import assert_same_solid, classified_and_simplified

    real = P.contributions

    def off(new, old, before, tol, *points):  # type: ignore[no-untyped-def]
        shares = real(new, old, before, tol, *points)
        bad = [BRepAdaptor_Surface(f).GetType() == GeomAbs_BSplineSurface for f in new]
        return shares + np.array(bad + [False] * len(old)) * 3e-6

    def refuse(new, old, before, tol, expected, shares, *rest):  # type: ignore[no-untyped-def]
        return 6e-6, shares  # the integrators agreeing on the wrong change

    part = variable_radius_box()
    _, measured = classified_and_simplified(part.shape)  # the integrators as they are
    monkeypatch.setattr(P, "contributions", off)
    monkeypatch.setattr(P, "local_volume_shares", refuse)
    cls, r = classified_and_simplified(part.shape)
    assert (r.faces_before, r.faces_after) == (7, 6) and not r.blends_kept
    assert r.volume_rel_change == pytest.approx(measured.volume_rel_change, abs=1e-8)
    assert_same_solid(cls.shape, r, 9, 16)


@pytest.mark.parametrize(
    ("gap", "expected", "settled"),
    [
        (1.0e-8, 1.2e-8, True),  # within a tenth of the tolerance of each other
        (1.4e-7, 1.2e-8, True),  # apart, but both far within the tolerance
        (4.0e-7, 1.0e-8, False),  # apart, and one of them could be near the tolerance
        (-3e-7, 3e-7, False),
    ],
)
def test_fitted_gap_and_fits_settle_a_change_both_put_well_within(gap, expected, settled):
    assert P.fits_agree(gap, expected, 0.1 * P.VOLUME_TOL) is settled


def test_gap_and_fits_apart_but_both_small_still_settle_it(monkeypatch):
    """The gap 1.2e-7 of the volume off the fit's own measure on each fitted face (beyond a
    tenth of the tolerance), OCCT's integrators 3e-6 off face by face and on the whole
    solid: the fillet still goes, its change within the tolerance by both independent
    measures."""
    from medax.cad.parts import variable_radius_box
    from medax.cad.simplify import gap_measure
    from medax.cad.simplify.validate import volume
    from truth import classified_and_simplified

    real, real_gap = P.contributions, gap_measure.gap_volume
    part = variable_radius_box()
    v = volume(part.shape)

    def off(new, old, before, tol, *points):  # type: ignore[no-untyped-def]
        shares = real(new, old, before, tol, *points)
        bad = [BRepAdaptor_Surface(f).GetType() == GeomAbs_BSplineSurface for f in new]
        return shares + np.array(bad + [False] * len(old)) * 3e-6

    def gap_off(new, old):  # type: ignore[no-untyped-def]
        got = real_gap(new, old)
        fitted = BRepAdaptor_Surface(new).GetType() == GeomAbs_BSplineSurface
        return None if got is None else (got[0] + (1.2e-7 * v if fitted else 0.0), got[1])

    def unsettled(new, old, before, tol, expected, shares, *rest):  # type: ignore[no-untyped-def]
        return None, shares  # Gauss-Kronrod face by face no help either

    def whole(*args, **kw):  # type: ignore[no-untyped-def]
        return 3e-6, "volume changed by 3.00e-06 (> 1e-06)"  # nor the whole solid's

    monkeypatch.setattr(P, "contributions", off)
    monkeypatch.setattr(P, "gap_volume", gap_off)
    monkeypatch.setattr(P, "local_volume_shares", unsettled)
    monkeypatch.setattr(P, "volume_change", whole)
    _, r = classified_and_simplified(part.shape)
    assert (r.faces_before, r.faces_after) == (7, 6) and not r.blends_kept, r.blends_kept
    assert abs(r.volume_rel_change) <= 0.5e-6


def test_fitted_faces_are_integrated_only_when_their_gaps_do_not_settle_it(monkeypatch):
    """OCCT's adaptive integrator on a fitted face of hundreds of knot spans takes seconds,
    and the gaps overrule it: the fitted group's faces are left out of the integrators'
    round while the gap and the fit's own measure settle the change (and the result is the
    same fillet removed, the same volume change to 1e-8)."""
    from medax.cad.parts import variable_radius_box
    from truth import classified_and_simplified

    part = variable_radius_box()
    before_r = classified_and_simplified(part.shape)[1]
    real = P.contributions
    skipped: list[int] = []

    def counted(new, old, before, tol, origins=None, cache=None, skip=None):  # type: ignore[no-untyped-def]
        skipped.append(0 if skip is None else int(np.count_nonzero(skip)))
        return real(new, old, before, tol, origins, cache, skip)

    monkeypatch.setattr(P, "contributions", counted)
    _, r = classified_and_simplified(part.shape)
    assert (r.faces_before, r.faces_after) == (7, 6) and not r.blends_kept
    # one round, the fitted group's new face and the pieces it replaces left out of it
    assert len(skipped) == 1 and skipped[0] >= 2
    assert r.volume_rel_change == pytest.approx(before_r.volume_rel_change, abs=1e-8)
