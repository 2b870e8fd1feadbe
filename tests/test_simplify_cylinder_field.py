"""The cylinder field route: a cylindrical supporting face merged with blend halves that
the ring route does not take (fillets along the rulings of a partial cylinder, a cylinder
split into two faces), fitted as points ``P(s, z)`` over the cylinder.

Parts are built with OCCT here; truth from OCCT and closed forms, not from the
simplifier's own validation: ``truth.assert_same_solid`` (analyzer, one closed shell,
volume, distances both ways between the whole boundaries), ``BRepGProp`` volumes, and the
geometry helpers against their surfaces' implicit equations.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Fuse
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepGProp import BRepGProp
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
from OCP.GeomAbs import GeomAbs_Line
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.GProp import GProp_GProps
from scipy.interpolate import BSpline

from medax.cad.classify import classify_solid
from medax.cad.simplify import simplify, specs_from_classification
from medax.cad.simplify.occ import edges_of, faces_of
from medax.geometry.cylinder_field import (
    PERIOD,
    CylinderFrame,
    PointFitter,
    largest_gap,
    radial_heights,
)
from medax.geometry.tensor_fit import solve_masked
from truth import assert_same_solid

RADIUS, FILLET, HEIGHT, CUT = 20.0, 3.0, 10.0, 12.0


def _d_shape(split: bool):
    """A cylinder (radius 20, height 10) cut by the plane x = 12, the two straight edges
    where the cut meets the cylinder filleted (radius 3): the fillets run along the
    rulings of a partial cylinder. ``split``: the cylinder made of two half cylinders
    fused, so its face is two faces (cut at the angles 0 and pi, as a STEP export
    splits closed faces)."""
    if split:
        halves = [
            BRepPrimAPI_MakeCylinder(
                gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1), gp_Dir(x, 0, 0)), RADIUS, HEIGHT, np.pi
            ).Shape()
            for x in (1.0, -1.0)
        ]
        cyl = BRepAlgoAPI_Fuse(halves[0], halves[1]).Shape()
    else:
        cyl = BRepPrimAPI_MakeCylinder(RADIUS, HEIGHT).Shape()
    box = BRepPrimAPI_MakeBox(gp_Pnt(-30, -30, -1), gp_Pnt(CUT, 30, HEIGHT + 1)).Shape()
    s = BRepAlgoAPI_Common(cyl, box).Shape()
    mk = BRepFilletAPI_MakeFillet(s)
    for e in edges_of(s):
        c = BRepAdaptor_Curve(e)
        if c.GetType() != GeomAbs_Line or abs(c.Line().Direction().Z()) < 0.5:
            continue  # the vertical edges only
        if abs(c.Value(c.FirstParameter()).X() - CUT) < 1e-6:
            mk.Add(FILLET, e)
    return mk.Shape()


def _volume(shape) -> float:
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, 1e-9)
    return float(props.Mass())


@pytest.mark.slow
@pytest.mark.parametrize("split", [False, True])
def test_fillets_along_a_partial_cylinder_are_removed(split):
    shape = _d_shape(split)
    cls = classify_solid(shape)
    specs = specs_from_classification(cls)
    if split:  # (the classifier also takes each half cylinder for a radius-20 blend)
        specs = replace(specs, fillets=tuple(f for f in specs.fillets if f.radius < RADIUS / 2))
    assert len(specs.fillets) == 2 and not specs.refused and not specs.corners
    r = simplify(cls.shape, specs)
    assert sorted(r.blends_removed) == sorted(s.face for s in specs.fillets)
    assert not r.blends_kept and r.valid
    assert r.faces_after == r.faces_before - 2
    # the cylinder's group (or each half's) is a fitted face: the cylinder field
    cylinders = [
        i
        for i, f in enumerate(faces_of(cls.shape))
        if BRepAdaptor_Surface(f).GetType().name == "GeomAbs_Cylinder"
        and i not in {s.face for s in specs.fillets}
    ]
    fitted = [g for g in r.face_groups if g.surface == "fitted"]
    assert len(cylinders) == (2 if split else 1)
    on_cylinders = sorted(w for g in fitted for w in g.whole)
    # the cylinder with the halves of fillets on parallel axes is an exact extrusion of
    # arcs when the medial curves' cross parameters are known; else a fillet goes whole
    # into the plane where that is exact, and the others' halves merge into the cylinder
    # field
    whole = [n for n in r.notes if "merged whole" in n]
    exact = [w for g in r.face_groups if g.surface == "extrusion" for w in g.whole]
    assert set(on_cylinders) <= set(cylinders)
    assert on_cylinders or len(whole) == 2 or set(cylinders) <= set(exact)
    # the targets, by OCCT and by distances between the whole boundaries
    assert_same_solid(cls.shape, r)
    v0, v1 = _volume(cls.shape), _volume(r.shape)
    assert abs(v1 - v0) <= 1e-6 * v0
    new = list(faces_of(r.shape))
    for g in fitted:  # one cubic B-spline over the face's span, not round the axis
        ad = BRepAdaptor_Surface(new[g.new_face])
        assert ad.GetType().name == "GeomAbs_BSplineSurface"
        assert ad.UDegree() == ad.VDegree() == 3 and not ad.IsUPeriodic()


def test_periodic_route_reproduces_a_whole_cylinder():
    """A whole cylinder face (with its seam) as its own group: the periodic fit of its
    points is the cylinder (every point at the radius from the axis, to the tolerance)."""
    from medax.cad.simplify.cylinder_field import cylinder_surface

    face = next(
        f
        for f in faces_of(BRepPrimAPI_MakeCylinder(RADIUS, HEIGHT).Shape())
        if BRepAdaptor_Surface(f).GetType().name == "GeomAbs_Cylinder"
    )
    tol = 1e-4
    fs = cylinder_surface(face, [face], tol, 1e-7)
    assert not isinstance(fs, str), fs
    assert fs.error <= tol
    surf = fs.surface
    assert surf.IsUPeriodic() and not surf.IsVPeriodic()
    u0, u1, v0, v1 = surf.Bounds()
    rng = np.random.default_rng(3)
    worst = 0.0
    for u, v in zip(rng.uniform(u0, u1, 300), rng.uniform(0.0, HEIGHT, 300), strict=True):
        p = surf.Value(float(u), float(v))
        worst = max(worst, abs(np.hypot(p.X(), p.Y()) - RADIUS))
    assert worst <= tol
    # the volume estimate between fit and cylinder is tiny against the enclosed volume
    assert abs(fs.volume_change) <= tol * PERIOD * RADIUS * HEIGHT


def _frame() -> CylinderFrame:
    return CylinderFrame.make(
        np.array([1.0, -2.0, 0.5]), np.array([0.2, 0.1, 1.0]), np.array([1.0, 0.0, 0.0]), 4.0
    )


def test_frame_round_trip():
    fr = _frame()
    rng = np.random.default_rng(0)
    s = rng.uniform(0, PERIOD * fr.radius - 1e-9, 200)
    z, h = rng.uniform(-3, 3, 200), rng.uniform(-1, 1, 200)
    x = fr.point(s, z, h)
    s2, z2, h2 = fr.coords(x)
    assert np.abs(s2 - s).max() <= 1e-9 and np.abs(z2 - z).max() <= 1e-12
    assert np.abs(h2 - h).max() <= 1e-12
    # arc length: neighbouring points on the cylinder are s apart along the circle
    a = fr.point(np.array([0.0]), np.array([0.0]))[0]
    b = fr.point(np.array([0.1]), np.array([0.0]))[0]
    assert abs(np.linalg.norm(b - a) - 2 * fr.radius * np.sin(0.1 / fr.radius / 2)) <= 1e-12
    # a loop round the axis unwraps to one period
    loop = fr.point(np.linspace(0, PERIOD * fr.radius, 50), np.zeros(50))
    u = fr.unwrapped(loop)
    assert abs(u[-1] - u[0] - PERIOD * fr.radius) <= 1e-9


def test_largest_gap():
    start, width = largest_gap(np.array([0.1, 0.5, 1.0, -0.3]))
    assert abs(start - 1.0) <= 1e-12 and abs(width - (PERIOD - 1.3)) <= 1e-12


def _on_ray(fr: CylinderFrame, s, z, h) -> np.ndarray:
    x = fr.point(s, z, h)
    s2, z2, _ = fr.coords(x)
    assert np.abs(np.mod(s2 - s + 1, PERIOD * fr.radius) - 1).max() <= 1e-9
    assert np.abs(z2 - z).max() <= 1e-12
    return x


def test_radial_heights_meet_each_surface():
    """Each hit lies on its surface (implicit equation) and on its radial line; the root
    taken is the one nearest the cylinder."""
    fr = CylinderFrame.make(np.zeros(3), np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), 10.0)
    rng = np.random.default_rng(1)
    s, z = rng.uniform(-2, 2, 100), rng.uniform(-1, 1, 100)
    # plane x = 10.5 + 0.1 z: near the cylinder at theta ~ 0
    n = np.array([1.0, 0.0, -0.1])
    c = np.array([10.5, 0.0, 0.0])
    h, ok = radial_heights(fr, "plane", s, z, c, n / np.linalg.norm(n), 0.0)
    assert ok.all()
    x = _on_ray(fr, s, z, h)
    assert np.abs((x - c) @ n).max() <= 1e-9
    # a fillet cylinder along the axis, centre 17 from the axis, radius 3 (inside it)
    cc = np.array([17.0, 0.5, 0.0])
    h, ok = radial_heights(fr, "cylinder", s, z, cc, np.array([0, 0, 1.0]), 3.0)
    x = _on_ray(fr, s[ok], z[ok], h[ok])
    assert ok.sum() > 50
    assert np.abs(np.hypot(x[:, 0] - 17.0, x[:, 1] - 0.5) - 3.0).max() <= 1e-9
    assert np.all(h[ok] > -0.5)  # the outer root, near the cylinder (the inner is ~ -6)
    # a sphere
    h, ok = radial_heights(fr, "sphere", s, z, np.array([9.0, 0.0, 0.0]), np.zeros(3), 2.0)
    x = _on_ray(fr, s[ok], z[ok], h[ok])
    assert ok.any() and np.abs(np.linalg.norm(x - [9.0, 0, 0], axis=1) - 2.0).max() <= 1e-9
    # a coaxial torus: the tube (radius 2) round the circle of radius 11 at z = 0.5
    tc = np.array([0.0, 0.0, 0.5])
    h, ok = radial_heights(fr, "torus", s, z, tc, np.array([0, 0, 1.0]), 2.0, 11.0)
    x = _on_ray(fr, s[ok], z[ok], h[ok])
    assert ok.all()
    rho = np.hypot(x[:, 0], x[:, 1])
    assert np.abs((rho - 11.0) ** 2 + (x[:, 2] - 0.5) ** 2 - 4.0).max() <= 1e-9
    assert np.allclose(rho, 11.0 - np.sqrt(4.0 - (z - 0.5) ** 2))  # nearest the radius 10


def test_point_fitter_error_is_honest():
    """A bump over a partial cylinder with a curvature jump on the ruling s = 1 (a knot
    line): the fit reaches the tolerance and its measured error holds at random points."""
    fr = CylinderFrame.make(np.zeros(3), np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), 5.0)

    def height(s, z):
        h = 0.3 * np.maximum(s - 1.0, 0.0) ** 2 * (1 + 0.2 * z)
        ok = np.ones(s.shape, bool)
        return h, ok, ok

    def points(s, z):
        h, ok, inside = height(s, z)
        return fr.point(s.ravel(), z.ravel(), h.ravel()).reshape((*s.shape, 3)), ok, inside

    tol = 1e-6
    fitter = PointFitter((0.0, 3.0), (0.0, 2.0), [1.0], [], points, height, 0.5, fr)
    fit = fitter.fit(tol, 6)
    assert fit is not None and fit.error <= tol and fit.coef.shape[2] == 3
    rng = np.random.default_rng(2)
    s, z = rng.uniform(0, 3, 400), rng.uniform(0, 2, 400)
    got = np.array([fit(np.array([a]), np.array([b]))[0, 0] for a, b in zip(s, z, strict=True)])
    want = points(s, z)[0]
    assert np.linalg.norm(got - want, axis=1).max() <= 1.5 * tol


def test_solve_masked_components_match_scalar_solves():
    rng = np.random.default_rng(4)
    tx = np.r_[[0.0] * 4, 0.5, [1.0] * 4]
    ty = np.r_[[0.0] * 4, 0.3, 0.6, [1.0] * 4]
    xs, ys = np.linspace(0, 1, 23), np.linspace(0, 1, 19)
    bx = BSpline.design_matrix(xs, tx, 3).tocsr()
    by = BSpline.design_matrix(ys, ty, 3).tocsr()
    ok = rng.uniform(size=(23, 19)) > 0.2
    z = rng.normal(size=(23, 19, 3))
    both = solve_masked(sp.csr_matrix(bx), sp.csr_matrix(by), ok, z)
    for k in range(3):
        one = solve_masked(bx, by, ok, z[..., k])
        assert np.abs(both[..., k] - one).max() <= 1e-9 * max(1.0, np.abs(one).max())


def test_periodic_fit_of_a_boss_foot_with_its_fillet_half():
    """A boss (radius 10) with the cylinder half of its foot fillet (a coaxial torus, tube
    2, down to the 45-degree medial circle): the offsets by :func:`radial_heights`, fitted
    round the axis with the knot circle at the contact, lie on the torus and the cylinder."""
    from medax.geometry.periodic_fit import fit_radial_height

    big, r = 10.0, 2.0
    fr = CylinderFrame.make(np.zeros(3), np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), big)
    medial = -r * np.sin(np.pi / 4)

    def points(th, z):
        s, zz = (th * big).ravel(), z.ravel()
        h, ok = radial_heights(fr, "torus", s, zz, np.zeros(3), np.array([0, 0, 1.0]), r, big + r)
        h = np.where(zz >= 0.0, 0.0, h)
        ok = ok | (zz >= 0.0)
        p = fr.point(s, zz, h).reshape((*th.shape, 3))
        return p, ok.reshape(th.shape), ok.reshape(th.shape)

    tol = 1e-5
    fit = fit_radial_height(
        (medial, 3.0), [0.0], points, tol, 0.5, big, levels=6, s_fine=[True, False]
    )
    assert fit is not None and fit.error <= tol
    rng = np.random.default_rng(6)
    th, z = rng.uniform(0, PERIOD, 2000), rng.uniform(medial, 3.0, 2000)
    p = fit.at(th, z)
    rho = np.hypot(p[:, 0], p[:, 1])
    on_torus = (rho - big - r) ** 2 + p[:, 2] ** 2 - r * r
    off = np.where(p[:, 2] < 0, np.abs(on_torus) / (2 * r), np.abs(rho - big))
    assert off.max() <= 2 * tol


def _box_with_spied_cylinder_pass(monkeypatch):  # type: ignore[no-untyped-def]
    """The 12-edge box (six fitted faces) classified, its specs, and the list that gets one
    entry per call of the cylinder field's pass (spied on in the pipeline)."""
    from medax.cad.simplify import parts, pipeline

    cls = classify_solid(parts.box_all_fillets(40.0, 30.0, 20.0, 4.0).shape)
    calls: list[int] = []
    real = pipeline.cylinder_pass

    def spy(*args):  # type: ignore[no-untyped-def]
        calls.append(1)
        return real(*args)

    monkeypatch.setattr(pipeline, "cylinder_pass", spy)
    return cls, specs_from_classification(cls), calls


def test_second_passes_not_started_past_their_budget(monkeypatch):
    """Past ``SECOND_PASS_BUDGET`` seconds of the run the cylinder field's pass (a second
    pass over the fitted faces) is not started, and the progress says so; the result is
    still a valid, validated solid (the 12-edge box, whose fillets need no second pass,
    simplified all the same). Within it, the pass runs."""
    from medax.cad.simplify import pipeline

    cls, specs, calls = _box_with_spied_cylinder_pass(monkeypatch)
    said: list[str] = []
    simplify(cls.shape, specs, progress=said.append)
    assert calls and not any("not tried:" in m for m in said)
    calls.clear()
    said.clear()
    monkeypatch.setattr(pipeline, "SECOND_PASS_BUDGET", -1.0)
    r = simplify(cls.shape, specs, progress=said.append)
    assert not calls and any(m.startswith("the cylinder field not tried:") for m in said)
    assert r.valid and len(r.blends_removed) == len(specs.fillets) + len(specs.corners)
    assert_same_solid(cls.shape, r)


def test_budgets_count_cpu_time_not_wall_time(monkeypatch):
    """The run's budgets are CPU seconds: on a machine so loaded that every look at the wall
    clock finds another 1000 s gone, the cylinder field's pass still runs and the result is
    the one of an idle machine."""
    import time
    import types

    from medax.cad.simplify import pipeline

    cls, specs, calls = _box_with_spied_cylinder_pass(monkeypatch)
    wall = iter(range(0, 10**9, 1000))
    loaded = types.SimpleNamespace(
        perf_counter=lambda: float(next(wall)), process_time=time.process_time
    )
    monkeypatch.setattr(pipeline, "time", loaded)
    said: list[str] = []
    r = simplify(cls.shape, specs, progress=said.append)
    assert calls and not any("not tried:" in m for m in said)
    assert r.valid and len(r.blends_removed) == len(specs.fillets) + len(specs.corners)
    assert r.time_s >= 1000.0 and 0.0 < r.cpu_s < r.time_s


@pytest.mark.parametrize("periodic", [False, True])
def test_fit_returns_to_the_cylinder_where_it_has_no_data(periodic):
    """A field over a cylinder (R = 5) with a 2-radian notch where the face is not (no data)
    and a blend-like bump at its rim: the fit meets its tolerance on the data, and across the
    notch it follows the cylinder (OCCT's default mass properties integrate the surface
    there, 0.7 - 1.3 radians into it). The points' free continuation ran 0.2 off it."""
    from medax.geometry.periodic_fit import fit_radial_height

    big = 5.0
    fr = CylinderFrame.make(np.zeros(3), np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), big)
    lo, hi = 2.0 * big, 4.0 * big  # the notch in s (arc length): theta 2 .. 4

    def height(s, z):
        s = np.mod(s, PERIOD * big) if periodic else s
        ok = (s <= lo) | (s >= hi)
        h = 0.4 * np.exp(-(((s - lo) / 3.0) ** 2)) * np.where(ok, 1.0, 0.0)
        return h, ok, ok

    def points(s, z):
        h, ok, inside = height(s, z)
        return fr.point(s.ravel(), z.ravel(), h.ravel()).reshape((*s.shape, 3)), ok, inside

    tol = 1e-3
    if periodic:

        def by_angle(th, z):
            return points(th * big, z)

        def on_cylinder(th, z):
            return fr.point((th * big).ravel(), z.ravel()).reshape((*th.shape, 3))

        fit = fit_radial_height((0.0, 3.0), [], by_angle, tol, 0.4, big, outside=on_cylinder)
        th, z = np.meshgrid(np.linspace(2.7, 3.3, 7), np.linspace(0.0, 3.0, 9), indexing="ij")
        p = None if fit is None else fit.at(th.ravel(), z.ravel())
    else:
        fitter = PointFitter((0.0, 6.0 * big), (0.0, 3.0), [], [], points, height, 0.4, fr)
        fit = fitter.fit(tol, 5)
        s, z = np.linspace(2.7 * big, 3.3 * big, 7), np.linspace(0.0, 3.0, 9)
        p = None if fit is None else fit(s, z).reshape(-1, 3)
    assert fit is not None and p is not None and fit.error <= tol
    rho = np.hypot(p[:, 0], p[:, 1])
    assert np.abs(rho - big).max() <= 0.02
