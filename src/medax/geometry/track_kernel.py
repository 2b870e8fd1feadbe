"""Compiled (numba) node tracking of the ratio grid: Newton steps from warm starts on the
jets of :mod:`medax.geometry.kernels` (announced and warmed up there with the others)."""

from __future__ import annotations

import numpy as np
from numba import njit

from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray
from medax.geometry.table_kernel import table_jet1, table_span


@njit(**HELPER)
def _track1(
    w: FloatArray, xs: FloatArray, i: int, t: float, tol: float, last: bool, foot: FloatArray
) -> tuple[float, float, bool]:
    """One tracking step (:func:`medax.geometry.curve.track_rows`) of point ``xs[:, i]``
    (xs (dim, n)) from its foot ``t`` with the jet ``w`` (3, dim) there: a Newton step on
    ``g = (C - x) . C'`` (a gradient step scaled by the speed where ``g' <= 0``), clamped to
    ``[0, 1]``; into ``foot[:, i]`` the Taylor point of the step. Returns the new foot, the
    curvature term ``|(C - x) . C''| / g'`` (inf unless settled; where ``g' <= 0``: 0 for a
    foot held at an end, else inf) and whether the row is done (a step of at most ``tol``
    that is a Newton step or held, or the ``last`` step)."""
    dim = xs.shape[0]
    c = w[0, 0] - xs[0, i]
    g = c * w[1, 0]
    speed2 = w[1, 0] * w[1, 0]
    dg = c * w[2, 0]
    for d in range(1, dim):
        c = w[0, d] - xs[d, i]
        g += c * w[1, d]
        speed2 += w[1, d] * w[1, d]
        dg += c * w[2, d]
    dg += speed2
    pos = dg > 0.0
    den = dg if pos else speed2
    if den < 1e-300:
        den = 1e-300
    new = t - g / den
    if new == new:
        new = min(max(new, 0.0), 1.0)
    ds = new - t
    zero = ds == 0.0
    settled = abs(ds) <= tol and (pos or zero)
    kap = abs(dg - speed2) / den
    if not settled:
        kap = np.inf
    if not pos:
        kap = 0.0 if zero and (new == 0.0 or new == 1.0) else np.inf
    half = 0.5 * ds
    for d in range(dim):
        foot[d, i] = (w[2, d] * half + w[1, d]) * ds + w[0, d]
    return new, kap, last or settled


@njit(**KERNEL)
def track_table(  # type: ignore[no-untyped-def]
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    offset: FloatArray,
    xs: FloatArray,
    t0: FloatArray,
    tol: FloatArray,
    iters: int,
):
    """:func:`medax.geometry.curve.track_rows` on a polynomial table (:func:`jet_rows`;
    point ``i`` on curve ``offset[i] / 2``, empty ``offset``: curve 0): points ``xs``
    (dim, n) from feet ``t0`` (n,, in [0, 1]), step tolerances ``tol`` (n,, or (1,) for
    all), at most ``iters`` steps per row (:func:`_track1`). Feet (n,), foot points
    (dim, n), curvature terms (n,)."""
    n = t0.size
    dim = xs.shape[0]
    t_out = t0.copy()
    foot = np.empty((dim, n))
    kap = np.zeros(n)
    w = np.empty((3, dim))
    for i in range(n):
        ti = t_out[i]
        off = offset[i] if offset.size else 0.0
        tl = tol[i] if tol.size > 1 else tol[0]
        for it in range(iters):
            span = table_span(inner, ti + off)
            table_jet1(rows, span, ti - starts[span], w)
            ti, kap[i], done = _track1(w, xs, i, ti, tl, it == iters - 1, foot)
            if done:
                break
        t_out[i] = ti
    return t_out, foot, kap


@njit(**KERNEL)
def track_step_rows(  # type: ignore[no-untyped-def]
    jets: FloatArray, xs: FloatArray, t: FloatArray, tol: FloatArray, last: bool
):
    """One tracking step (:func:`_track1`) of every row, the jets ``jets`` (3 * dim, n)
    evaluated by the caller (curves without a polynomial table): new feet (n,), foot points
    (dim, n), curvature terms (n,), done (n,)."""
    n = t.size
    dim = xs.shape[0]
    new = np.empty(n)
    foot = np.empty((dim, n))
    kap = np.empty(n)
    done = np.empty(n, dtype=np.bool_)
    w = np.empty((3, dim))
    for i in range(n):
        for o in range(3):
            for d in range(dim):
                w[o, d] = jets[o * dim + d, i]
        tl = tol[i] if tol.size > 1 else tol[0]
        new[i], kap[i], done[i] = _track1(w, xs, i, t[i], tl, last, foot)
    return new, foot, kap, done
