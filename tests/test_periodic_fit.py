"""The periodic radial height fit against analytic radial heights (independent truth)."""

import numpy as np

from medax.geometry.periodic_fit import PERIOD, fit_radial_height, periodic_design

R0 = 2.0


def _bump(th, s):
    r = R0 + 0.3 * np.exp(-(((s - 1.0) / 0.5) ** 2)) * (
        1.0 + 0.5 * np.cos(th) + 0.2 * np.sin(2 * th)
    )
    ok = np.ones(r.shape, bool)
    return r, ok, ok


def test_periodic_basis_is_a_partition_of_unity_and_periodic():
    th = np.linspace(-7.0, 14.0, 501)
    b = periodic_design(th, 9).toarray()
    assert np.allclose(b.sum(axis=1), 1.0, atol=1e-14)
    assert np.allclose(b, periodic_design(th + PERIOD, 9).toarray(), atol=1e-13)


def test_smooth_radial_height_converges_and_is_seamless():
    fit = fit_radial_height((0.0, 3.0), [], _bump, 1e-5, 0.5, R0, levels=6)
    assert fit is not None and fit.error <= 1e-5
    # dense, random, off the check grid: the measured error is honest
    rng = np.random.default_rng(1)
    th, s = rng.uniform(0, PERIOD, 20000), rng.uniform(0, 3, 20000)
    worst = np.abs(fit.at(th, s) - _bump(th, s)[0]).max()
    assert worst <= 1.5e-5
    # across the seam: value and slope continuous (periodic, no seam)
    s_line = np.linspace(0, 3, 31)
    e = 1e-7
    a, b = (
        fit(np.array([-e, 0.0, e]), s_line),
        fit(np.array([PERIOD - e, PERIOD, PERIOD + e]), s_line),
    )
    assert np.allclose(a, b, atol=1e-12)


def test_curvature_jump_on_a_break_converges():
    # cylinder for s < 1, a quadratic flare after: the jump sits on the C1 knot line
    def h(th, s):
        r = R0 + 0.2 * np.maximum(s - 1.0, 0.0) ** 2 * (1.0 + 0.3 * np.cos(th))
        ok = np.ones(r.shape, bool)
        return r, ok, ok

    fit = fit_radial_height((0.0, 2.0), [1.0], h, 1e-6, 0.5, R0, levels=6)
    assert fit is not None and fit.error <= 1e-6
    th = np.linspace(0, PERIOD, 97)
    assert np.abs(fit(th, np.linspace(0, 0.99, 50)) - R0).max() <= 1e-6
