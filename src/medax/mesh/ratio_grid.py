"""Nodes as crossings of constant-distance-ratio curves, solved directly (``method="ratio"``).

For the pair ``(S0, S2)`` the curve ``d0 / (d0 + d2) = j / n2`` is the one the tracer follows
with ``ratio = j / n2`` (``j = n2 / 2``: the medial axis); for ``(S1, S3)`` the curve
``d1 / (d1 + d3) = 1 - i / n1``. Node ``(i, j)`` is the crossing of the two, i.e. the root of

    g_a(p) = (1 - r_a) d0(p) - r_a d2(p) = 0,   g_b(p) = (1 - r_b) d1(p) - r_b d3(p) = 0,

with ``d_k`` the distance in space from ``E(p)`` to side ``k``. Boundary nodes are the curves'
end points: the root of one equation along the side (1-D, bracketed, vectorised), so they lie
on the sides exactly. Interior nodes are solved all at once by a damped 2-D Newton iteration
(gradient of a distance = the unit vector from its foot point), started from the transfinite
interpolation of the boundary nodes. This gives the crossings of the tracer's curves without
tracing and fitting them, to ``point_tol x diagonal``.
"""

from __future__ import annotations

import logging

import numpy as np

from medax import tolerances
from medax.errors import MeshError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve
from medax.geometry.region import Region
from medax.mesh.grid import boundary_indices

log = logging.getLogger(__name__)
_SCAN = 513  # samples per side when bracketing boundary nodes
_NEWTON_ITERS = 40


def _dist(region: Region, k: int, x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Distances (n,) from space points ``x`` (n, dim) to side ``k`` and unit vectors (n, dim)."""
    c = region.space_curve(k).closest(x)
    u = (x - c.foot) / np.maximum(c.distance, np.finfo(float).tiny)[:, None]
    return c.distance, u


def _g(
    region: Region, a: int, b: int, r: FloatArray, p: FloatArray, grad: bool = True
) -> tuple[FloatArray, FloatArray | None]:
    """``g = (1 - r) d_a - r d_b`` at parameter points ``p`` (n, 2), and its gradient (n, 2)."""
    x = region.embedding.evaluate(p)
    da, ua = _dist(region, a, x)
    db, ub = _dist(region, b, x)
    g = (1.0 - r) * da - r * db
    if not grad:
        return g, None
    gx = (1.0 - r)[:, None] * ua - r[:, None] * ub
    if not region.embedding.is_identity:
        gx = np.einsum("nij,ni->nj", region.embedding.jacobian(p), gx)
    return g, gx


def side_nodes(
    region: Region, side: int, a: int, b: int, ratios: FloatArray, tol: float
) -> FloatArray:
    """Parameters ``t`` (len(ratios),) on ``side`` where ``d_a / (d_a + d_b) = ratio``.

    Ratios 0 and 1 are the side's end points on ``a`` and on ``b``. Each ratio is bracketed
    on a scan of the side (the first sign change from the ``a`` end) and solved by the
    Illinois variant of regula falsi, all ratios at once, to ``|t1 - t0| <= 1e-15``.
    """
    curve: Curve = region.sides[side]
    r = np.asarray(ratios, dtype=np.float64)
    s = np.linspace(0.0, 1.0, _SCAN)
    x = region.embedding.evaluate(curve.evaluate(s))
    da, _ = _dist(region, a, x)
    db, _ = _dist(region, b, x)
    phi = da / np.maximum(da + db, np.finfo(float).tiny)
    # orient the scan so that phi runs from the a end (0) to the b end (1)
    a_at_start = phi[0] <= phi[-1]
    if not a_at_start:
        s, phi = s[::-1], phi[::-1]
    out = np.empty(r.size)
    inner = (r > 0.0) & (r < 1.0)
    out[r <= 0.0] = s[0]
    out[r >= 1.0] = s[-1]
    ri = r[inner]
    if ri.size == 0:
        return out
    above = phi[None, :] >= ri[:, None]  # (k, scan)
    first = np.argmax(above, axis=1)
    if np.any(~above.any(axis=1)) or np.any(first == 0):
        raise MeshError(
            f"region '{region.name}': a ratio curve of sides ({a}, {b}) does not meet side {side}"
        )
    if np.any(np.diff(phi) < -1e-12):
        log.warning("region '%s': distance ratio is not monotone along side %d", region.name, side)
    lo, hi = s[first - 1], s[first]

    def f(t: FloatArray) -> FloatArray:
        """``(1 - r) d_a - r d_b`` on the side: the sign of ``phi - r``."""
        xx = region.embedding.evaluate(curve.evaluate(t))
        d1, _ = _dist(region, a, xx)
        d2, _ = _dist(region, b, xx)
        return (1.0 - ri) * d1 - ri * d2

    flo, fhi = f(lo), f(hi)
    moved = np.zeros(ri.size, dtype=np.int8)  # -1: lo moved last, +1: hi moved last
    for _ in range(100):
        den = fhi - flo
        t = np.where(den != 0.0, lo - flo * (hi - lo) / np.where(den != 0.0, den, 1.0), lo)
        t = np.clip(t, np.minimum(lo, hi), np.maximum(lo, hi))
        ft = f(t)
        left = ft < 0.0
        # Illinois: halve the value kept at an end that stays put twice in a row
        fhi = np.where(left & (moved == -1), 0.5 * fhi, fhi)
        flo = np.where(~left & (moved == 1), 0.5 * flo, flo)
        lo, flo = np.where(left, t, lo), np.where(left, ft, flo)
        hi, fhi = np.where(left, hi, t), np.where(left, fhi, ft)
        moved = np.where(left, -1, 1).astype(np.int8)
        if np.all((np.abs(hi - lo) <= 4e-16) | (np.abs(ft) <= 1e-3 * tol)):
            break
    out[inner] = np.where(np.abs(flo) <= np.abs(fhi), lo, hi)
    return out


def ratio_grid(
    region: Region, n1: int, n2: int, point_tol: float = tolerances.POINT_TOL
) -> tuple[FloatArray, dict[str, float]]:
    """Parameter-plane nodes (``(n1 + 1) * (n2 + 1)``, 2) of the ratio grid; and counts."""
    diag = region.diagonal
    tol = point_tol * diag
    ri = 1.0 - np.arange(n1 + 1) / n1  # pair (S1, S3): ratio 1 on S3 (i = 0), 0 on S1
    rj = np.arange(n2 + 1) / n2  # pair (S0, S2): ratio 0 on S0 (j = 0), 1 on S2
    idx = boundary_indices(n1, n2)
    params = np.full(((n1 + 1) * (n2 + 1), 2), np.nan)
    # side k carries the end points of the curves of the other pair; in side direction
    specs = ((0, 1, 3, ri), (1, 0, 2, rj), (2, 1, 3, ri[::-1]), (3, 0, 2, rj[::-1]))
    for side, a, b, r in specs:
        t = side_nodes(region, side, a, b, r, tol)
        params[idx[side]] = region.sides[side].evaluate(t)
    params[idx[0][[0, -1]]] = region.corners[[0, 1]]
    params[idx[2][[0, -1]]] = region.corners[[2, 3]]
    grid = params.reshape(n2 + 1, n1 + 1, 2)
    # transfinite (Coons) interpolation of the boundary nodes as the initial guess
    u = (np.arange(n1 + 1) / n1)[None, :, None]
    v = (np.arange(n2 + 1) / n2)[:, None, None]
    bottom, top = grid[0][None], grid[-1][None]
    left, right = grid[:, 0][:, None], grid[:, -1][:, None]
    c00, c10, c11, c01 = grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]
    coons = (
        (1 - v) * bottom + v * top + (1 - u) * left + u * right
        - ((1 - u) * (1 - v) * c00 + u * (1 - v) * c10 + u * v * c11 + (1 - u) * v * c01)
    )  # fmt: skip
    inner = coons[1:-1, 1:-1].reshape(-1, 2)
    ra = np.broadcast_to(rj[1:-1, None], (n2 - 1, n1 - 1)).ravel()
    rb = np.broadcast_to(ri[None, 1:-1], (n2 - 1, n1 - 1)).ravel()
    solved, iters, resid = _newton(region, inner, ra, rb, 1e-3 * tol, diag)
    grid[1:-1, 1:-1] = solved.reshape(n2 - 1, n1 - 1, 2)
    return grid.reshape(-1, 2), {"newton_iterations": iters, "max_residual": resid / diag}


def _newton(
    region: Region, p: FloatArray, ra: FloatArray, rb: FloatArray, tol: float, diag: float
) -> tuple[FloatArray, int, float]:
    """Solve ``g_a = g_b = 0`` for all rows of ``p`` (n, 2) at once, damped by backtracking."""
    if p.shape[0] == 0:
        return p, 0, 0.0
    p = p.copy()
    active = np.arange(p.shape[0])
    ga, Ga = _g(region, 0, 2, ra, p)
    gb, Gb = _g(region, 1, 3, rb, p)
    assert Ga is not None and Gb is not None
    res = np.hypot(ga, gb)
    max_step = 0.1 * diag
    it = 0
    while it < _NEWTON_ITERS:
        active = active[res[active] > tol]
        if active.size == 0:
            break
        it += 1
        A, B = Ga[active], Gb[active]
        det = A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0]
        safe = np.where(np.abs(det) > 1e-300, det, 1e-300)
        fa, fb = ga[active], gb[active]
        step = (
            -np.column_stack((B[:, 1] * fa - A[:, 1] * fb, -B[:, 0] * fa + A[:, 0] * fb))
            / safe[:, None]
        )
        norm = np.linalg.norm(step, axis=1)
        step *= np.minimum(1.0, max_step / np.maximum(norm, 1e-300))[:, None]
        lam = np.ones(active.size)
        todo = np.arange(active.size)
        for _ in range(12):  # backtracking on the residual
            rows = active[todo]
            q = p[rows] + lam[todo, None] * step[todo]
            na, nGa = _g(region, 0, 2, ra[rows], q)
            nb, nGb = _g(region, 1, 3, rb[rows], q)
            nres = np.hypot(na, nb)
            ok = nres < res[rows] * (1.0 - 1e-4 * lam[todo]) + tol
            acc = rows[ok]
            p[acc], ga[acc], gb[acc], res[acc] = q[ok], na[ok], nb[ok], nres[ok]
            assert nGa is not None and nGb is not None
            Ga[acc], Gb[acc] = nGa[ok], nGb[ok]
            todo = todo[~ok]
            if todo.size == 0:
                break
            lam[todo] *= 0.5
    worst = float(res.max())
    if worst > 1e3 * tol or not np.isfinite(worst):
        bad = int(np.argmax(res))
        raise MeshError(
            f"region '{region.name}': ratio curves d0/(d0+d2)={ra[bad]:.4g} and "
            f"d1/(d1+d3)={rb[bad]:.4g} do not cross (Newton residual {worst / diag:.2e} x "
            "diagonal); the region is too distorted for a structured grid"
        )
    return p, it, worst
