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


def _cardinal_cubic(x):
    """The uniform cubic B-spline on [0, 4] in closed form (independent of scipy)."""
    x = np.asarray(x, float)
    return np.select(
        [(x >= 0) & (x < 1), (x >= 1) & (x < 2), (x >= 2) & (x < 3), (x >= 3) & (x < 4)],
        [
            x**3 / 6,
            (-3 * x**3 + 12 * x**2 - 12 * x + 4) / 6,
            (3 * x**3 - 24 * x**2 + 60 * x - 44) / 6,
            (4 - x) ** 3 / 6,
        ],
        0.0,
    )


def test_periodic_basis_is_the_wrapped_cardinal_cubic():
    n = 9
    th = np.linspace(-7.0, 14.0, 501)
    b = periodic_design(th, n).toarray()
    u = th / (PERIOD / n)  # angle in spans
    cols = np.arange(n)
    truth = _cardinal_cubic(np.mod(u[:, None] - cols[None, :] + 3.0, n))
    assert np.abs(b - truth).max() <= 1e-12
    assert np.allclose(b.sum(axis=1), 1.0, atol=1e-14)


def test_smooth_radial_height_converges_and_is_seamless():
    fit = fit_radial_height((0.0, 3.0), [], _bump, 1e-5, 0.5, R0, levels=6)
    assert fit is not None and fit.error <= 1e-5
    # dense, random, off the check grid: the measured error is honest
    rng = np.random.default_rng(1)
    th, s = rng.uniform(0, PERIOD, 20000), rng.uniform(0, 3, 20000)
    worst = np.abs(fit.at(th, s) - _bump(th, s)[0]).max()
    assert worst <= 1.5e-5
    # across the seam theta = 0 the left side is evaluated on the spans just below 2 pi,
    # the right side on those above 0: one-sided slopes agree as at an interior angle
    s_line = np.linspace(0, 3, 31)
    e = 1e-5

    def slope_jump(t0):
        f = fit(np.array([t0 - e, t0, t0 + e]), s_line)
        return np.abs((f[2] - f[1]) - (f[1] - f[0])).max() / e

    assert slope_jump(0.0) <= 1e-3
    assert slope_jump(0.0) <= 10 * slope_jump(np.pi) + 1e-9


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
