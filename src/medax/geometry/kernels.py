"""Compiled (numba) kernels of the closest-point queries and B-spline jets.

The axis tracer's distance-field queries are mostly 1 - 100 points: in numpy their time is
per-call overhead (tens of array calls per query), not arithmetic. These kernels run the
same algorithms as compiled loops over the points, one call per query:

* :func:`jet_rows` - value, first and second derivative of piecewise polynomials (B-splines
  in the power basis, several curves stacked in one table) by Horner's rule;
* :func:`closest_search` - the global closest points of :func:`medax.geometry.curve.
  closest_by_search` on such tables: the ``k`` best local minima of the sampled distance,
  the sign-change bracket of each, a bracketed Newton iteration, the C0 corners;
* :func:`closest_bracketed` - the bracketed Newton of
  :func:`medax.geometry.curve.closest_near` on such tables;
* :func:`candidates` and :func:`newton_rows` - the candidate search and one safeguarded
  Newton step for the curves without a polynomial table (their jets come from Python);
* :func:`newton_table` - the whole safeguarded Newton iteration of curves with a jet table
  but no global search table (rational B-splines: the homogeneous jet and the quotient
  rule in the kernel; a separate global search kernel for them cost 2.4 s more to compile
  for a few percent of a part's axis time);
* ``track_table`` and ``track_step_rows`` (:mod:`medax.geometry.track_kernel`) - the
  ratio grid's node tracking (Newton steps from warm starts);
* ``crossing`` (:mod:`medax.geometry.crossing_kernel`) - the region's side-crossing checks;
* ``span_basis_rows`` (:mod:`medax.geometry.basis_kernel`) - B-spline basis values and
  derivatives, per span polynomials or Cox-de Boor; ``jet_rows`` and ``heights_newton``
  (:mod:`medax.geometry.nurbs_kernel`) - NURBS surface jets and the Newton of
  :func:`medax.geometry.surface_heights.graph_heights` (announced and warmed up here with
  the others);
* ``winslow_sweeps`` (:mod:`medax.geometry.grid_kernel`) - the mesh quality pass.

Compiled with ``cache=True``: the first run after an install compiles (a few seconds, logged
at INFO) and stores the machine code in ``__pycache__`` next to this file, or, where that is
not writable (a read-only site-packages), in numba's user-wide cache directory
(``NUMBA_CACHE_DIR`` overrides it).
"""

from __future__ import annotations

import logging
import os
import time
from typing import Any

import numpy as np
from numba import njit

from medax.geometry import grid_kernel
from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray
from medax.geometry.basis_kernel import span_basis_rows
from medax.geometry.crossing_kernel import crossing
from medax.geometry.nurbs_kernel import heights_newton
from medax.geometry.table_kernel import table_jet1, table_span
from medax.geometry.track_kernel import track_step_rows, track_table

log = logging.getLogger(__name__)

#: a Newton step on the foot parameter at most this long ends a row (see
#: :data:`medax.geometry.curve._STEP_TOL`)
STEP_TOL = 1e-8
#: steps of the plain Newton iteration before the safeguarded one takes over
QUICK_STEPS = 3
#: steps of the safeguarded iteration at most (bisection halves the bracket each time)
SAFE_STEPS = 60


# ---- jets ---------------------------------------------------------------------------------
@njit(**KERNEL)
def jet_rows(
    inner: FloatArray, starts: FloatArray, rows: FloatArray, t: FloatArray, offset: FloatArray
) -> FloatArray:
    """Jets as component rows (3 * dim, n) of stacked piecewise polynomials
    (:meth:`medax.geometry.bspline.BSpline.stacked_rows`: interior breaks ``inner``, span
    starts ``starts``, coefficients ``rows`` (degree + 1, dim, spans)) at local parameters
    ``t`` (n,) of the curves ``offset / 2`` (n,; empty: all on curve 0)."""
    n, dim = t.size, rows.shape[1]
    out = np.empty((3 * dim, n))
    w = np.empty((3, dim))
    for i in range(n):
        u = t[i] + (offset[i] if offset.size else 0.0)
        span = table_span(inner, u)
        table_jet1(rows, span, t[i] - starts[span], w)
        for o in range(3):
            for d in range(dim):
                out[o * dim + d, i] = w[o, d]
    return out


# ---- Newton steps -------------------------------------------------------------------------
@njit(**HELPER)
def _g_dg(w: FloatArray, x: FloatArray) -> tuple[float, float]:
    """``g = (C - x) . C'`` and ``g' = C' . C' + (C - x) . C''`` from a jet ``w`` (3, dim)."""
    g = 0.0
    speed2 = 0.0
    curv = 0.0
    for d in range(x.size):
        c = w[0, d] - x[d]
        g += c * w[1, d]
        speed2 += w[1, d] * w[1, d]
        curv += c * w[2, d]
    return g, speed2 + curv


@njit(**HELPER)
def _clamp(v: float, lo: float, hi: float) -> float:
    """``min(max(v, lo), hi)`` with numpy's NaN propagation."""
    if v != v:
        return v
    return min(max(v, lo), hi)


@njit(**HELPER)
def _safe_step(
    g: float, dg: float, s: float, a: float, b: float, last: bool
) -> tuple[float, float, float, bool, float]:
    """One step of the safeguarded Newton iteration at ``s`` in the sign-change bracket
    ``[a, b]`` (``g(a) < 0 < g(b)``): the next parameter, the shrunk bracket, whether the
    row is done, and the step to its foot (0 unless the step was a short Newton step).
    Bisection where the Newton step leaves the bracket or ``g' <= 0``; done at a step of
    at most :data:`STEP_TOL`, a bracket of 4e-16, ``g = 0`` or the ``last`` step."""
    aa = s if g < 0.0 else a
    bb = s if g > 0.0 else b
    step = g / dg if dg > 0.0 else np.inf
    new = s - step
    small = abs(step) <= STEP_TOL
    bad = not (new >= aa) or not (new <= bb)
    kept = _clamp(new, aa, bb)
    if small:
        new = kept
    elif bad:
        new = 0.5 * (aa + bb)
    done = small or (bb - aa <= 4e-16) or g == 0.0 or last
    ds = kept - s if small else 0.0
    if done:
        new = kept if small else s
    return new, aa, bb, done, ds


@njit(**KERNEL)
def newton_rows(
    c0: FloatArray,
    c1: FloatArray,
    c2: FloatArray,
    x: FloatArray,
    s: FloatArray,
    a: FloatArray,
    b: FloatArray,
    last: bool,
    foot: FloatArray,
) -> np.ndarray:
    """One safeguarded Newton step (:func:`_safe_step`) of rows whose jets ``c0, c1, c2``
    (n, dim) at ``s`` (n,) were evaluated by the caller (curves without a polynomial
    table), points ``x`` (n, dim), brackets ``a``, ``b`` (n,): ``s``, ``a``, ``b`` updated in
    place, the done rows' foot points (Taylor from the jet) into ``foot`` (n, dim); returns
    which rows are done (n,)."""
    n, dim = x.shape
    done = np.empty(n, dtype=np.bool_)  # (every row set below)
    w = np.empty((3, dim))
    for i in range(n):
        for d in range(dim):
            w[0, d], w[1, d], w[2, d] = c0[i, d], c1[i, d], c2[i, d]
        g, dg = _g_dg(w, x[i])
        s[i], a[i], b[i], done[i], ds = _safe_step(g, dg, s[i], a[i], b[i], last)
        if done[i]:
            for d in range(dim):
                foot[i, d] = w[0, d] + ds * (w[1, d] + 0.5 * ds * w[2, d])
    return done


@njit(**HELPER)
def _jet_table(
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    rational: bool,
    t: float,
    h: FloatArray,
    w: FloatArray,
) -> None:
    """Into ``w`` (3, dim): the jet of a one-curve table (:func:`jet_rows`) at ``t``
    clamped to ``[0, 1]``, as :meth:`medax.geometry.bspline.BSpline.jet` forms it: of a
    rational curve from its homogeneous jet (``rows`` (degree + 1, dim + 1, spans), weight
    last; into ``h`` (3, dim + 1)) by the quotient rule, in the same operations."""
    if t == t:
        t = min(max(t, 0.0), 1.0)
    span = table_span(inner, t)
    if not rational:
        table_jet1(rows, span, t - starts[span], w)
        return
    table_jet1(rows, span, t - starts[span], h)
    dim = w.shape[1]
    w0, w1, w2 = h[0, dim], h[1, dim], h[2, dim]
    for d in range(dim):
        c = h[0, d] / w0
        d1 = (h[1, d] - w1 * c) / w0
        w[0, d] = c
        w[1, d] = d1
        w[2, d] = (h[2, d] - 2.0 * w1 * d1 - w2 * c) / w0


@njit(**KERNEL)
def newton_table(  # type: ignore[no-untyped-def]
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    rational: bool,
    x: FloatArray,
    a: FloatArray,
    b: FloatArray,
    s: FloatArray,
    iters: int,
):
    """The safeguarded Newton iteration of :func:`medax.geometry.curve._newton_in_brackets`
    (:func:`_safe_step` from ``s`` (n,) in the brackets ``a``, ``b`` (n,), at most ``iters``
    steps) for points ``x`` (n, dim) on a one-curve table, its jets evaluated here
    (:func:`_jet_table`): parameters (n,) and foot points (n, dim)."""
    n, dim = x.shape
    t = np.empty(n)
    foot = np.empty((n, dim))
    w = np.empty((3, dim))
    h = np.empty((3, dim + 1))
    for i in range(n):
        si, ai, bi = s[i], a[i], b[i]
        if not np.isfinite(si):
            si = 0.5 * (ai + bi)
        for it in range(iters):
            _jet_table(inner, starts, rows, rational, si, h, w)
            g, dg = _g_dg(w, x[i])
            si, ai, bi, done, ds = _safe_step(g, dg, si, ai, bi, it == iters - 1)
            if done:
                for d in range(dim):
                    foot[i, d] = w[0, d] + ds * (w[1, d] + 0.5 * ds * w[2, d])
                break
        t[i] = si
    return t, foot


@njit(**HELPER)
def _refine(
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    off: float,
    x: FloatArray,
    a: float,
    b: float,
    s: float,
    w: FloatArray,
    foot: FloatArray,
) -> float:
    """The root of ``g`` in ``[a, b]`` (``g(a) < 0 < g(b)``) of one curve of a table from a
    good start ``s``: :data:`QUICK_STEPS` plain Newton steps clamped to the bracket, then
    (rows that did not settle) the safeguarded iteration from where they are. Returns the
    parameter; its foot point (Taylor from the last jet) into ``foot`` (dim,)."""
    dim = x.size
    new = s
    ds = 0.0
    for _ in range(QUICK_STEPS):
        span = table_span(inner, s + off)
        table_jet1(rows, span, s - starts[span], w)
        g, dg = _g_dg(w, x)
        new = _clamp(s - g / dg, a, b)
        ds = new - s
        if dg > 0.0 and abs(ds) <= STEP_TOL:
            for d in range(dim):
                foot[d] = w[0, d] + ds * (w[1, d] + 0.5 * ds * w[2, d])
            return new
        s = new
    if not np.isfinite(s):
        s = 0.5 * (a + b)
    for it in range(SAFE_STEPS):
        span = table_span(inner, s + off)
        table_jet1(rows, span, s - starts[span], w)
        g, dg = _g_dg(w, x)
        s, a, b, done, ds = _safe_step(g, dg, s, a, b, it == SAFE_STEPS - 1)
        if done:
            for d in range(dim):
                foot[d] = w[0, d] + ds * (w[1, d] + 0.5 * ds * w[2, d])
            break
    return s


# ---- closest points on polynomial tables --------------------------------------------------
@njit(**HELPER)
def _corner(
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    off: float,
    breaks: FloatArray,
    x: FloatArray,
    lo: float,
    hi: float,
    t: float,
    foot: FloatArray,
    w: FloatArray,
) -> float:
    """:func:`medax.geometry.curve.at_breaks` for one row: the first C0 corner of ``breaks``
    (local parameters of this curve) in ``[lo, hi]`` if it is nearer to ``x`` than ``foot``
    (then written into ``foot``); returns the parameter."""
    if breaks.size == 0:
        return t
    i = 0  # np.searchsorted(breaks, lo, side="left"), by bisection (NaN above all)
    j = breaks.size
    while i < j:
        mid = (i + j) >> 1
        if breaks[mid] < lo or lo != lo:
            i = mid + 1
        else:
            j = mid
    if i >= breaks.size or breaks[i] > hi:
        return t
    e = breaks[i]
    span = table_span(inner, e + off)
    table_jet1(rows, span, e - starts[span], w)
    dc = 0.0
    df = 0.0
    for d in range(x.size):
        dc += (w[0, d] - x[d]) ** 2
        df += (foot[d] - x[d]) ** 2
    if dc < df:
        for d in range(x.size):
            foot[d] = w[0, d]
        return e
    return t


@njit(**HELPER)
def _table_d2(ct: FloatArray, pp: FloatArray, x: FloatArray, i: int, d2: FloatArray) -> None:
    """Into ``d2`` (m,): ``|x_i - p_j|^2 - |x_i|^2`` for the table's samples ``p_j``
    (``ct`` (dim, m) their coordinates, ``pp`` (m,) their squared norms; the per-point
    constant does not move the minima), a loop over contiguous rows per coordinate."""
    m, dim = ct.shape[1], ct.shape[0]
    x0 = x[i, 0]
    for j in range(m):
        d2[j] = ct[0, j] * x0
    for d in range(1, dim):
        xd = x[i, d]
        for j in range(m):
            d2[j] += ct[d, j] * xd
    for j in range(m):
        d2[j] = pp[j] - 2.0 * d2[j]


@njit(**KERNEL)
def candidates(ct: FloatArray, pp: FloatArray, bounds: np.ndarray, x: FloatArray, k: int):  # type: ignore[no-untyped-def]
    """Indices (n, curves, k) of the ``k`` nearest local minima of the sampled distance of
    each point ``x`` (n, dim; centred as the samples) on each curve; samples ``ct``
    (dim, m) centred, coordinates as rows, ``pp`` (m,) their squared norms, curve ``j`` on
    samples ``bounds[j]:bounds[j + 1]``. Rows with fewer than ``k`` minima repeat their best
    one."""
    n, dim = x.shape
    m = ct.shape[1]
    nc = bounds.size - 1
    out = np.empty((n, nc, k), dtype=np.int64)
    d2 = np.empty(m)
    best_v = np.empty(k)
    for i in range(n):
        _table_d2(ct, pp, x, i, d2)
        for c in range(nc):
            lo, hi = bounds[c], bounds[c + 1]
            cnt = 0
            for j in range(lo, hi):
                v = d2[j]
                if j > lo and not v <= d2[j - 1]:
                    continue
                if j < hi - 1 and not v <= d2[j + 1]:
                    continue
                # insert among the k best (earlier index first on ties)
                pos = min(cnt, k)
                while pos > 0 and v < best_v[pos - 1]:
                    pos -= 1
                if pos < k:
                    for q in range(min(cnt, k - 1), pos, -1):
                        best_v[q] = best_v[q - 1]
                        out[i, c, q] = out[i, c, q - 1]
                    best_v[pos] = v
                    out[i, c, pos] = j
                    cnt += 1
            for q in range(max(min(cnt, k), 1), k):
                out[i, c, q] = out[i, c, 0]
            if cnt == 0:  # (a constant distance has minima everywhere: never happens)
                out[i, c, :] = lo
    return out


@njit(**HELPER)
def _bracket(  # type: ignore[no-untyped-def]
    ts: FloatArray,
    pts: FloatArray,
    slopes: FloatArray,
    lo_s: int,
    hi_s: int,
    jc: int,
    xi: FloatArray,
    foot: FloatArray,
    g3: FloatArray,
    d3: FloatArray,
    j3: np.ndarray,
):
    """The three-sample window of candidate sample ``jc`` (kept in ``lo_s..hi_s``) for
    point ``xi``: ``g = (C - x) . C'`` and the squared distance at its samples (tabulated
    points and slopes: no curve evaluation); the half with the sign change of ``g``. Returns
    the nearest sample's parameter (its point into ``foot``), the half ``[ta, tb]``, the
    start of the refinement (:func:`_iqi_start`), whether ``ga < 0 < gb`` (a minimum
    inside: to refine), and the window's first and last sample."""
    for r in range(3):
        j3[r] = min(max(jc + r - 1, lo_s), hi_s)
        g = 0.0
        dd = 0.0
        for d in range(xi.size):
            e = pts[j3[r], d] - xi[d]
            g += e * slopes[j3[r], d]
            dd += e * e
        g3[r], d3[r] = g, dd
    jb = j3[0]
    db = d3[0]
    for r in range(1, 3):
        if d3[r] < db:
            jb, db = j3[r], d3[r]
    for d in range(xi.size):
        foot[d] = pts[jb, d]
    left = g3[1] >= 0.0
    ia = j3[0] if left else j3[1]
    ga = g3[0] if left else g3[1]
    gb = g3[1] if left else g3[2]
    ta, tb = ts[ia], ts[min(ia + 1, hi_s)]
    interior = ga < 0.0 and gb > 0.0
    s0 = ts[jb]
    if interior:
        s0 = _iqi_start(ts[j3[0]], ts[j3[1]], ts[j3[2]], g3, ta, tb, ga, gb)
    return ts[jb], ta, tb, s0, interior, j3[0], j3[2]


@njit(**KERNEL)
def bracket_rows(  # type: ignore[no-untyped-def]
    ts: FloatArray, pts: FloatArray, slopes: FloatArray, x: FloatArray, cand: np.ndarray
):
    """:func:`_bracket` of the candidate samples ``cand`` (n,) of points ``x`` (n, dim) on
    one curve's search samples (a curve without a polynomial table, whose refinement
    evaluates it from Python): nearest-sample parameters (n,) and points (n, dim), halves
    ``ta``, ``tb`` (n,), starts (n,), whether to refine (n,), windows' first and last
    sample parameters (n,)."""
    n, dim = x.shape
    lo_s, hi_s = np.int64(0), ts.size - 1  # (a literal 0 would compile _bracket twice)
    t = np.empty(n)
    foot = np.empty((n, dim))
    ta = np.empty(n)
    tb = np.empty(n)
    s0 = np.empty(n)
    inside = np.empty(n, dtype=np.bool_)
    w_lo = np.empty(n)
    w_hi = np.empty(n)
    g3 = np.empty(3)
    d3 = np.empty(3)
    j3 = np.empty(3, dtype=np.int64)
    for i in range(n):
        t[i], ta[i], tb[i], s0[i], inside[i], j0, j2 = _bracket(
            ts, pts, slopes, lo_s, hi_s, cand[i], x[i], foot[i], g3, d3, j3
        )
        w_lo[i], w_hi[i] = ts[j0], ts[j2]
    return t, foot, ta, tb, s0, inside, w_lo, w_hi


@njit(**KERNEL)
def closest_search(  # type: ignore[no-untyped-def]
    ts: FloatArray,
    pts: FloatArray,
    slopes: FloatArray,
    centre: FloatArray,
    ct: FloatArray,
    pp: FloatArray,
    bounds: np.ndarray,
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    breaks: FloatArray,
    break_bounds: np.ndarray,
    x: FloatArray,
    k: int,
):
    """Global closest points of ``x`` (n, dim) on each curve of a polynomial table
    (:func:`jet_rows`; curve ``j`` at offset ``2 j``): parameters (n, curves), foot points
    (n, curves, dim) and distances (n, curves).

    The search samples of curve ``j`` are ``ts``, ``pts``, ``slopes`` (local parameters,
    points, ``C'``) on ``bounds[j]:bounds[j + 1]``, ``ct`` (dim, m) and ``pp`` the points
    centred on ``centre`` and their squared norms; its C0 corners
    ``breaks[break_bounds[j]:break_bounds[j + 1]]``. Per point and curve: the ``k`` best
    local minima of the sampled distance (:func:`candidates`), each refined in the
    sign-change half of its three-sample window (inverse quadratic start, :func:`_refine`;
    no sign change: its nearest sample), a nearer corner in the window taken, the nearest
    candidate kept (the first on ties)."""
    n, dim = x.shape
    nc = bounds.size - 1
    xc = np.empty((n, dim))  # (x - centre, as a loop: an array expression compiles slowly)
    for i in range(n):
        for d in range(dim):
            xc[i, d] = x[i, d] - centre[d]
    cand = candidates(ct, pp, bounds, xc, k)
    t_out = np.empty((n, nc))
    foot_out = np.empty((n, nc, dim))
    dist_out = np.empty((n, nc))
    w = np.empty((3, dim))
    foot = np.empty(dim)
    g3 = np.empty(3)
    d3 = np.empty(3)
    j3 = np.empty(3, dtype=np.int64)
    for i in range(n):
        xi = x[i]
        for c in range(nc):
            lo_s, hi_s = bounds[c], bounds[c + 1] - 1
            off = 2.0 * c
            br = breaks[break_bounds[c] : break_bounds[c + 1]]
            best_d = np.inf
            for q in range(k):
                t, ta, tb, s0, interior, j0, j2 = _bracket(
                    ts, pts, slopes, lo_s, hi_s, cand[i, c, q], xi, foot, g3, d3, j3
                )
                if interior:
                    t = _refine(inner, starts, rows, off, xi, ta, tb, s0, w, foot)
                t = _corner(inner, starts, rows, off, br, xi, ts[j0], ts[j2], t, foot, w)
                dd = 0.0
                for d in range(dim):
                    dd += (foot[d] - xi[d]) ** 2
                dist = np.sqrt(dd)
                if dist < best_d or q == 0:
                    best_d = dist
                    t_out[i, c] = t
                    dist_out[i, c] = dist
                    for d in range(dim):
                        foot_out[i, c, d] = foot[d]
    return t_out, foot_out, dist_out


@njit(**HELPER)
def _iqi_start(
    t0: float, t1: float, t2: float, g3: FloatArray, ta: float, tb: float, ga: float, gb: float
) -> float:
    """Start for the root of ``g`` in ``[ta, tb]``: inverse quadratic interpolation through
    the three samples, regula falsi where that leaves the bracket or is undefined."""
    g0, g1, g2 = g3[0], g3[1], g3[2]
    den0 = (g0 - g1) * (g0 - g2)
    den1 = (g1 - g0) * (g1 - g2)
    den2 = (g2 - g0) * (g2 - g1)
    falsi = ta + (tb - ta) * ga / (ga - gb)
    if den0 == 0.0 or den1 == 0.0 or den2 == 0.0:
        return falsi
    s = t0 * g1 * g2 / den0 + t1 * g0 * g2 / den1 + t2 * g0 * g1 / den2
    if s > ta and s < tb:
        return s
    return falsi


@njit(**KERNEL)
def closest_bracketed(  # type: ignore[no-untyped-def]
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    curve: np.ndarray,
    x: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    start: FloatArray,
):
    """The nearest point to ``x[i]`` (n, dim) on curve ``curve[i]`` (n,) of a polynomial
    table (:func:`jet_rows`) with parameter in ``[lo[i], hi[i]]`` (n,): parameters (n,) and
    foot points (n, dim). Where ``g = (C - x) . C'`` does not change sign from ``lo`` (< 0)
    to ``hi`` (> 0) the nearer end; else :func:`_refine` from ``start`` clamped to the
    bracket (regula falsi where ``start`` is NaN)."""
    n, dim = x.shape
    t_out = np.empty(n)
    foot_out = np.empty((n, dim))
    w = np.empty((3, dim))
    we = np.empty((3, dim))
    foot = np.empty(dim)
    for i in range(n):
        xi = x[i]
        off = 2.0 * curve[i]
        a, b = lo[i], hi[i]
        span = table_span(inner, a + off)
        table_jet1(rows, span, a - starts[span], w)
        g_lo, _ = _g_dg(w, xi)
        span = table_span(inner, b + off)
        table_jet1(rows, span, b - starts[span], we)
        g_hi, _ = _g_dg(we, xi)
        if g_lo < 0.0 and g_hi > 0.0:
            s = start[i]
            if s != s:
                s = a + (b - a) * g_lo / (g_lo - g_hi)
            else:
                s = min(max(s, a), b)
            t_out[i] = _refine(inner, starts, rows, off, xi, a, b, s, w, foot)
            for d in range(dim):
                foot_out[i, d] = foot[d]
            continue
        d_lo = 0.0
        d_hi = 0.0
        for d in range(dim):
            d_lo += (w[0, d] - xi[d]) ** 2
            d_hi += (we[0, d] - xi[d]) ** 2
        at_lo = d_lo <= d_hi
        t_out[i] = a if at_lo else b
        for d in range(dim):
            foot_out[i, d] = w[0, d] if at_lo else we[0, d]
    return t_out, foot_out


# ---- certification -----------------------------------------------------------------------
@njit(**KERNEL)
def certify_rows(  # type: ignore[no-untyped-def]
    ts: FloatArray,
    ct: FloatArray,
    pp: FloatArray,
    x: FloatArray,
    t: FloatArray,
    distance: FloatArray,
    half: float,
    quarter: float,
    sag: float,
    slack: float,
):
    """:func:`medax.geometry.curve.certify_closest` per point: ``x`` (n, dim) centred as
    the samples (``ct`` (dim, m), ``pp`` (m,) as in :func:`candidates`; parameters ``ts``
    (m,), evenly spaced), local feet ``t`` (n,) at ``distance`` (n,). The nearest local
    minimum of the sample distance that is not within 1.5 spacings of the foot (among the
    5 samples around it) at ``s``; certified (True) where the larger of ``s - half`` and
    ``sqrt(s^2 - quarter) - sag`` is at least ``distance - slack``."""
    n, dim = x.shape
    m = ct.shape[1]
    dt = ts[1] - ts[0]
    ok = np.empty(n, dtype=np.bool_)
    d2 = np.empty(m)
    for i in range(n):
        xx = 0.0
        for d in range(dim):
            xx += x[i, d] * x[i, d]
        _table_d2(ct, pp, x, i, d2)
        f = int(np.floor(t[i] / dt))
        other = np.inf
        for j in range(m):
            v = d2[j]
            if j > 0 and not v <= d2[j - 1]:
                continue
            if j < m - 1 and not v <= d2[j + 1]:
                continue
            if f - 2 <= j <= f + 2 and abs(ts[j] - t[i]) <= 1.5 * dt:
                continue  # the foot's own minimum
            if v < other:
                other = v
        other = max(other + xx, 0.0)  # the nearest other sample, squared
        b1 = np.sqrt(other) - half
        b2 = np.sqrt(max(other - quarter, 0.0)) - sag
        bound = b1 if b2 != b2 or b1 >= b2 else b2  # (fmax: inf - inf is no bound)
        ok[i] = bound >= distance[i] - slack
    return ok


# ---- the first-run compile message --------------------------------------------------------
_COMPILED = (
    jet_rows,
    newton_rows,
    candidates,
    bracket_rows,
    closest_search,
    closest_bracketed,
    track_table,
    track_step_rows,
    certify_rows,
    newton_table,
    crossing,
    span_basis_rows,
    heights_newton,
    grid_kernel.winslow_sweeps,
)
_announced = False


def announce_compile() -> None:
    """Log (INFO, once per process) that the kernels are being compiled where numba's cache
    holds no index for one of them (the first run after an install, or a changed source)."""
    global _announced
    if _announced:
        return
    _announced = True
    if _cached(_COMPILED):
        return
    log.info("compiling numeric kernels (first run only)...")
    t0 = time.perf_counter()
    warm_up()
    log.info("numeric kernels compiled in %.1f s", time.perf_counter() - t0)


def _cached(kernels: tuple[Any, ...]) -> bool:
    """Whether numba's cache has an index file for every kernel (a numba internal; when it
    cannot be read the kernels count as cached: no message)."""
    try:
        return all(os.path.exists(kern._cache._cache_file._index_path) for kern in kernels)
    except AttributeError:  # pragma: no cover - another numba version's internals
        return True


def warm_up() -> None:
    """Compile (or load from the cache) every kernel for the argument types medax uses."""
    inner, starts = np.array([0.5]), np.array([0.0, 0.5])
    rows = np.ones((4, 2, 2))
    t = np.array([0.25])
    jet_rows(inner, starts, rows, t, np.zeros(0))
    x = np.zeros((1, 2))
    z = np.zeros(1)
    newton_rows(x, x, x, x, z.copy(), z.copy(), np.ones(1), False, np.empty((1, 2)))
    ts = np.linspace(0.0, 1.0, 5)
    pts = np.column_stack((ts, ts * ts))
    slopes = np.column_stack((np.ones(5), 2.0 * ts))
    closest_search(
        ts, pts, slopes, np.zeros(2), pts.T.copy(), np.einsum("ij,ij->i", pts, pts),
        np.array([0, 5]), inner, starts, rows, np.zeros(0), np.array([0, 0]), x, 2,
    )  # fmt: skip
    closest_bracketed(inner, starts, rows, np.zeros(1, dtype=np.int64), x, z, np.ones(1), z)
    for rational, dim in ((False, 2), (True, 1)):  # (the rows: 2 coordinates, or 1 and w)
        newton_table(inner, starts, rows, rational, x[:, :dim].copy(), z, np.ones(1), z, 60)
    cand = candidates(pts.T.copy(), np.einsum("ij,ij->i", pts, pts), np.array([0, 5]), x, 2)
    bracket_rows(ts, pts, slopes, x, cand[:, 0, 0].copy())
    xs = np.zeros((2, 1))
    track_table(inner, starts, rows, np.zeros(0), xs, t, np.ones(1), 8)
    track_step_rows(np.zeros((6, 1)), xs, t, np.ones(1), False)
    certify_rows(ts, pts.T.copy(), ts.copy(), x, t, t, 0.1, 0.01, 0.0, 0.0)
    crossing(pts, pts[::-1].copy(), 0.0, False)
    kn = np.array([0.0, 0.0, 1.0, 1.0])
    for coef in (np.zeros((3, 2, 2)), np.zeros((0, 2, 2))):  # power basis, Cox-de Boor
        span_basis_rows(kn, coef, 1, False, t)
        surf = (np.ones((2, 2, 4)), kn, coef, kn, coef, False)
        box = np.array([0.0, 1.0, 0.0, 1.0])
        heights_newton(*surf, np.eye(3), x, x, np.zeros(1, np.bool_), box, 0.1, 2)
    grid_kernel.warm_up()
