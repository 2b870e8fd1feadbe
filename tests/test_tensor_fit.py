"""The penalised tensor-product fit of a height field (numpy only, no OCP): a rounded box
corner in closed form (plane, two cylinder strips, a sphere corner)."""

from __future__ import annotations

import numpy as np

from medax.geometry.tensor_fit import HeightFitter, fit_height, greville

R = 4.0  # fillet radius; the flat part starts at x = y = R


def _corner(x, y):
    """Height of a rounded corner below the top plane (closed form) and the face mask: the
    top face's share of the rounded box, out to the 45-degree medial lines."""
    dx, dy = np.maximum(R - x, 0.0), np.maximum(R - y, 0.0)
    s = R * R - dx * dx - dy * dy
    z = R - np.sqrt(np.maximum(s, 0.0))
    medial = R * (1 - np.sqrt(0.5))
    inside = (x >= medial) & (y >= medial) & (s >= R * R / 3)  # corner piece to 54.7 deg
    return z, inside


def _h(x, y):
    z, inside = _corner(x, y)
    return z, inside.copy(), inside


def test_fit_meets_tolerance_against_closed_form():
    tol = 2e-5
    fit = fit_height((0.9, 20.0), (0.9, 20.0), [1.1716, R], [1.1716, R], _h, tol, R / 4)
    assert fit.error <= tol
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0.9, 20.0, 400), rng.uniform(0.9, 20.0, 400)
    z = np.diag(fit(np.sort(x), np.sort(y)))
    truth, inside = _corner(np.sort(x), np.sort(y))
    assert np.abs(z - truth)[inside].max() <= 2 * tol  # off the check grid, same order


def test_breaks_on_the_curvature_jumps_matter():
    """With C1 knots where the curvature jumps the fit converges at its full order; without,
    it does not (measured: 16x, then 60x apart at R/16 and R/32)."""
    errs = []
    for step in (R / 16, R / 32):
        with_b = fit_height((0.9, 20.0), (0.9, 20.0), [R], [R], _h, 0.0, step, levels=1)
        without = fit_height((0.9, 20.0), (0.9, 20.0), [], [], _h, 0.0, step, levels=1)
        errs.append((with_b.error, without.error))
    (a1, b1), (a2, b2) = errs
    assert b1 > 10 * a1 and b2 > 30 * a2
    assert a1 / a2 > 4  # at least third order with breaks
    assert b1 / b2 < 2  # stalled without


def test_linear_height_is_exact_and_greville_reproduces_x():
    def plane(x, y):
        ones = np.ones(x.shape, bool)
        return 2.0 * x - 3.0 * y + 1.0, ones, ones

    fit = fit_height((0.0, 10.0), (-5.0, 5.0), [3.0], [], plane, 1e-12, 1.0)
    assert fit.error <= 1e-10
    t = fit.tx
    g = greville(t)
    assert g[0] == t[0] and g[-1] == t[-1] and np.all(np.diff(g) > 0)


def _strip(x, y):
    """A cylinder of radius 1 rising over x < 1 (a fillet strip along y), flat beyond."""
    d = np.maximum(1.0 - x, 0.0)
    z = 1.0 - np.sqrt(np.maximum(1.0 - d * d, 0.0))
    inside = x >= 1.0 - np.sqrt(0.5)
    return z, inside.copy(), inside


def test_a_curved_strip_gets_fine_spans_only_there():
    """On a 50-wide plate whose height is curved only over x < 1, fine spans stay on the
    strip (plus a padding of two probe samples), the flat 48 units get spans doubling away
    from it (graded: a fit's continuation stays near its data), and the fit still meets
    its tolerance."""
    fit = fit_height((0.2, 50.0), (0.0, 20.0), [1.0], [], _strip, 1e-6, 0.25)
    assert fit is not None and fit.error <= 1e-6
    knots = np.unique(fit.tx)
    assert np.sum(knots < 1.0) >= 8  # fine on the strip
    flat = np.diff(knots[knots >= 1.0])
    assert len(flat) <= 10  # log2(48 / spacing) spans, not 48 / spacing
    assert np.allclose(flat[1:-1] / flat[:-2], 2.0)  # doubling (the last one ends at 50)
    assert np.unique(fit.ty).size == 2  # straight along y: a single span


def test_a_fit_too_large_to_solve_is_refused():
    def waves(x, y):
        z = np.sin(x) * np.cos(y)
        return z, np.ones(z.shape, bool), np.ones(z.shape, bool)

    assert fit_height((0.0, 100.0), (0.0, 100.0), [], [], waves, 0.0, 0.05, levels=1) is None


def test_banded_cholesky_matches_the_general_sparse_solve():
    """The normal equations assembled from the tensor structure and solved by banded
    Cholesky give the fit SuperLU gives from the Kronecker design matrix: the same heights
    wherever data pin them (the corner's face, a third of the rectangle empty), in both
    orientations (the band runs along the smaller direction)."""
    from scipy.interpolate import BSpline

    from medax.geometry import tensor_fit as tf

    for nx, ny in ((40, 16), (16, 40)):
        tx = tf.knot_vector(0.9, 20.0, [R], [True, False], 20.0 / nx)
        ty = tf.knot_vector(0.9, 20.0, [R], [True, True], 20.0 / ny)
        xs, ys = tf.span_samples(tx, tf.SAMPLES_PER_SPAN), tf.span_samples(ty, tf.SAMPLES_PER_SPAN)
        z, ok, _ = _h(*np.meshgrid(xs, ys, indexing="ij"))
        bx = BSpline.design_matrix(xs, tx, tf.DEGREE).tocsr()
        by = BSpline.design_matrix(ys, ty, tf.DEGREE).tocsr()
        banded, general = tf.solve_masked(bx, by, ok, z), tf._solve_superlu(bx, by, ok, z)
        assert banded.shape == general.shape == (bx.shape[1], by.shape[1])
        on_data = (bx @ (by @ banded.T).T)[ok] - (bx @ (by @ general.T).T)[ok]
        assert np.abs(on_data).max() <= 1e-9


def test_too_large_a_band_falls_back_to_the_general_solve(monkeypatch):
    from medax.geometry import tensor_fit as tf

    fit = fit_height((0.9, 20.0), (0.9, 20.0), [1.1716, R], [1.1716, R], _h, 2e-5, R / 4)
    monkeypatch.setattr(tf, "MAX_BAND_ENTRIES", 0)
    general = fit_height((0.9, 20.0), (0.9, 20.0), [1.1716, R], [1.1716, R], _h, 2e-5, R / 4)
    assert general.coef.shape == fit.coef.shape
    assert abs(general.error - fit.error) <= 1e-9


def _oblique_kink(x, y):
    """A parabolic rise beyond the oblique line x = 1.3 + 0.15 y, smooth along y: the
    curvature jumps along a line that is no knot line, so the error converges only as h^2
    in the x spacing, and barely depends on the y spacing."""
    d = np.maximum(x - 1.3 - 0.15 * y, 0.0)
    z = 0.25 * d * d * (1.0 + 0.2 * np.sin(y))
    ones = np.ones(x.shape, bool)
    return z, ones, ones.copy()


def test_only_the_direction_that_matters_is_refined(monkeypatch):
    """Across the kink line the x spacing decides the error: refined along x only (and y as
    far as needed), the fit meets the tolerance with under a third of the unknowns of the
    fit refined in both directions (ONE_DIRECTION 0: never one direction alone)."""
    from medax.geometry import tensor_fit as tf

    one = fit_height((0.0, 4.0), (0.0, 4.0), [], [], _oblique_kink, 1e-4, 0.25)
    monkeypatch.setattr(tf, "ONE_DIRECTION", 0.0)
    both = fit_height((0.0, 4.0), (0.0, 4.0), [], [], _oblique_kink, 1e-4, 0.25)
    assert one.error <= 1e-4 and both.error <= 1e-4
    assert one.coef.shape[0] == both.coef.shape[0]  # the same x spacing
    assert 3 * one.coef.size < both.coef.size


def test_coefficient_count_is_that_of_the_knots():
    """The count checked against the cap before any knot vector is built equals the built
    knot vector's (random breaks, fine flags and spacings)."""
    from medax.geometry import tensor_fit as tf

    rng = np.random.default_rng(0)
    for _ in range(200):
        breaks = sorted(rng.uniform(0.05, 0.95, int(rng.integers(0, 4))).tolist())
        fine = rng.integers(0, 2, len(breaks) + 1).astype(bool).tolist()
        sp = float(rng.uniform(0.01, 0.5))
        built = tf.knot_vector(0.0, 1.0, breaks, fine, sp).size - tf.DEGREE - 1
        assert tf._coefficient_count(0.0, 1.0, breaks, fine, sp) == built


def test_a_degenerate_spacing_is_refused_not_raised():
    """A spacing of 0 or 1e-300 (a degenerate piece's radius / 4) is a fit too large to
    solve: None, not a knot vector beyond memory (numpy's 'Maximum allowed size
    exceeded', seen on a box with fillets of three radii)."""
    for step in (0.0, 1e-300):
        assert fit_height((0.9, 20.0), (0.9, 20.0), [R], [R], _h, 1e-6, step) is None


def test_a_fit_that_cannot_reach_its_tolerance_stops_early(monkeypatch):
    """Without the breaks at x, y = R the curvature jumps fall inside spans and the error
    shrinks about 4x per halving: at a tolerance a million times below the first error the
    rate shows after two levels that the last levels (each ~4x the cost) cannot reach it."""
    from medax.geometry import tensor_fit as T

    calls = []
    real = T._fit_once
    monkeypatch.setattr(T, "_fit_once", lambda *a, **k: calls.append(1) or real(*a, **k))
    first = fit_height((0.9, 20.0), (0.9, 20.0), [], [], _h, 1.0, R / 4, levels=1)
    assert first is not None and first.error > 0
    calls.clear()
    fit = fit_height((0.9, 20.0), (0.9, 20.0), [], [], _h, 1e-6 * first.error, R / 4, levels=5)
    assert fit is not None and fit.error > 1e-6 * first.error
    assert len(calls) < 5  # both directions halved 4 times, or the one-direction tries, cost more
    monkeypatch.setattr(T, "HOPELESS", float("inf"))  # the rule off: every level is fitted
    calls.clear()
    fit_height((0.9, 20.0), (0.9, 20.0), [], [], _h, 1e-6 * first.error, R / 4, levels=5)
    assert len(calls) > 4


def test_height_fitter_shares_fits_between_probe_and_full_fit():
    """A coarse probe (one level) then the full refinement on one HeightFitter give the same
    fit as fit_height alone, and the height is sampled only for spacings not fitted before:
    the probe's fit is not made again."""
    from medax.geometry.tensor_fit import HeightFitter

    calls: list[int] = []

    def counted(x, y):
        calls.append(x.size)
        return _h(x, y)

    args = ((0.9, 20.0), (0.9, 20.0), [1.1716, R], [1.1716, R])
    alone = fit_height(*args, counted, 2e-5, R / 4)
    n_alone = len(calls)
    calls.clear()
    fitter = HeightFitter(*args, counted, R / 4)
    probe = fitter.fit(2e-5, levels=1)
    n_probe = len(calls)
    full = fitter.fit(2e-5)
    assert probe is not None and full is not None and alone is not None
    assert probe.spacing == R / 4 and full.spacing < probe.spacing
    np.testing.assert_array_equal(full.coef, alone.coef)
    assert full.error == alone.error
    # the full fit alone: the knot placement's samples and 2 height grids per fit; with the
    # probe first, its level's 2 grids are not taken again
    assert len(calls) == n_alone
    assert n_probe < n_alone


def _dimpled_plate(cx: float, cy: float, a: float, hole: tuple[float, float, float]):
    """A plate ``z = 0.01 x`` on [0, 100]^2 with a C1 bump of radius ``a`` at (cx, cy)
    (``0.2 (1 - rho^2 / a^2)^2``: its curvature jumps on the circle) and a round hole
    (centre x, y, radius) where the face has no data."""
    hx, hy, hr = hole

    def h(x, y):
        rho2 = ((x - cx) ** 2 + (y - cy) ** 2) / a**2
        z = 0.01 * x + np.where(rho2 < 1.0, 0.2 * (1.0 - rho2) ** 2, 0.0)
        face = (x - hx) ** 2 + (y - hy) ** 2 > hr**2
        return z, face.copy(), face

    return h


def test_a_bump_between_the_probe_lines_is_found_by_probes_through_it():
    """A bump narrower than the uniform probe lines' spacing (2.5) that none of them crosses
    looks flat: one span over it and a large error; lines through its rim find it."""
    from medax.geometry.tensor_fit import HeightFitter

    cx = cy = 51.25  # halfway between the uniform lines at 50 and 52.5
    h = _dimpled_plate(cx, cy, 0.7, (20.0, 80.0, 8.0))
    blind = HeightFitter((0.0, 100.0), (0.0, 100.0), [], [], h, 0.25).fit(1e-3, 3)
    t = np.linspace(0.0, 2 * np.pi, 48)
    rim = (cx + 0.7 * np.cos(t), cy + 0.7 * np.sin(t))
    seen = HeightFitter((0.0, 100.0), (0.0, 100.0), [], [], h, 0.25, rim).fit(1e-3, 3)
    assert blind is not None and seen is not None
    assert blind.error > 0.05  # the bump is 0.2 high
    assert seen.error <= 1e-3


def test_a_flat_span_over_a_hole_keeps_samples_on_both_sides():
    """A plane with a hole 16 wide under one long flat span: sampled at most a spacing
    apart, every column keeps data on both sides of the hole and the plane is fitted to
    rounding (4 samples per span left columns with 2 and a free cubic)."""
    from medax.geometry.tensor_fit import HeightFitter, span_samples, span_weights

    h = _dimpled_plate(80.0, 80.0, 1.0, (30.0, 30.0, 8.0))
    rim = (80.0 + np.cos(np.linspace(0, 6.3, 48)), 80.0 + np.sin(np.linspace(0, 6.3, 48)))
    fit = HeightFitter((0.0, 100.0), (0.0, 100.0), [], [], h, 0.25, rim).fit(1e-3, 3)
    assert fit is not None and fit.error <= 1e-3
    xc, yc = fit.check_samples()
    x, y = np.meshgrid(xc, yc, indexing="ij")
    flat = (x < 60.0) & (y < 60.0) & h(x, y)[2]  # round the hole, far from the bump
    assert np.abs(fit(xc, yc) - 0.01 * x)[flat].max() <= 1e-9
    # the samples of a long span are at most the gap apart, and the cells cover the range
    t = np.array([0.0] * 4 + [1.0, 41.0] + [42.0] * 4)
    s, w = span_samples(t, 4, 2.0), span_weights(t, 4, 2.0)
    assert np.diff(s).max() <= 2.0 + 1e-12 and abs(w.sum() - 42.0) < 1e-12
    assert np.allclose(s, np.cumsum(w) - w / 2)


def test_the_fit_does_not_run_off_where_it_has_no_data():
    """The corner's heights continue to at most R where the face ends (the sphere's own
    continuation); the fit there must not run off: the coefficients whose functions only
    touch the face with their tails are held by the penalty (unheld: 29 = 7 R, and a
    larger error inside)."""
    fitter = HeightFitter((0.9, 20.0), (0.9, 20.0), [1.1716, R], [1.1716, R], _h, R / 4)
    fit = fitter.fit_at(R / 16, R / 16)
    assert fit is not None and fit.error <= 2e-5
    xs = np.linspace(0.9, 20.0, 300)
    assert np.abs(fit(xs, xs)).max() <= 1.5 * R
