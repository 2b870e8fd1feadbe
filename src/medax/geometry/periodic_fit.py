"""Least-squares radial height ``r(theta, s)`` over a cylinder's own frame: a tensor cubic
B-spline, periodic in the angle ``theta`` (period ``2 pi``, uniform knots, no seam: the
surface and all its derivatives match across ``theta = 0``), clamped in the axial
coordinate ``s`` with double (C1) knots at prescribed ``s`` breaks.

The route a fillet half over a cylinder needs (issue 5: the slanted boss's cylinder side):
the merged face is ``x = o + s a + r(theta, s) (cos theta e1 + sin theta e2)`` in the
cylinder's frame, ``r`` the cylinder's radius where the face is the cylinder and the
blend's distance from the axis on the half. Same conventions as
:mod:`medax.geometry.tensor_fit` (masked data, a small second-difference penalty decides
where there are none, error measured on a check grid of 7 points per span, not the fitting
samples), but the periodic direction wraps the normal matrix, so no banded Cholesky: the
Kronecker design matrix and SuperLU (the fits here are a few thousand unknowns).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import BSpline

from medax.geometry._types import FloatArray
from medax.geometry.tensor_fit import (
    CHECK_PER_SPAN,
    DEGREE,
    MAX_COEFFICIENTS,
    SAMPLES_PER_SPAN,
    HeightFn,
    _solve_superlu,
    knot_vector,
    refine_both,
    span_samples,
)

PERIOD = 2.0 * np.pi
#: ``outside(theta, s) -> values``: what a fit returns to where it has no data (the shape of
#: the data's values on the grid).
PriorFn = Callable[[FloatArray, FloatArray], FloatArray]


def periodic_knots(n: int) -> FloatArray:
    """Uniform knots ``k 2 pi / n``, ``k = -DEGREE .. n + DEGREE``: the ``n + DEGREE``
    B-splines on them, folded modulo ``n`` (:func:`periodic_design`), are the ``n``
    periodic cubic B-splines of period ``2 pi``."""
    return np.asarray(np.arange(-DEGREE, n + DEGREE + 1) * (PERIOD / n), dtype=np.float64)


def periodic_design(theta: FloatArray, n: int) -> sp.csr_matrix:
    """(len(theta), n) design matrix of the periodic cubic B-splines with ``n`` uniform
    spans at the angles ``theta`` (any real values: reduced modulo ``2 pi``)."""
    t = periodic_knots(n)
    x = np.mod(np.asarray(theta, dtype=float), PERIOD)
    b = BSpline.design_matrix(x, t, DEGREE).tocoo()
    return sp.csr_matrix((b.data, (b.row, b.col % n)), shape=(x.size, n))


def _periodic_second_diff(n: int) -> sp.spmatrix:
    """Cyclic second differences of ``n`` coefficients."""
    i = np.arange(n)
    rows = np.repeat(i, 3)
    cols = np.column_stack([i, (i + 1) % n, (i + 2) % n]).ravel()
    vals = np.tile([1.0, -2.0, 1.0], n)
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


@dataclass(frozen=True)
class PeriodicFit:
    """``r(theta, s) = sum_ij c_ij T_i(theta) S_j(s)``: ``n_theta`` periodic uniform spans
    in theta, clamped cubic knot vector ``ts`` in s (with repeats), coefficients ``coef``
    (n_theta, ns), or (n_theta, ns, k) for values with ``k`` components (points: k = 3),
    measured ``error`` (max |r - h| on the check grid where ``inside``, the Euclidean norm
    for components; length unit)."""

    n_theta: int
    ts: FloatArray
    coef: FloatArray
    error: float

    def __call__(self, theta: FloatArray, s: FloatArray) -> FloatArray:
        """Values on the tensor grid ``theta`` (n,) by ``s`` (m,), shape (n, m) (or
        (n, m, k))."""
        bt = periodic_design(theta, self.n_theta)
        bs = BSpline.design_matrix(np.asarray(s, dtype=float), self.ts, DEGREE).tocsr()
        n, m = bt.shape[0], bs.shape[0]
        nt, ns = self.coef.shape[:2]
        along = np.asarray(bt @ self.coef.reshape(nt, -1)).reshape(n, ns, -1)  # (n, ns, k)
        out = np.asarray(bs @ along.transpose(1, 0, 2).reshape(ns, -1))  # (m, n k)
        return out.reshape(m, n, -1).transpose(1, 0, 2).reshape((n, m, *self.coef.shape[2:]))

    def at(self, theta: FloatArray, s: FloatArray) -> FloatArray:
        """Values at the points ``(theta[k], s[k])`` (scattered, not a grid)."""
        bt = periodic_design(theta, self.n_theta)
        bs = BSpline.design_matrix(np.asarray(s, dtype=float), self.ts, DEGREE).tocsr()
        nt, ns = self.coef.shape[:2]
        along = np.asarray(bt @ self.coef.reshape(nt, -1)).reshape(bt.shape[0], ns, -1)
        # DEGREE + 1 entries per row of the s design matrix
        idx = bs.indices.reshape(-1, DEGREE + 1)
        val = bs.data.reshape(-1, DEGREE + 1)
        rows = np.arange(bt.shape[0])[:, None]
        out = np.einsum("pq,pqk->pk", val, along[rows, idx])
        return out.reshape((bt.shape[0], *self.coef.shape[2:]))


def _fit_once(
    s_range: tuple[float, float],
    sb: list[float],
    fine: list[bool],
    h: HeightFn,
    n_theta: int,
    step: float,
    zero_last: int | None = None,
    outside: PriorFn | None = None,
) -> PeriodicFit:
    ts = knot_vector(s_range[0], s_range[1], sb, fine, step)
    tt = np.unique(periodic_knots(n_theta)[DEGREE : n_theta + DEGREE + 1])
    th = span_samples(tt, SAMPLES_PER_SPAN)
    ss = span_samples(ts, SAMPLES_PER_SPAN)
    grid = np.meshgrid(th, ss, indexing="ij")
    z, ok, _ = h(*grid)
    prior = None if outside is None else outside(*grid)
    bt = periodic_design(th, n_theta)
    bs = BSpline.design_matrix(ss, ts, DEGREE).tocsr()
    cyclic = _periodic_second_diff(n_theta)
    if zero_last is None:
        coef = _solve_superlu(bt, bs, ok, z, diff_x=cyclic, prior=prior)
    else:
        # the component ``zero_last`` held at zero on the last interval: the s functions
        # whose support meets it are not solved for (zero there, so exactly zero)
        free = ts[DEGREE + 1 :] <= sb[-1] + 1e-12 * (s_range[1] - s_range[0])
        k = z.shape[2]
        rest = [c for c in range(k) if c != zero_last]
        coef = np.zeros((n_theta, ts.size - DEGREE - 1, k))
        part = (None, None) if prior is None else (prior[..., rest], prior[..., zero_last])
        coef[:, :, rest] = _solve_superlu(bt, bs, ok, z[..., rest], diff_x=cyclic, prior=part[0])
        coef[:, :, zero_last] = _solve_superlu(
            bt, bs, ok, z[..., zero_last], diff_x=cyclic, free_y=free, prior=part[1]
        )
    fit = PeriodicFit(n_theta, ts, coef, 0.0)
    thc, sc = span_samples(tt, CHECK_PER_SPAN), span_samples(ts, CHECK_PER_SPAN)
    zc, okc, inside = h(*np.meshgrid(thc, sc, indexing="ij"))
    if np.any(inside & ~okc):
        error = float("inf")  # data missing inside the face
    else:
        diff = np.abs(fit(thc, sc) - zc)
        if diff.ndim == 3:
            diff = np.linalg.norm(diff, axis=2)
        error = float(diff[inside].max(initial=0.0))
    return replace(fit, error=error)


def fit_radial_height(
    s_range: tuple[float, float],
    s_breaks: Sequence[float],
    h: HeightFn,
    tol: float,
    spacing: float,
    radius: float,
    levels: int = 5,
    s_fine: Sequence[bool] | None = None,
    zero_last: int | None = None,
    outside: PriorFn | None = None,
) -> PeriodicFit | None:
    """Fit the radial height ``h(theta, s)`` to ``tol`` (length unit) over the full turn and
    ``s_range``, spans of at most ``spacing`` (length: in theta arc length at ``radius``),
    halved at most ``levels - 1`` times while the error misses ``tol`` and keeps falling
    (:func:`medax.geometry.tensor_fit.refine_both`: in one direction alone when the other hardly
    matters). The best fit with its measured error (the
    caller decides), None when even the first level has more than ``MAX_COEFFICIENTS``.
    ``s_breaks``: axial coordinates where the curvature may jump (C1 knots there);
    ``s_fine``: per interval between them, False where the values are linear in ``s`` (one
    span there; default: all fine). ``h`` may give values with components, (..., k) (the
    points of a surface: :mod:`medax.geometry.ring_heights`); they share the knots and the
    factorisation, and the error is the largest distance. ``zero_last``: a component that
    is zero on the last interval between the breaks (a height off the support), fitted with
    its coefficients there held at zero, so it is exactly zero there (it needs a break).
    ``outside(theta, s)``: the values the fit returns to where ``h`` has no data (the
    supporting surface's, taken at ``PRIOR_WEIGHT``)."""
    s0, s1 = s_range
    sb = sorted(b for b in set(s_breaks) if s0 < b < s1)
    fine = [True] * (len(sb) + 1) if s_fine is None else list(s_fine)
    if len(fine) != len(sb) + 1:
        raise ValueError("s_fine needs one flag per interval between the breaks inside s_range")
    if zero_last is not None and not sb:
        raise ValueError("zero_last needs a break: the component is zero after the last one")

    def fit_at(step_theta: float, step_s: float) -> PeriodicFit | None:
        n_theta = max(4, int(np.ceil(PERIOD * radius / step_theta - 1e-9)))
        ns = knot_vector(s0, s1, sb, fine, step_s).size - DEGREE - 1
        if n_theta * ns > MAX_COEFFICIENTS:
            return None
        return _fit_once(s_range, sb, fine, h, n_theta, step_s, zero_last, outside)

    return refine_both(fit_at, spacing, tol, levels)
