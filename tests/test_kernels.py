"""The compiled kernels (medax.geometry.kernels) against independent computations: scipy's
de Boor evaluation for the jets, dense sampling refined by scipy's bounded Brent search for
the closest points (global and within a bracket), on polynomial B-splines (one compiled
call), rational curves (compiled Newton on homogeneous jets), sub-curves (jets from
Python, compiled steps) and splines with C0 corners."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from scipy.interpolate import BSpline as SciBSpline
from scipy.optimize import minimize_scalar

from medax.geometry import BSpline, kernels
from medax.geometry.bspline import stacked_jet
from medax.geometry.curve import closest_near, sub_curve
from medax.geometry.pair_search import PairSearch

RNG = np.random.default_rng(11)


def random_spline(degree: int, n_ctrl: int, seed: int) -> BSpline:
    """A wiggly planar B-spline with non-uniform interior knots."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 10.0, n_ctrl)
    pts = np.column_stack((x, rng.uniform(-2.0, 2.0, n_ctrl)))
    inner = np.sort(rng.uniform(0.05, 0.95, n_ctrl - degree - 1))
    knots = np.r_[np.zeros(degree + 1), inner, np.ones(degree + 1)]
    return BSpline(pts, degree, knots)


def scipy_spline(c: BSpline) -> SciBSpline:
    return SciBSpline(c.knots, c.control_points, c.degree)


def dense_closest(c, x: np.ndarray, lo: float = 0.0, hi: float = 1.0) -> float:
    """Distance from ``x`` (dim,) to ``c`` over ``t in [lo, hi]``: the nearest of 20k
    samples and of the 6 best sampled local minima, each refined by bounded Brent search
    between its neighbouring samples (independent of the kernels' Newton iteration)."""
    t = np.linspace(lo, hi, 20_001)
    d = np.linalg.norm(c.evaluate(t) - x, axis=1)
    best = float(d.min())
    if hi == lo:
        return best
    k = np.arange(1, t.size - 1)
    k = k[(d[k] <= d[k - 1]) & (d[k] <= d[k + 1])]
    for j in k[np.argsort(d[k])][:6]:
        r = minimize_scalar(
            lambda s: float(np.linalg.norm(c.evaluate(np.array([s]))[0] - x)),
            bounds=(t[j - 1], t[j + 1]),
            method="bounded",
            options={"xatol": 1e-14},
        )
        best = min(best, float(r.fun))
    return best


@pytest.mark.parametrize("degree", [1, 2, 3, 4, 5])
def test_jets_equal_scipy_de_boor(degree):
    """Value, first and second derivative (jet, evaluate, derivative, jet_rows) equal
    scipy's de Boor evaluation, at random parameters, the knots and the ends."""
    c = random_spline(degree, degree + 6, seed=degree)
    ref = scipy_spline(c)
    t = np.r_[RNG.uniform(0.0, 1.0, 500), np.unique(c.knots)]
    scale = np.abs(c.control_points).max()
    for nu, got in enumerate(c.jet(t)):
        np.testing.assert_allclose(got, ref(t, nu), rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(c.evaluate(t), ref(t), rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(c.derivative(t, 2), ref(t, 2), rtol=0, atol=1e-10 * scale)
    rows = c.jet_rows(t)
    assert rows is not None
    for nu in range(3):
        np.testing.assert_allclose(rows[2 * nu : 2 * nu + 2].T, ref(t, nu), atol=1e-10 * scale)


def test_stacked_jets_of_curves_of_several_degrees_equal_scipy():
    """Curves of degrees 2, 3 and 5 in one table (lower degrees padded): each point's jet
    equals scipy's of its own curve."""
    curves = [random_spline(d, d + 4, seed=10 + d) for d in (2, 3, 5)]
    table = BSpline.stacked_rows(curves)
    assert table is not None
    j = RNG.integers(0, 3, 600)
    t = RNG.uniform(0.0, 1.0, 600)
    got = stacked_jet(table, t, 2.0 * j)
    for k, c in enumerate(curves):
        ref = scipy_spline(c)
        on = j == k
        for nu in range(3):
            np.testing.assert_allclose(got[2 * nu : 2 * nu + 2, on].T, ref(t[on], nu), atol=1e-9)


CASES = {
    "cubic": random_spline(3, 9, seed=3),
    "quintic": random_spline(5, 11, seed=5),
    "quadratic": random_spline(2, 7, seed=2),
    # C0 corners (Bezier pieces joined): the corner test of the kernel
    "corners": BSpline.from_bezier(
        np.array([[0, 0], [1, 2], [2, 0], [3, 3], [4, 0], [5, -2], [6, 0]], float),
        np.array([0.0, 0.3, 0.7, 1.0]),
        2,
    ),
    # jets from Python (compiled steps only): rational, and a piece of a curve
    "nurbs": BSpline(
        np.array([[1, 0], [1, 1], [0, 1]], float), 2, weights=np.array([1, math.sqrt(0.5), 1])
    ),
    "sub": sub_curve(random_spline(3, 9, seed=4), 0.15, 0.85),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_closest_equals_dense_sampling_and_brent(name):
    """Global closest points: the distance equals that of 20k samples refined by Brent's
    method to 1e-12 x diagonal, the foot is on the curve at ``t``, the distance is to the
    foot."""
    c = CASES[name]
    dense = c.sample(2001)
    lo, hi = dense.min(axis=0), dense.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    x = RNG.uniform(lo - 0.3 * diag, hi + 0.3 * diag, (60, 2))
    got = c.closest(x)
    ref = np.array([dense_closest(c, p) for p in x])
    np.testing.assert_allclose(got.distance, ref, rtol=0, atol=1e-12 * diag)
    np.testing.assert_allclose(c.evaluate(got.t), got.foot, rtol=0, atol=1e-12 * diag)
    np.testing.assert_allclose(np.linalg.norm(got.foot - x, axis=1), got.distance, atol=1e-14)


@pytest.mark.parametrize("name", ["cubic", "corners", "nurbs", "sub"])
def test_closest_near_equals_brent_in_the_bracket(name):
    """Bracketed closest points (closest_near: compiled for polynomial tables, compiled
    steps otherwise): where the distance is unimodal over ``[t0 - w, t0 + w]`` (one branch
    of the curve: the query is local), the nearest point there, ends included, equals
    bounded Brent search over that interval; at least 20 of the 50 rows are such."""
    c = CASES[name]
    dense = c.sample(2001)
    diag = float(np.linalg.norm(dense.max(axis=0) - dense.min(axis=0)))
    x = RNG.uniform(dense.min(axis=0) - 0.2 * diag, dense.max(axis=0) + 0.2 * diag, (50, 2))
    t0 = RNG.uniform(0.0, 1.0, 50)
    width = 0.08
    got = closest_near(c, x, t0, width)
    checked = 0
    for i in range(x.shape[0]):
        a, b = max(t0[i] - width, 0.0), min(t0[i] + width, 1.0)
        assert a - 1e-15 <= got.t[i] <= b + 1e-15
        d = np.linalg.norm(c.evaluate(np.linspace(a, b, 2001)) - x[i], axis=1)
        if np.count_nonzero(np.diff(np.sign(np.diff(d))) > 0) > 0:
            continue  # a local maximum inside: two branches
        checked += 1
        assert got.distance[i] == pytest.approx(dense_closest(c, x[i], a, b), abs=1e-12 * diag)
    assert checked >= 20


def test_pair_search_equals_single_curve_searches():
    """The two constraints searched in one compiled call give the single-curve answers, and
    the branch-restricted query on either curve those of closest_near."""
    c1, c2 = CASES["cubic"], CASES["quintic"]
    pair = PairSearch.build(c1, c2)
    assert pair is not None
    x = RNG.uniform([-2.0, -4.0], [12.0, 4.0], (300, 2))
    for got, c in zip(pair.closest(x), (c1, c2), strict=True):
        ref = c.closest(x)
        np.testing.assert_array_equal(got.t, ref.t)
        np.testing.assert_array_equal(got.distance, ref.distance)
    on2 = RNG.uniform(size=300) < 0.5
    t0 = RNG.uniform(0.0, 1.0, 300)
    got = pair.closest_near(on2, x, t0, 0.1)
    for c, rows in ((c1, ~on2), (c2, on2)):
        ref = closest_near(c, x[rows], t0[rows], 0.1)
        np.testing.assert_allclose(got.distance[rows], ref.distance, rtol=0, atol=1e-14)


def test_newton_rows_step_shrinks_the_bracket_and_bisects():
    """One safeguarded step of g(t) = (C - x) . C' from jets given by the caller: a Newton
    step to the root of the line x = t at the point 0.3 (not yet done: its length is
    0.6), its bracket shrunk to [0, 0.9]; where g' < 0 a bisection of the shrunk bracket;
    g = 0 ends the row where it is, its foot the jet's point."""
    x = np.array([[0.3, 0.0]])
    c0, c1 = np.array([[0.9, 0.0]]), np.array([[1.0, 0.0]])
    foot = np.empty((1, 2))

    def step(c2: np.ndarray, c1: np.ndarray = c1) -> tuple[bool, float, float, float]:
        s, a, b = np.array([0.9]), np.array([0.0]), np.array([1.0])
        done = kernels.newton_rows(c0, c1, c2, x, s, a, b, False, foot)
        return bool(done[0]), float(s[0]), float(a[0]), float(b[0])

    assert step(np.zeros((1, 2))) == (False, pytest.approx(0.3), 0.0, 0.9)
    assert step(np.array([[-10.0, 0.0]])) == (False, 0.45, 0.0, 0.9)  # g' = 1 - 6 < 0
    done, s, a, b = step(np.zeros((1, 2)), np.zeros((1, 2)))  # C' = 0: g = 0
    assert done and s == 0.9 and (a, b) == (0.0, 1.0)
    np.testing.assert_array_equal(foot, c0)


def test_newton_table_on_a_rational_arc_finds_the_circle_feet_as_the_steps_do():
    """The compiled Newton of rational B-splines (jets in the kernel): on an exact NURBS
    quarter circle of radius 2 in space (centre c, tilted plane), the feet of points off
    the arc's plane are the circle's radial projections (c + R u / |u|, u the point's
    offset projected on the plane) to 1e-13; and they equal bit for bit the step-by-step
    iteration with the jets evaluated from Python (kernels.newton_rows)."""
    e1 = np.array([1.0, 2.0, 2.0]) / 3.0
    e2 = np.array([2.0, 1.0, -2.0]) / 3.0
    centre, radius = np.array([5.0, -1.0, 3.0]), 2.0
    plane = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]) * radius
    arc = BSpline(
        centre + plane @ np.vstack((e1, e2)), 2, weights=np.array([1.0, math.sqrt(0.5), 1.0])
    )
    table = arc.jet_table()
    assert table is not None and table[3]
    ang = RNG.uniform(0.1, 0.5 * math.pi - 0.1, 40)
    rad = RNG.uniform(0.3, 3.5, 40)
    normal = np.cross(e1, e2)
    x = (
        centre
        + (rad * np.cos(ang))[:, None] * e1
        + (rad * np.sin(ang))[:, None] * e2
        + RNG.uniform(-1.0, 1.0, 40)[:, None] * normal
    )
    a, b, s0 = np.zeros(40), np.ones(40), np.full(40, 0.5)
    t, foot = kernels.newton_table(*table, x, a, b, s0, 60)
    truth = centre + radius * (np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2)
    np.testing.assert_allclose(foot, truth, rtol=0, atol=1e-13)
    np.testing.assert_allclose(arc.evaluate(t), truth, rtol=0, atol=1e-13)
    # the same iteration, one compiled step per Python round with the jets from arc.jet
    s, aa, bb = s0.copy(), a.copy(), b.copy()
    ref_t, ref_foot = np.empty(40), np.empty((40, 3))
    rows = np.arange(40)
    for it in range(60):
        sr, ar, br = s[rows], aa[rows], bb[rows]
        c0, c1, c2 = (np.ascontiguousarray(c) for c in arc.jet(sr))
        fr = np.empty((rows.size, 3))
        done = kernels.newton_rows(c0, c1, c2, x[rows], sr, ar, br, it == 59, fr)
        s[rows], aa[rows], bb[rows] = sr, ar, br
        ref_t[rows[done]], ref_foot[rows[done]] = sr[done], fr[done]
        rows = rows[~done]
        if rows.size == 0:
            break
    assert rows.size == 0
    np.testing.assert_array_equal(t, ref_t)
    np.testing.assert_array_equal(foot, ref_foot)


def _arc_distance(x: np.ndarray, centre, radius: float, a0: float, a1: float) -> np.ndarray:
    """Distance from ``x`` (n, 2) to the circle arc of angles ``[a0, a1]`` (a0 < a1)."""
    v = x - centre
    ang = np.arctan2(v[:, 1], v[:, 0])
    ang = np.where(ang < a0 - 1e-12, ang + 2.0 * math.pi, ang)
    on = ang <= a1
    ends = np.array([[math.cos(a0), math.sin(a0)], [math.cos(a1), math.sin(a1)]]) * radius
    to_ends = np.linalg.norm(v[:, None, :] - ends[None], axis=2).min(axis=1)
    return np.where(on, np.abs(np.linalg.norm(v, axis=1) - radius), to_ends)


def test_closest_on_a_rational_spline_with_a_corner_equals_the_two_arcs():
    """Global closest points on a rational B-spline (the Newton steps in one compiled call,
    kernels.newton_table): two exact quarter circles (centres (0, 0) and (-1, 1), radius 1)
    meeting at a 90-degree C0 corner (0, 1); the distance of 400 points around equals the
    nearer arc's in closed form to 1e-13 (and 40 more near the corner), the foot is the
    curve at ``t``, and points on the corner's convex side get the corner itself."""
    r = math.sqrt(0.5)
    c = BSpline(
        np.array([[1, 0], [1, 1], [0, 1], [0, 2], [-1, 2]], float),
        2,
        np.array([0, 0, 0, 0.5, 0.5, 1, 1, 1], float),
        np.array([1, r, 1, r, 1]),
    )
    assert c.jet_table() is not None and c.breaks().tolist() == [0.5]
    x = np.vstack(
        (
            RNG.uniform([-2.5, -1.5], [2.5, 3.0], (400, 2)),
            RNG.uniform([-0.45, 0.55], [0, 1], (40, 2)),
        )
    )
    got = c.closest(x)
    ref = np.minimum(
        _arc_distance(x, np.array([0.0, 0.0]), 1.0, 0.0, 0.5 * math.pi),
        _arc_distance(x, np.array([-1.0, 1.0]), 1.0, 0.0, 0.5 * math.pi),
    )
    np.testing.assert_allclose(got.distance, ref, rtol=0, atol=1e-13)
    np.testing.assert_allclose(c.evaluate(got.t), got.foot, rtol=0, atol=1e-13)
    # on the corner's convex side (left of x = 0 and below y = 1, where neither arc's
    # normal lines reach) and nearer than the ends (within 0.7 of it): the corner
    corner = (x[:, 0] < -0.05) & (x[:, 1] < 0.95) & (np.linalg.norm(x - [0.0, 1.0], axis=1) < 0.7)
    assert corner.sum() >= 10
    np.testing.assert_allclose(got.foot[corner], np.tile([0.0, 1.0], (corner.sum(), 1)))
    np.testing.assert_array_equal(got.t[corner], 0.5)


def _all_pairs_cross(a: np.ndarray, b: np.ndarray, eps: float, skip_neighbours: bool) -> bool:
    """Brute force: every segment of ``a`` against every segment of ``b`` (no boxes)."""
    if len(a) < 2 or len(b) < 2:
        return False
    a0, a1 = a[:-1, None, :], a[1:, None, :]
    b0, b1 = b[None, :-1, :], b[None, 1:, :]

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (
            r[..., 0] - p[..., 0]
        )

    tol = eps * eps
    hit = (orient(a0, a1, b0) * orient(a0, a1, b1) < -tol) & (
        orient(b0, b1, a0) * orient(b0, b1, a1) < -tol
    )
    if skip_neighbours:
        i, j = np.indices(hit.shape)
        hit &= j >= i + 2
    return bool(hit.any())


def test_crossing_kernels_equal_all_pairs_tables():
    """The chunked compiled crossing tests (boxes of 16 segments) answer as the brute-force
    table of every segment pair, on random walks (many crossings and near misses), smooth
    curves that do and do not meet, a figure eight and polylines of 2 - 40 points."""
    from medax.geometry.crossing_kernel import polylines_cross, self_crossing  # (one kernel)

    rng = np.random.default_rng(7)
    cases = []
    for n in (2, 3, 4, 5, 17, 18, 33, 40, 200):
        cases.append(np.cumsum(rng.normal(size=(n, 2)), axis=0))
        cases.append(np.cumsum(rng.normal(size=(n, 2)) * [1.0, 0.05], axis=0))
    t = np.linspace(0.0, 2.0 * math.pi, 201)
    cases.append(np.column_stack((np.sin(t), np.sin(2.0 * t))))  # a figure eight
    cases.append(np.column_stack((t, np.sin(t))))
    cases.append(np.column_stack((t, np.sin(t) + 2.5)))  # above the last: no crossing
    cases.append(np.column_stack((t, np.cos(t))))  # crosses the sine twice
    seen = {True: 0, False: 0}
    for eps in (0.0, 1e-12, 1e-3):
        for a in cases:
            a = np.ascontiguousarray(a)
            ref = _all_pairs_cross(a, a, eps, skip_neighbours=True)
            assert self_crossing(a, eps) == ref
            seen[ref] += 1
        for a, b in zip(cases[:-1], cases[1:], strict=True):
            ref = _all_pairs_cross(a, b, eps, skip_neighbours=False)
            assert polylines_cross(np.ascontiguousarray(a), np.ascontiguousarray(b), eps) == ref
            seen[ref] += 1
    assert seen[True] >= 20 and seen[False] >= 20


def test_first_run_compile_is_announced(monkeypatch, caplog):
    """Without a cache index the first query logs the compile message (INFO) once."""
    monkeypatch.setattr(kernels, "_announced", False)
    monkeypatch.setattr(kernels, "_cached", lambda kerns: False)
    with caplog.at_level(logging.INFO, logger="medax.geometry.kernels"):
        random_spline(3, 7, seed=1).closest(np.zeros((1, 2)))
        random_spline(3, 7, seed=2).closest(np.zeros((1, 2)))
    msgs = [r.getMessage() for r in caplog.records]
    assert msgs.count("compiling numeric kernels (first run only)...") == 1
    assert any(m.startswith("numeric kernels compiled in") for m in msgs)


def test_kernels_are_cached_after_a_run():
    """Every kernel has its numba cache index once it has run (the warm start loads them)."""
    kernels.warm_up()
    assert kernels._cached(kernels._COMPILED)


def test_cli_shows_the_compile_message_by_default_and_q_hides_it(monkeypatch, tmp_path, capsys):
    """The first run's pause is announced on stderr without -v (a stage message), and -q
    silences it."""
    from medax.cli.main import main
    from medax.samples import copy_samples

    copy_samples(["regions.json"], tmp_path)
    args = ["axis", str(tmp_path / "regions.json"), "--region", "wavy"]
    monkeypatch.setattr(kernels, "_cached", lambda kerns: False)
    monkeypatch.setattr(kernels, "_announced", False)
    assert main([*args, "-o", str(tmp_path / "a.json")]) == 0
    err = capsys.readouterr().err
    assert "medax: compiling numeric kernels (first run only)..." in err
    monkeypatch.setattr(kernels, "_announced", False)
    assert main([*args, "-o", str(tmp_path / "b.json"), "-q"]) == 0
    assert "compiling" not in capsys.readouterr().err
