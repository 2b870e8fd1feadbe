"""Curves: evaluation, length, closest points against independent computations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import BSpline as SciBSpline
from scipy.spatial import cKDTree

from medax.geometry import Arc, BSpline, Line, Polyline
from medax.geometry.curve import sub_curve
from medax.geometry.pair_search import PairSearch

RNG = np.random.default_rng(7)


def wavy_spline() -> BSpline:
    pts = np.array([[0, 0], [2, -1.2], [4, 0.9], [6, -0.8], [8, 1.3], [10, 0.5]], float)
    return BSpline(pts, 3)


CURVES = {
    "line": Line(np.array([1.0, 2.0]), np.array([4.0, -2.0])),
    "arc": Arc.from_sagitta(np.array([0.0, 0.0]), np.array([10.0, 0.0]), -3.0),
    "bspline": wavy_spline(),
    "polyline": Polyline(np.array([[0, 0], [1, 2], [3, 2.5], [4, 0], [6, 1]], float)),
    "nurbs": BSpline(
        np.array([[1, 0], [1, 1], [0, 1]], float), 2, weights=np.array([1, math.sqrt(0.5), 1])
    ),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CURVES))
def test_closest_is_global_and_exact(name):
    c = CURVES[name]
    dense = c.sample(400_001)
    pts = RNG.uniform(dense.min(0) - 3, dense.max(0) + 3, size=(2000, 2))
    ref, _ = cKDTree(dense).query(pts)
    got = c.closest(pts)
    # never farther than the dense reference; at most the sampling error (half a spacing) closer
    spacing = np.linalg.norm(np.diff(dense, axis=0), axis=1).max()
    assert np.all(got.distance <= ref + 1e-12)
    assert np.all(got.distance >= ref - 0.5 * spacing)
    assert np.allclose(np.linalg.norm(got.foot - pts, axis=1), got.distance)
    assert np.allclose(c.evaluate(got.t), got.foot)


@pytest.mark.slow
def test_closest_is_exact_near_the_evolute():
    """Points near the centres of curvature (where ``g'`` is small and Newton slow: the
    medial axis of a wavy side runs there): feet stationary to round-off, foot points (a
    Taylor step, not an evaluation) on the curve, never farther than 400k samples."""
    c = wavy_spline()
    t = np.linspace(0.01, 0.99, 400)
    d1, d2 = c.derivative(t), c.derivative(t, 2)
    speed = np.linalg.norm(d1, axis=1)
    kappa = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / speed**3
    normal = np.column_stack((-d1[:, 1], d1[:, 0])) / speed[:, None]
    f = np.repeat([0.5, 0.9, 0.99, 1.01, 1.1], t.size)
    rho = f / np.tile(kappa, 5)  # signed radii of curvature, scaled
    pts = np.tile(c.evaluate(t), (5, 1)) + rho[:, None] * np.tile(normal, (5, 1))
    pts = pts[np.all(np.abs(pts) < 20.0, axis=1)]
    got = c.closest(pts)
    ref, _ = cKDTree(c.sample(400_001)).query(pts)
    assert np.all(got.distance <= ref + 1e-12)
    assert np.allclose(c.evaluate(got.t), got.foot, rtol=0.0, atol=1e-13)
    # interior feet: stationary; 8 more plain Newton steps leave the distance as it is
    inner = (got.t > 0.0) & (got.t < 1.0)
    t, x = got.t[inner].copy(), pts[inner]
    for _ in range(8):
        r = c.evaluate(t) - x
        d1, d2 = c.derivative(t), c.derivative(t, 2)
        dg = np.einsum("ij,ij->i", d1, d1) + np.einsum("ij,ij->i", r, d2)
        t -= np.einsum("ij,ij->i", r, d1) / dg
    assert np.max(np.abs(t - got.t[inner])) < 1e-8
    polished = np.linalg.norm(c.evaluate(t) - x, axis=1)
    assert np.allclose(got.distance[inner], polished, rtol=1e-14, atol=1e-14)


def test_nurbs_quarter_circle_is_exact():
    c = CURVES["nurbs"]
    t = np.linspace(0, 1, 101)
    assert np.allclose(np.linalg.norm(c.evaluate(t), axis=1), 1.0, atol=1e-14)
    assert c.length() == pytest.approx(math.pi / 2, rel=1e-12)


def test_bspline_matches_scipy_and_derivative():
    c = wavy_spline()
    knots = np.r_[np.zeros(4), [1 / 3, 2 / 3], np.ones(4)]
    ref = SciBSpline(knots, c.control_points, 3)
    t = np.linspace(0, 1, 57)
    assert np.allclose(c.evaluate(t), ref(t), atol=1e-14)
    h = 1e-6
    fd = (c.evaluate(t[1:-1] + h) - c.evaluate(t[1:-1] - h)) / (2 * h)
    assert np.allclose(c.derivative(t[1:-1]), fd, atol=1e-6)


def test_bspline_jet_of_many_points_matches_scipy():
    """Value and derivatives of many points at once (the compiled jet kernel) equal
    scipy's de Boor evaluation, point by point."""
    c = wavy_spline()
    knots = np.r_[np.zeros(4), [1 / 3, 2 / 3], np.ones(4)]
    ref = SciBSpline(knots, c.control_points, 3)
    t = np.random.default_rng(2).uniform(0.0, 1.0, 4321)
    for got, nu in zip(c.jet(t), range(3), strict=True):
        np.testing.assert_allclose(got, ref(t, nu), rtol=0, atol=1e-11)


def test_lengths():
    assert CURVES["line"].length() == pytest.approx(5.0)
    arc = Arc(np.zeros(2), 2.0, 0.3, -1.7)
    assert arc.length() == pytest.approx(3.4)
    assert Curve_length_by_sampling(CURVES["bspline"]) == pytest.approx(
        CURVES["bspline"].length(), rel=1e-8
    )


def Curve_length_by_sampling(c) -> float:  # noqa: N802
    p = c.sample(200_001)
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))


def test_sagitta_arc_geometry():
    arc = Arc.from_sagitta(np.array([0.0, 0.0]), np.array([10.0, 0.0]), 2.0)
    # positive sagitta bulges to the right of travel: apex at (5, -2)
    assert np.allclose(arc.evaluate(np.array([0.5]))[0], [5.0, -2.0])
    assert np.allclose(arc.end, [10.0, 0.0])


def test_reversed_and_sub_curve():
    c = CURVES["bspline"]
    t = np.linspace(0, 1, 11)
    assert np.allclose(c.reversed().evaluate(t), c.evaluate(1 - t))
    s = sub_curve(c, 0.25, 0.75)
    assert np.allclose(s.evaluate(t), c.evaluate(0.25 + 0.5 * t))
    assert np.allclose(sub_curve(s, 0.5, 1.0).evaluate(t), c.evaluate(0.5 + 0.25 * t))


@pytest.mark.slow
def test_pair_search_matches_dense_samples_on_both_curves():
    """Two B-splines searched together (stacked tables): each answer global and exact,
    against 400k samples of each curve, and equal to the separate queries."""
    c1 = wavy_spline()
    c2 = BSpline(np.array([[10, 0.5], [11.4, 2.5], [9, 4.5], [11.2, 7], [9.5, 9.5]], float), 3)
    pair = PairSearch.build(c1, c2)
    assert pair is not None
    pts = RNG.uniform([-2.0, -3.0], [13.0, 12.0], size=(700, 2))
    got = pair.closest(pts)
    for c, g in zip((c1, c2), got, strict=True):
        dense = c.sample(400_001)
        ref, _ = cKDTree(dense).query(pts)
        spacing = np.linalg.norm(np.diff(dense, axis=0), axis=1).max()
        assert np.all(g.distance <= ref + 1e-12)
        assert np.all(g.distance >= ref - 0.5 * spacing)
        assert np.allclose(c.evaluate(g.t), g.foot, rtol=0.0, atol=1e-12)
        assert np.allclose(g.distance, c.closest(pts).distance, rtol=0.0, atol=1e-13)
    # rational or non-B-spline curves are not stacked
    assert PairSearch.build(c1, CURVES["nurbs"]) is None
    assert PairSearch.build(c1, CURVES["line"]) is None


def test_transformed_bspline_keeps_exact_pieces():
    """The image of a B-spline whose pieces are cached gets them in closed form: its jet
    equals that of scipy's B-spline of the transformed control points."""
    c = wavy_spline()
    c.evaluate(np.zeros(1))  # caches the pieces
    off, scale = np.array([5.0, -2.0]), 16.0
    img = c.transformed(off, scale)
    assert "_pieces" in img.__dict__
    knots = np.r_[np.zeros(4), [1 / 3, 2 / 3], np.ones(4)]
    ref = SciBSpline(knots, (c.control_points - off) / scale, 3)
    t = np.linspace(0.0, 1.0, 301)
    for got, nu in zip(img.jet(t), (0, 1, 2), strict=True):
        assert np.allclose(got, ref(t, nu), rtol=0.0, atol=1e-13)


def test_polyline_closest_in_bracket_is_exact():
    """Polyline.closest_in: the nearest point with its parameter in [lo, hi] (exact segments,
    clipped to the bracket) equals the nearest of dense samples of that bracket, and never
    loses to the bracketed Newton it replaces."""
    from medax.geometry.curve import _bracketed_newton

    rng = np.random.default_rng(5)
    pts = np.cumsum(rng.normal(size=(40, 2)), axis=0)
    poly = Polyline(pts)
    x = rng.uniform(pts.min(0), pts.max(0), (300, 2))
    lo = rng.uniform(0.0, 0.9, 300)
    hi = np.minimum(lo + rng.uniform(0.0, 0.2, 300), 1.0)
    t, foot = poly.closest_in(x, lo, hi, lo)
    assert np.all((t >= lo) & (t <= hi))
    np.testing.assert_allclose(foot, poly.evaluate(t), atol=1e-12)
    d = np.linalg.norm(foot - x, axis=1)
    s = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, 4001)[None, :]
    dense = np.linalg.norm(poly.evaluate(s.ravel()).reshape(300, -1, 2) - x[:, None], axis=2)
    assert np.all(d <= dense.min(axis=1) + 1e-12)
    assert np.all(d >= dense.min(axis=1) - 1e-2 * (hi - lo) * poly.length())  # sample spacing
    _, f_newton = _bracketed_newton(poly, x, lo, hi, start=lo)
    assert np.all(d <= np.linalg.norm(f_newton - x, axis=1) + 1e-12)


@pytest.mark.parametrize("far", [0.01, 1.0, 100.0])
def test_polyline_closest_many_segments_is_exact(far):
    """Polylines of many segments settle most points from their nearest vertices' segments
    (k-d tree): the same feet as the distance to every segment, points near the polyline
    and far from it (relative to the segments' length)."""
    rng = np.random.default_rng(7)
    a = np.linspace(0.0, 4.0, 500)
    pts = np.column_stack((np.cos(a), np.sin(a))) * (1.0 + 0.01 * rng.normal(size=(500, 1)))
    poly = Polyline(pts)
    x = pts[rng.integers(0, 500, 400)] + rng.normal(size=(400, 2)) * far
    got = poly.closest(x)
    t_all = poly._closest_all(x)
    d_all = np.linalg.norm(poly.evaluate(t_all) - x, axis=1)
    np.testing.assert_allclose(got.distance, d_all, rtol=0.0, atol=1e-14 * (1.0 + far))


#: a region hypothesis found (tests/test_property_regions.py): side 2 a degree-1 B-spline
CORNER_REGION = {
    "corners": [
        [-2.9534160636075995, 1.250360647143797],
        [-1.2446486661087848, -3.3692369891657314],
        [7.169488535414266, -12.640574740468796],
        [13.417638806849286, 3.304690836589584],
    ],
    "sides": [
        {"kind": "line"},
        {"kind": "line"},
        {
            "kind": "bspline",
            "degree": 1,
            "points": [
                [7.169488535414266, -12.640574740468796],
                [8.062081431333555, -10.362679658031885],
                [8.954674327252842, -8.084784575594973],
                [9.557149851861631, -5.6932070384167766],
                [10.171071986841532, -3.3061148540445036],
                [11.632453015010707, -1.2510993282842406],
                [13.708142322093018, 0.5631995771672184],
                [13.417638806849286, 3.304690836589584],
            ],
        },
        {"kind": "arc", "sagitta": 1.557881157621627},
    ],
}


def test_closest_at_a_corner_from_a_pieces_normal_line():
    """A point (an axis transition) on the normal line of one piece of a degree-1 B-spline
    at a corner convex towards it: the nearest point is the corner, where ``(C - x) . C'``
    jumps from negative to positive without a root; the bracketed Newton stopped on the
    piece, 2.9e-6 x diagonal farther (the region's axis was off by that). The side as the
    tracer has it (centred, unit diagonal: the rounding of its samples decides)."""
    from medax.geometry.region import normalised_region
    from medax.geometry.region_io import region_from_dict

    work, _, _ = normalised_region(region_from_dict(CORNER_REGION, "r"))
    curve = work.sides[2]
    x = np.array([[-0.05004809617337858, -0.0009438420310409994]])
    vertex = curve.evaluate(np.array([3.0 / 7.0]))
    got = curve.closest(x)
    assert got.distance[0] <= np.linalg.norm(vertex - x) + 1e-15
    assert abs(got.t[0] - 3.0 / 7.0) <= 1e-15


def test_closest_of_no_points():
    """An empty query gives empty answers on every kind of curve (the generic search
    failed to reshape its empty candidates)."""
    curves = [
        Line(np.zeros(2), np.ones(2)),
        Arc(np.zeros(2), 1.0, 0.0, 1.0),
        Polyline(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])),
        BSpline(np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 0.0], [3.0, 1.0]]), 3),
    ]
    for c in curves:
        got = c.closest(np.zeros((0, 2)))
        assert got.t.shape == (0,) and got.distance.shape == (0,) and got.foot.shape[0] == 0


def test_arclength_at_against_dense_polyline():
    """``arclength_at`` (lengths from the start to given parameters) against a dense polyline
    of the curve (2e5 chords, independent of the quadrature), and inverse to
    ``arclength_params``, on an arc and a wavy rational B-spline."""
    from medax.mesh.arclength import arclength_at, arclength_params

    wavy = BSpline(
        np.array([[0, 0], [1, 2], [2, -1], [3, 3], [4, 0], [6, 1]], dtype=float),
        3,
        weights=np.array([1.0, 2.0, 0.5, 1.0, 3.0, 1.0]),
    )
    for curve in (Arc(np.array([1.0, 2.0]), 3.0, 0.3, 2.5), wavy):
        t = np.array([0.0, 0.13, 0.5, 0.77, 1.0])
        dense = np.linspace(0.0, 1.0, 200_001)
        p = curve.evaluate(dense)
        cum = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
        truth = np.interp(t, dense, cum)
        np.testing.assert_allclose(arclength_at(curve, t), truth, rtol=1e-8, atol=1e-12)
        f = np.array([0.0, 0.2, 0.45, 0.9, 1.0])
        back = arclength_at(curve, arclength_params(curve, f)) / arclength_at(curve, [1.0])[0]
        np.testing.assert_allclose(back, f, atol=1e-12)
