"""Untangling and quality stage of a structured quad grid (numpy only).

Applied after the medial grid where it has inverted or near-degenerate quads (scaled
Jacobian at most :data:`DEGENERATE_SJ`): only the nodes of the bad quads and a halo around
them move (2, 4, 8, 16 node rings, then the whole grid, until a result is valid), corners
stay, boundary nodes slide along their sides (their side parameter is the variable, so a
node stays on its side exactly; each kept within 0.4 of the way to its neighbours' start
parameters), every other node keeps its medial place.

Options (:data:`OPTIONS`), all run on each halo and the best result kept; measured on the
random regions in ``docs/benchmarks.md``:

- ``"knupp"``: Knupp's untangling objective ``sum_c max(0, beta_c - alpha_c)^2`` over the
  corner areas ``alpha_c`` (the cross product of a corner's two edges; ``beta_c`` a share
  :data:`UNTANGLE_BETA` of the product of their lengths at the start, lowered while the
  grid stays tangled), then, once every corner is positive, a barrier objective: the sum
  over corners of ``(|a|^2 + |b|^2) / (2 alpha_c)`` (the condition number of the corner's
  Jacobian, 1 for a square corner, infinite when flat), both by L-BFGS with a
  backtracking line search that refuses steps to a tangled mesh; boundary nodes sliding.
- ``"knupp-fixed"``: the same with the boundary nodes fixed.
- ``"winslow"``: the Winslow (elliptic) equations started from the grid, red-black sweeps
  on the free nodes with the boundary nodes fixed.

Every result is guarded: it replaces the grid only when it has no inverted quad and a
higher minimum scaled Jacobian than the grid had. :func:`smooth_grid` is the quality pass
that follows (the default; ``medax mesh --no-smooth`` leaves it out): Winslow on the whole
grid, compiled (:mod:`medax.geometry.grid_kernel`), kept only where it lowers neither the
minimum nor the 5th percentile of the scaled Jacobian nor the smallest angle.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from medax.errors import InputError
from medax.geometry import grid_kernel
from medax.geometry._types import FloatArray, IntArray
from medax.geometry.curve import Curve
from medax.mesh.grid import boundary_indices, structured_quads, transfinite_grid

log = logging.getLogger(__name__)

OPTIONS = ("knupp", "knupp-fixed", "winslow")
#: a quad whose scaled Jacobian is at most this is treated (inverted at 0, degenerate above)
DEGENERATE_SJ = 0.02
#: halo widths (node rings around the bad quads) tried in turn; the last is the whole grid
HALOS = (2, 4, 8, 16)
#: Knupp's untangling targets, in turn while the grid stays tangled (continuation):
#: beta_c = share x |a| |b| of the start
UNTANGLE_BETA = (0.2, 0.05, 0.0125)
#: the quality pass (:func:`smooth_grid`): Winslow sweeps at most and at least, node
#: updates at most (the sweeps' budget between those two), and the move (x the grid's
#: extent) below which they stop
SMOOTH_SWEEPS = 1000
SMOOTH_MIN_SWEEPS = 10
SMOOTH_WORK = 2**20
SMOOTH_TOL = 1e-6
#: its over-relaxation (Gauss-Seidel in row order; on 120 random-region grids 1.7 - 1.8
#: took the fewest sweeps to converge, 1.9 twice as many; on wavy at 128x128 within the
#: budget 1.8 reached p5 0.939, 1.5 0.921)
SMOOTH_OMEGA = 1.8
#: the points tried on the segment from the grid to Winslow's (shares of the way; on 200
#: random-region grids Winslow's grid alone passed the guard on 42, these on 108)
SMOOTH_SHARES = (1.0, 0.5, 0.25, 0.125)
_LBFGS_MEMORY = 8
_SLIDE_SHARE = 0.4
_UNTANGLE_ITERS = 400


@dataclass(frozen=True)
class Sliding:
    """Boundary nodes that slide: ``index`` (b,) node indices, ``side`` (b,) side numbers,
    ``t`` (b,) their parameters on ``curves[side]`` (the four side curves, in the grid's
    plane), each kept in ``[lo, hi]`` (b,): up to 0.4 of the way to its neighbours' start
    parameters, so that nodes keep their order and never meet or reach a corner."""

    index: IntArray
    side: IntArray
    t: FloatArray
    lo: FloatArray
    hi: FloatArray
    curves: Sequence[Curve]


def corner_terms(p: FloatArray, quads: IntArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per quad corner (m, 4): the edge vectors ``a`` to the next and ``b`` to the previous
    node (m, 4, 2) and the corner area ``cross(a, b)`` (m, 4), positive when CCW."""
    q = p[quads]
    a = np.roll(q, -1, axis=1) - q
    b = np.roll(q, 1, axis=1) - q
    return a, b, a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def scaled_jacobian(p: FloatArray, quads: IntArray) -> FloatArray:
    """Verdict's scaled Jacobian (m,) of planar quads: the smallest corner sine (0 when an
    edge has zero length)."""
    a, b, area = corner_terms(p, quads)
    la, lb = np.hypot(a[..., 0], a[..., 1]), np.hypot(b[..., 0], b[..., 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        s = area / (la * lb)
    return np.asarray(np.where(np.isfinite(s), s, 0.0).min(axis=1))


def _scatter(quads: IntArray, ga: FloatArray, gb: FloatArray, n: int) -> FloatArray:
    """Node gradients (n, 2) from the corner gradients with respect to ``a`` and ``b``
    (m, 4, 2): ``a = P_next - P``, ``b = P_prev - P``."""
    nxt, prv = np.roll(quads, -1, axis=1), np.roll(quads, 1, axis=1)
    g = np.empty((n, 2))
    for d in range(2):
        g[:, d] = (
            np.bincount(nxt.ravel(), ga[..., d].ravel(), n)
            + np.bincount(prv.ravel(), gb[..., d].ravel(), n)
            - np.bincount(quads.ravel(), (ga[..., d] + gb[..., d]).ravel(), n)
        )
    return g


def _untangle_objective(
    p: FloatArray, quads: IntArray, beta: FloatArray
) -> tuple[float, FloatArray]:
    """Knupp's ``sum max(0, beta - alpha)^2`` and its node gradient (n, 2)."""
    a, b, area = corner_terms(p, quads)
    short = np.maximum(beta - area, 0.0)
    w = -2.0 * short  # d f / d alpha
    # d alpha / d a = (b_y, -b_x), d alpha / d b = (-a_y, a_x)
    ga = w[..., None] * np.stack((b[..., 1], -b[..., 0]), axis=-1)
    gb = w[..., None] * np.stack((-a[..., 1], a[..., 0]), axis=-1)
    return float(np.sum(short * short)), _scatter(quads, ga, gb, len(p))


def _condition_objective(p: FloatArray, quads: IntArray) -> tuple[float, FloatArray]:
    """Sum over corners of ``(|a|^2 + |b|^2) / (2 alpha)`` and its node gradient (n, 2);
    ``inf`` when a corner is not positive (the barrier)."""
    a, b, area = corner_terms(p, quads)
    if not np.all(area > 0.0):
        return float("inf"), np.zeros_like(p)
    num = np.sum(a * a, axis=-1) + np.sum(b * b, axis=-1)
    k = 0.5 * num / area
    # d k / d a = a / area - k / area * (b_y, -b_x); likewise for b
    inv = 1.0 / area
    ga = inv[..., None] * (a - k[..., None] * np.stack((b[..., 1], -b[..., 0]), axis=-1))
    gb = inv[..., None] * (b - k[..., None] * np.stack((-a[..., 1], a[..., 0]), axis=-1))
    return float(np.sum(k)), _scatter(quads, ga, gb, len(p))


class _Variables:
    """The free nodes as one vector: (x, y) of the free interior nodes, then ``t`` of the
    free sliding boundary nodes."""

    def __init__(self, p: FloatArray, free: IntArray, sliding: Sliding | None, rim: IntArray):
        self.base = p.copy()
        if sliding is not None:
            on = np.isin(sliding.index, free)
            self.bidx, self.bside, t0 = sliding.index[on], sliding.side[on], sliding.t[on]
            self.lo, self.hi = sliding.lo[on], sliding.hi[on]
            self.curves: Sequence[Curve] = sliding.curves
        else:
            self.bidx, self.bside, t0 = np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
            self.lo, self.hi = np.zeros(0), np.zeros(0)
            self.curves = ()
        self.inner = np.setdiff1d(free, rim)
        self.z0 = np.concatenate((p[self.inner].ravel(), t0))

    def points(self, z: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Node positions (n, 2) for ``z``, and the side tangents (b, 2) at the boundary
        variables."""
        p = self.base.copy()
        k = 2 * len(self.inner)
        p[self.inner] = z[:k].reshape(-1, 2)
        tan = np.zeros((len(self.bidx), 2))
        t = np.clip(z[k:], self.lo, self.hi)
        for s in np.unique(self.bside):
            sel = self.bside == s
            p[self.bidx[sel]] = self.curves[s].evaluate(t[sel])
            tan[sel] = self.curves[s].derivative(t[sel])
        return p, tan

    def gradient(self, g: FloatArray, tan: FloatArray) -> FloatArray:
        """The objective's gradient in ``z`` from its node gradient (n, 2)."""
        gt = np.einsum("bd,bd->b", g[self.bidx], tan)
        return np.concatenate((g[self.inner].ravel(), gt))


def _lbfgs(
    f: Callable[[FloatArray], tuple[float, FloatArray]],
    z: FloatArray,
    iters: int,
    stop: Callable[[FloatArray], bool] | None = None,
) -> FloatArray:
    """L-BFGS on ``f`` (value, gradient) from ``z``, backtracking (Armijo) on every step and
    refusing steps where ``f`` is not finite; stops after ``iters`` steps, at a stationary
    point, or when ``stop(z)``."""
    fz, g = f(z)
    if not np.isfinite(fz):
        return z
    s_hist: list[FloatArray] = []
    y_hist: list[FloatArray] = []
    scale0 = 1e-2 * max(float(np.max(np.abs(z))), 1.0) / max(float(np.linalg.norm(g)), 1e-300)
    for _ in range(iters):
        if stop is not None and stop(z):
            break
        # two-loop recursion
        qv = g.copy()
        alphas = []
        for s, y in zip(reversed(s_hist), reversed(y_hist), strict=True):
            rho = 1.0 / float(y @ s)
            al = rho * float(s @ qv)
            alphas.append((rho, al))
            qv -= al * y
        if s_hist:
            gamma = float(s_hist[-1] @ y_hist[-1]) / float(y_hist[-1] @ y_hist[-1])
        else:
            gamma = scale0
        r = gamma * qv
        for (s, y), (rho, al) in zip(zip(s_hist, y_hist, strict=True), reversed(alphas),
                                     strict=True):  # fmt: skip
            be = rho * float(y @ r)
            r += (al - be) * s
        d = -r
        slope = float(g @ d)
        if slope >= 0.0:  # not a descent direction: restart from the gradient
            s_hist.clear()
            y_hist.clear()
            d = -scale0 * g
            slope = float(g @ d)
            if slope >= 0.0:
                break
        step = 1.0
        for _ in range(40):
            zn = z + step * d
            fn, gn = f(zn)
            if np.isfinite(fn) and fn <= fz + 1e-4 * step * slope:
                break
            step *= 0.5
        else:
            break
        s, y = zn - z, gn - g
        if float(s @ y) > 1e-300:
            s_hist.append(s)
            y_hist.append(y)
            if len(s_hist) > _LBFGS_MEMORY:
                s_hist.pop(0)
                y_hist.pop(0)
        done = fz - fn <= 1e-12 * max(abs(fz), 1e-300)
        z, fz, g = zn, fn, gn
        if done:
            break
    return z


def knupp(p: FloatArray, n1: int, n2: int, free: IntArray, sliding: Sliding | None) -> FloatArray:
    """Knupp's untangling, then the condition-number barrier optimisation, on the ``free``
    node indices of the ``(n2 + 1) x (n1 + 1)`` grid (the others fixed; boundary nodes
    among ``free`` slide on their sides when in ``sliding``, else stay); returns the new
    nodes (n, 2)."""
    quads = structured_quads(n1, n2)
    var = _Variables(p, free, sliding, np.concatenate(boundary_indices(n1, n2)))
    cells = quads[np.any(np.isin(quads, free), axis=1)]
    a, b, area = corner_terms(p, cells)
    size = np.hypot(a[..., 0], a[..., 1]) * np.hypot(b[..., 0], b[..., 1])

    def valid(z: FloatArray) -> bool:
        return bool(np.all(corner_terms(var.points(z)[0], cells)[2] > 0.0))

    z = var.z0
    # continuation: a target that stalls in a local minimum is lowered and the run goes on
    for share in UNTANGLE_BETA:
        if valid(z):
            break
        beta = share * size

        def untangle(z: FloatArray, beta: FloatArray = beta) -> tuple[float, FloatArray]:
            q, tan = var.points(z)
            val, g = _untangle_objective(q, cells, beta)
            return val, var.gradient(g, tan)

        z = _lbfgs(untangle, z, _UNTANGLE_ITERS, stop=valid)

    def condition(z: FloatArray) -> tuple[float, FloatArray]:
        q, tan = var.points(z)
        val, g = _condition_objective(q, cells)
        return val, var.gradient(g, tan)

    if valid(z):
        z = _lbfgs(condition, z, 300)
    return var.points(z)[0]


def winslow(
    p: FloatArray,
    n1: int,
    n2: int,
    free: IntArray,
    sweeps: int = 400,
    tol: float = 1e-10,
    omega: float = 1.0,
) -> FloatArray:
    """Winslow's equations ``g22 x_ss - 2 g12 x_st + g11 x_tt = 0`` on the ``free`` interior
    nodes of the ``(n2 + 1) x (n1 + 1)`` grid (boundary nodes fixed), started from ``p``
    (n, 2): red-black Gauss-Seidel sweeps over-relaxed by ``omega`` (1: none), until no
    node moves by more than ``tol`` x the grid's extent or after ``sweeps``; returns the new
    nodes (n, 2)."""
    g = p.reshape(n2 + 1, n1 + 1, 2).copy()
    mask = np.zeros((n2 + 1, n1 + 1), dtype=bool)
    mask.flat[free] = True
    mask[0, :] = mask[-1, :] = mask[:, 0] = mask[:, -1] = False
    m = mask[1:-1, 1:-1]
    if not m.any():
        return p.copy()
    jj, ii = np.indices(m.shape)
    colours = [(m & ((ii + jj) % 2 == c))[..., None] for c in (0, 1)]
    tol = tol * float(np.ptp(p, axis=0).max())
    inner = g[1:-1, 1:-1]
    for _ in range(sweeps):
        largest = 0.0
        for colour in colours:
            xs = 0.5 * (g[1:-1, 2:] - g[1:-1, :-2])
            xt = 0.5 * (g[2:, 1:-1] - g[:-2, 1:-1])
            a = np.sum(xt * xt, axis=-1)[..., None]
            c = np.sum(xs * xs, axis=-1)[..., None]
            b = np.sum(xs * xt, axis=-1)[..., None]
            cross = g[2:, 2:] - g[2:, :-2] - g[:-2, 2:] + g[:-2, :-2]
            new = (a * (g[1:-1, 2:] + g[1:-1, :-2]) + c * (g[2:, 1:-1] + g[:-2, 1:-1])
                   - 0.5 * b * cross) / np.maximum(2.0 * (a + c), 1e-300)  # fmt: skip
            move = np.where(colour, omega * (new - inner), 0.0)
            inner += move
            largest = max(largest, float(np.abs(move).max()))
        if largest < tol:
            break
    return g.reshape(-1, 2)


def _dilate(mask: np.ndarray, rings: int) -> np.ndarray:
    """``mask`` (rows, cols) grown by ``rings`` cells in index space (8-neighbourhood)."""
    out = mask.copy()
    for _ in range(rings):
        grown = out.copy()
        grown[1:] |= out[:-1]
        grown[:-1] |= out[1:]
        grown[:, 1:] |= grown[:, :-1].copy()
        grown[:, :-1] |= grown[:, 1:].copy()
        out = grown
    return out


def free_nodes(bad: np.ndarray, n1: int, n2: int, rings: int) -> IntArray:
    """Node indices within ``rings`` of the bad quads (``bad`` (n1 * n2,) bool), corners
    left out."""
    nodes = np.zeros((n2 + 1, n1 + 1), dtype=bool)
    b = bad.reshape(n2, n1)
    for dj in (0, 1):
        for di in (0, 1):
            nodes[dj : dj + n2, di : di + n1] |= b
    nodes = _dilate(nodes, rings)
    nodes[0, 0] = nodes[0, -1] = nodes[-1, 0] = nodes[-1, -1] = False
    return np.flatnonzero(nodes.ravel())


def sliding_nodes(p: FloatArray, n1: int, n2: int, curves: Sequence[Curve]) -> Sliding:
    """The boundary nodes but the corners as :class:`Sliding` on ``curves`` (the four
    sides), their parameters from the sides' closest points."""
    idx, side, t, lo, hi = [], [], [], [], []
    for k, nodes in enumerate(boundary_indices(n1, n2)):
        inner = nodes[1:-1]
        if inner.size:
            tk = curves[k].closest(p[inner]).t
            ends = np.concatenate(([0.0], tk, [1.0]))
            idx.append(inner)
            side.append(np.full(inner.size, k, dtype=np.int64))
            t.append(tk)
            lo.append(tk - _SLIDE_SHARE * (tk - ends[:-2]))
            hi.append(tk + _SLIDE_SHARE * (ends[2:] - tk))
    if not idx:
        e = np.zeros(0)
        return Sliding(np.zeros(0, np.int64), np.zeros(0, np.int64), e, e, e, curves)
    cat = np.concatenate
    return Sliding(cat(idx), cat(side), cat(t), cat(lo), cat(hi), curves)


def _score(p: FloatArray, quads: IntArray) -> tuple[float, float]:
    """(min, 5th percentile) of the scaled Jacobian."""
    sj = scaled_jacobian(p, quads)
    return float(sj.min()), float(np.percentile(sj, 5.0))


def _attempt(
    p: FloatArray,
    n1: int,
    n2: int,
    sliding: Sliding | None,
    options: Sequence[str],
    threshold: float,
) -> tuple[FloatArray, tuple[float, float], str]:
    """Each option on the bad quads of ``p`` and a halo growing until some result is valid:
    the best result (highest min, then 5th-percentile scaled Jacobian), its score and what
    made it (``p`` itself and ``""`` if none beats it)."""
    quads = structured_quads(n1, n2)
    sj = scaled_jacobian(p, quads)
    best, best_score, best_what = p, (float(sj.min()), float(np.percentile(sj, 5.0))), ""
    bad = sj <= threshold
    if not bad.any():
        return best, best_score, best_what
    for rings in (*HALOS, max(n1, n2)):
        free = free_nodes(bad, n1, n2, rings)
        for opt in options:
            if opt == "knupp":
                cand = knupp(p, n1, n2, free, sliding)
            elif opt == "knupp-fixed":
                cand = knupp(p, n1, n2, free, None)
            elif opt == "winslow":
                cand = winslow(p, n1, n2, free)
            else:
                raise InputError(f"unknown untangling option '{opt}' (known: {OPTIONS})")
            score = _score(cand, quads)
            log.debug("untangle %s, halo %d: min sj %.4f p5 %.4f", opt, rings, *score)
            if score[0] > 0.0 and score > best_score:
                best, best_score, best_what = cand, score, f"{opt}, halo {rings}"
        if best_score[0] > 0.0 or rings >= max(n1, n2):
            break
    return best, best_score, best_what


def untangle_grid(
    p: FloatArray,
    n1: int,
    n2: int,
    curves: Sequence[Curve] | None,
    options: Sequence[str] | None = None,
    threshold: float = DEGENERATE_SJ,
    coons: bool = True,
    info: dict | None = None,
) -> FloatArray:
    """The grid ``p`` ((n1 + 1) * (n2 + 1), 2), its quads with scaled Jacobian at most
    ``threshold`` (and a halo around them) untangled and improved by each of ``options``;
    boundary nodes slide along ``curves`` (the four sides, in ``p``'s plane; ``None``: they
    stay). When no result from ``p`` is valid and ``coons``, the same from the transfinite
    (Coons) patch of ``p``'s boundary nodes. Returns the best result (highest minimum, then
    5th-percentile scaled Jacobian) among those with no inverted quad and a higher minimum
    than ``p``'s, else ``p`` unchanged. ``info`` gets ``untangle`` (what was done).
    ``options`` default: :data:`OPTIONS` at the time of the call."""
    options = OPTIONS if options is None else options
    sj = grid_quality(p, n1, n2, angles=False)[0]  # (most grids need nothing more)
    if float(sj.min()) > threshold:
        return p
    start = (float(sj.min()), float(np.percentile(sj, 5.0)))
    record: dict = {"start_min_sj": start[0], "bad_quads": int(np.count_nonzero(sj <= threshold))}
    sliding = sliding_nodes(p, n1, n2, curves) if curves is not None else None
    best, score, what = _attempt(p, n1, n2, sliding, options, threshold)
    if score[0] <= 0.0 and coons:
        patch = transfinite_grid(p, n1, n2)
        cand, cscore, cwhat = _attempt(patch, n1, n2, sliding, options, threshold)
        if cscore[0] > 0.0 and cscore > score:
            best, score, what = cand, cscore, f"{cwhat or 'as is'}, from the transfinite patch"
    if score > start and score[0] > 0.0:
        record.update(option=what, min_sj=score[0], p5_sj=score[1])
    else:
        best = p
        record["option"] = "none valid"
    if info is not None:
        info["untangle"] = record
    return best


def grid_quality(
    p: FloatArray, n1: int, n2: int, angles: bool = True
) -> tuple[FloatArray, FloatArray]:
    """Per quad of the grid ``p`` ((n1 + 1) * (n2 + 1), 2), row by row: the scaled Jacobian
    (n1 * n2,) (the smallest corner sine, 0 where an edge has zero length) and the largest
    corner cosine (n1 * n2,) (the smallest angle; 2 where a corner is not convex; empty
    unless ``angles``), from the grid's edge arrays (no gather: 4x faster than
    :func:`scaled_jacobian` at 512x512)."""
    g = p.reshape(n2 + 1, n1 + 1, 2)
    x, y = np.ascontiguousarray(g[..., 0]), np.ascontiguousarray(g[..., 1])
    hx, hy = x[:, 1:] - x[:, :-1], y[:, 1:] - y[:, :-1]  # edges along i (n2 + 1, n1)
    vx, vy = x[1:] - x[:-1], y[1:] - y[:-1]  # edges along j (n2, n1 + 1)
    lh, lv = np.hypot(hx, hy), np.hypot(vx, vy)
    # corner k of quad (i, j): its edges a (to the next corner) and b (to the previous) are,
    # up to one sign for both, corner 0 (h[j, i], v[j, i]), 1 (v[j, i+1], h[j, i]),
    # 2 (h[j+1, i], v[j, i+1]), 3 (v[j, i], h[j+1, i])
    lo, hi, left, right = np.s_[:-1], np.s_[1:], np.s_[:, :-1], np.s_[:, 1:]
    pairs = (
        (hx[lo], hy[lo], vx[left], vy[left], lh[lo], lv[left], 1.0),
        (vx[right], vy[right], hx[lo], hy[lo], lv[right], lh[lo], -1.0),
        (hx[hi], hy[hi], vx[right], vy[right], lh[hi], lv[right], 1.0),
        (vx[left], vy[left], hx[hi], hy[hi], lv[left], lh[hi], -1.0),
    )
    sj = np.full((n2, n1), np.inf)
    cmax = np.full((n2, n1), -np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for ax, ay, bx, by, la, lb, sign in pairs:
            d = la * lb
            if sign < 0.0:
                d = -d
            s = ax * by
            s -= ay * bx
            s /= d
            s[~np.isfinite(s)] = 0.0
            np.minimum(sj, s, out=sj)
            if angles:
                c = ax * bx
                c += ay * by
                c /= d
                c[~(s > 0.0)] = 2.0
                np.maximum(cmax, c, out=cmax)
    return sj.ravel(), cmax.ravel() if angles else np.zeros(0)


def _measures(p: FloatArray, n1: int, n2: int) -> tuple[float, float, float]:
    """(minimum, 5th percentile) of the scaled Jacobian and the smallest angle (degrees) of
    the grid ``p``."""
    sj, c = grid_quality(p, n1, n2)
    cm = float(c.max())
    angle = float(np.degrees(np.arccos(min(cm, 1.0)))) if cm <= 1.0 else 0.0
    return float(sj.min()), float(np.percentile(sj, 5.0)), angle


def _better(after: tuple[float, float, float], before: tuple[float, float, float]) -> bool:
    """No inverted quad, neither the minimum nor the 5th percentile of the scaled Jacobian
    nor the smallest angle lower than ``before``'s, and one of them higher by more than
    1e-9 (more than rounding)."""
    pairs = list(zip(after, before, strict=True))
    return after[0] > 0.0 and all(a >= b for a, b in pairs) and any(a > b + 1e-9 for a, b in pairs)


def smooth_grid(
    p: FloatArray,
    n1: int,
    n2: int,
    info: dict | None = None,
    tol: float = SMOOTH_TOL,
    exact: bool = False,
) -> FloatArray:
    """The quality pass on the grid ``p`` ((n1 + 1) * (n2 + 1), 2): Winslow's equations on
    every interior node (compiled Gauss-Seidel sweeps,
    :func:`medax.geometry.grid_kernel.winslow_sweeps`, over-relaxed by
    :data:`SMOOTH_OMEGA`, until no node moves by ``tol`` x the grid's extent; at most
    :data:`SMOOTH_WORK` node updates, between :data:`SMOOTH_MIN_SWEEPS` and
    :data:`SMOOTH_SWEEPS` sweeps); boundary nodes never move (the same floats). Of the
    points :data:`SMOOTH_SHARES` of the way from ``p`` to Winslow's grid, those that lower
    neither the minimum nor the 5th percentile of the scaled Jacobian nor the smallest
    angle and raise one of them are candidates; the one with the highest 5th percentile
    is returned, else ``p``.

    ``exact``: the grid is the exact polar grid and stays as it is. ``info`` gets
    ``smooth``: the minimum and 5th percentile scaled Jacobian and the smallest angle
    (degrees) before and after, the sweeps run, ``share`` (the point kept), ``stages``
    (``["winslow"]`` when kept, else empty) and ``kept``."""
    before = _measures(p, n1, n2)
    record: dict = {"min_sj": [before[0]], "p5_sj": [before[1]], "min_angle": [before[2]]}
    out = p
    stages: list[str] = []
    if exact:
        record["why"] = "exact polar grid"
    elif min(n1, n2) >= 2:
        move = tol * float(np.ptp(p, axis=0).max())
        interior = (n1 - 1) * (n2 - 1)
        cap = int(np.clip(SMOOTH_WORK // interior, SMOOTH_MIN_SWEEPS, SMOOTH_SWEEPS))
        g = p.reshape(n2 + 1, n1 + 1, 2).copy()
        with np.errstate(all="ignore"):  # (a diverging run is refused by the guard)
            record["sweeps"] = int(grid_kernel.winslow_sweeps(g, cap, SMOOTH_OMEGA, move))
        w = g.reshape(-1, 2)
        if np.all(np.isfinite(w)):
            # the best of the points of the segment from p to Winslow's grid that pass the
            # guard (Winslow's grid itself lowers the smallest angle or scaled Jacobian
            # somewhere on many distorted regions, a step towards it often does not)
            start = before
            for share in SMOOTH_SHARES:
                cand = w if share == 1.0 else p + share * (w - p)
                now = _measures(cand, n1, n2)
                if _better(now, start) and (not stages or now[1] > before[1]):
                    out, before, stages = cand, now, ["winslow"]
                    record["share"] = share
    else:
        record["why"] = "no interior node"
    for key, value in zip(("min_sj", "p5_sj", "min_angle"), before, strict=True):
        record[key].append(value)
    record["kept"] = bool(stages)
    record["stages"] = stages
    if info is not None:
        info["smooth"] = record
    return out


__all__ = [
    "DEGENERATE_SJ",
    "OPTIONS",
    "Sliding",
    "corner_terms",
    "free_nodes",
    "grid_quality",
    "knupp",
    "scaled_jacobian",
    "smooth_grid",
    "sliding_nodes",
    "untangle_grid",
    "winslow",
]
