"""Compiled (numba) node Newton of the ratio grid on planar regions with free-form sides
(:mod:`medax.mesh.free_field`): both distance-weighted equations, their gradients and the
bounds of the distances' Hessians at a node, from the closed-form terms of segments and arcs
and from feet tracked on the stacked polynomial table of the other sides
(:func:`medax.geometry.track_kernel.track_point`); the damped Newton iteration of every node
with its step cap, unevaluated steps and backtracking, one node after the other.

A trial point farther than the tracking range from its node needs its tracked feet
certified global, and a global query where that is not shown: the node is then left
waiting (its tracked feet in the pending rows) for the caller to do that and call again;
it resumes at that trial point. Announced and warmed up with the others in
:mod:`medax.geometry.kernels`.

Layout of the per-node arrays (n nodes, one row each): ``xs`` (n, 2) the nodes, ``w``
(n, 4) the side weights, ``g`` (n, 6) the equations ``g_a, gax, gay, g_b, gbx, gby``,
``res`` (n,) the residuals; ``fs`` (n, 24) the accepted state per side ``k``: foot
parameter ``k``, distance ``4 + k``, foot point ``8 + 2k, 9 + 2k``, curvature term of the
tracking ``16 + k`` (inf where not known), the bound of the distance's Hessian ``20 + k``
(NaN on untracked sides but the last); ``pend`` (n, 20) the same (without the bounds) for
a trial point's feet, and the caller's starting feet for the first call (a global foot
``k`` with its point where the start is NaN; a second start at ``4 + k``, NaN: none);
``st`` (n, 6) the step ``sx, sy``, its uncapped length, the damping ``lam`` and the trial
point; ``ist`` (n, 3) the phase (:data:`RUN` ...), the iterations done and the
backtracking step (-1 before the first call). ``sides`` (4, 13) per side: kind (0
segment, 1 arc, 2 tracked), table offset, tracking step tolerance and the 10 constants of
its term (:func:`medax.mesh.ratio_field._segment_consts`, ``_arc_consts``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray
from medax.geometry.table_kernel import table_jet1, table_span
from medax.geometry.track_kernel import _track1

#: node phases: at the start of an iteration, backtracking, waiting for the caller's
#: certification of a trial point's feet, resuming with them, converged (or out of steps)
RUN, STEP, WAIT, RESUME, DONE = 0, 1, 2, 3, 4
_TINY = float(np.finfo(np.float64).tiny)
_BACKTRACKS = 12
_LOCAL = 0.05  # a step unevaluated only if at most this times each distance's curvature radius
_TRACK_ITERS = 8  # tracking steps per foot (as :func:`medax.geometry.curve.track_rows`)


@njit(**HELPER)
def _nmax(a: float, b: float) -> float:
    """``np.maximum`` of two numbers (NaN if either is)."""
    if a != a or b != b:
        return a + b
    return a if a >= b else b


@njit(**HELPER)
def segment_term(c: FloatArray, x: float, y: float, w: float) -> tuple[float, float, float]:
    """``w d`` and ``w u`` (``u`` the unit vector from the foot, 0 on the segment) of point
    ``(x, y)`` for a segment with constants ``c`` (``ax, ay, ex, ey, ee``)."""
    dx, dy = x - c[0], y - c[1]
    t = dx * c[2]
    t += dy * c[3]
    if c[4] > 0.0:
        t *= 1.0 / c[4]
        t = min(max(t, 0.0), 1.0)
    else:
        t = 0.0
    rx = dx - t * c[2]
    ry = dy - t * c[3]
    d = math.sqrt(rx * rx + ry * ry)
    f = w / max(d, _TINY)
    return w * d, rx * f, ry * f


@njit(**HELPER)
def arc_term(c: FloatArray, x: float, y: float, w: float) -> tuple[float, float, float]:
    """``w d`` and ``w u`` of point ``(x, y)`` for an arc with constants ``c`` (``cx, cy, R,
    mx, my, cos h, x0, y0, x1, y1``): radial inside its angle, the nearer end outside it or
    at the centre."""
    vx, vy = x - c[0], y - c[1]
    rho = math.sqrt(vx * vx + vy * vy)
    dot = vx * c[3]
    dot += vy * c[4]
    outside = dot < rho * c[5] or rho == 0.0
    dr = rho - c[2]
    f = math.copysign(w, dr) / max(rho, _TINY)
    vx *= f
    vy *= f
    dr = abs(dr) * w
    if outside:
        r0x, r0y, r1x, r1y = x - c[6], y - c[7], x - c[8], y - c[9]
        d0 = math.sqrt(r0x * r0x + r0y * r0y)
        d1 = math.sqrt(r1x * r1x + r1y * r1y)
        first = d0 <= d1
        do = d0 if first else d1
        dr = w * do
        fo = w / max(do, _TINY)
        vx = (r0x if first else r1x) * fo
        vy = (r0y if first else r1y) * fo
    return dr, vx, vy


@njit(**HELPER)
def _field(
    sides: FloatArray,
    r: FloatArray,
    i: int,
    x: float,
    y: float,
    fs: FloatArray,
    g: FloatArray,
    h: FloatArray,
) -> None:
    """Both equations ``g`` (6,: ``g_a, gax, gay, g_b, gbx, gby``) and the Hessian bounds
    ``h`` (4,) of node ``i`` (ratios ``r[:, i]``: weights ``1 - r`` on sides 0, 1, ``r`` on 2, 3) at ``(x, y)``; on tracked sides from the
    feet in ``fs`` (20,: a column of the state layout), whose distances are set here."""
    for k in range(4):
        rk = r[k & 1, i]
        wk = 1.0 - rk if k < 2 else rk
        kind = sides[k, 0]
        if kind == 2.0:
            rx, ry = x - fs[8 + 2 * k], y - fs[9 + 2 * k]
            d = math.sqrt(rx * rx + ry * ry)
            inv = 1.0 / max(d, _TINY)
            h[k] = (fs[16 + k] + 1.0) * inv
            f = wk * inv
            v, vx, vy = wk * d, rx * f, ry * f
            fs[4 + k] = d
        elif kind == 0.0:
            v, vx, vy = segment_term(sides[k, 3:], x, y, wk)
            h[k] = wk / max(v, _TINY)
        else:
            v, vx, vy = arc_term(sides[k, 3:], x, y, wk)
            rho = math.hypot(x - sides[k, 3], y - sides[k, 4])
            h[k] = wk / max(v, _TINY) + 1.0 / max(rho, _TINY)
        if k < 2:
            g[3 * k], g[3 * k + 1], g[3 * k + 2] = v, vx, vy
        else:
            g[3 * k - 6] -= v
            g[3 * k - 5] -= vx
            g[3 * k - 4] -= vy


@njit(**HELPER)
def _track(
    sides: FloatArray,
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    x: float,
    y: float,
    t0: FloatArray,
    fs: FloatArray,
    pt: FloatArray,
    foot: FloatArray,
    jet: FloatArray,
) -> None:
    """Feet of ``(x, y)`` on the tracked sides from the feet ``t0`` (20,: state layout) into
    ``fs`` (foot, foot point, curvature term); scratch ``pt``, ``foot`` (2, 1), ``jet``."""
    pt[0, 0], pt[1, 0] = x, y
    for k in range(4):
        if sides[k, 0] != 2.0 or t0[k] != t0[k]:
            continue
        t = min(max(t0[k], 0.0), 1.0)
        kap = 0.0
        off, tol = sides[k, 1], sides[k, 2]
        for it in range(_TRACK_ITERS):  # (the loop of track_table, on one point)
            span = table_span(inner, t + off)
            table_jet1(rows, span, t - starts[span], jet)
            t, kap, done = _track1(jet, pt, 0, t, tol, it == _TRACK_ITERS - 1, foot)
            if done:
                break
        fs[k], fs[16 + k] = t, kap
        fs[8 + 2 * k], fs[9 + 2 * k] = foot[0, 0], foot[1, 0]


@njit(**HELPER)
def _start(
    sides: FloatArray,
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    x: float,
    y: float,
    tio: FloatArray,
    i: int,
    given: FloatArray,
    fs: FloatArray,
    alt: FloatArray,
    pt: FloatArray,
    foot: FloatArray,
    jet: FloatArray,
) -> None:
    """The starting feet of node ``i`` at ``(x, y)`` into ``fs``: on each tracked side
    ``k`` tracked from ``tio[k, i]``, and also from a second start ``tio[4 + k, i]`` where
    that is one (not NaN), the nearer kept (scratch ``alt``); where ``tio[k, i]`` is NaN
    the caller's global foot ``given[k]`` (foot point ``given[8 + 2k:10 + 2k]``)."""
    second = False
    for k in range(4):
        alt[k] = tio[k, i]
    _track(sides, inner, starts, rows, x, y, alt, fs, pt, foot, jet)
    for k in range(4):
        alt[k] = tio[4 + k, i] if sides[k, 0] == 2.0 and tio[k, i] == tio[k, i] else np.nan
        second = second or alt[k] == alt[k]
    if second:
        _track(sides, inner, starts, rows, x, y, alt, alt, pt, foot, jet)
    for k in range(4):
        if sides[k, 0] != 2.0:
            continue
        if tio[k, i] != tio[k, i]:
            fs[k], fs[16 + k] = given[k], np.inf
            fs[8 + 2 * k], fs[9 + 2 * k] = given[8 + 2 * k], given[9 + 2 * k]
        elif alt[k] == alt[k]:
            ax, ay = x - alt[8 + 2 * k], y - alt[9 + 2 * k]
            bx, by = x - fs[8 + 2 * k], y - fs[9 + 2 * k]
            if ax * ax + ay * ay < bx * bx + by * by:
                fs[k], fs[16 + k] = alt[k], alt[16 + k]
                fs[8 + 2 * k], fs[9 + 2 * k] = alt[8 + 2 * k], alt[9 + 2 * k]


@njit(**KERNEL)
def free_newton(  # type: ignore[no-untyped-def]
    sides: FloatArray,
    inner: FloatArray,
    starts: FloatArray,
    rows: FloatArray,
    xs: FloatArray,
    r: FloatArray,
    tio: FloatArray,
    fs: FloatArray,
    pend: FloatArray,
    g: FloatArray,
    res: FloatArray,
    st: FloatArray,
    ist: np.ndarray,
    par: FloatArray,
    iters: int,
    first: bool,
) -> int:
    """The damped Newton of :func:`medax.mesh.free_field.newton_free` on every node not
    done or waiting (module layout; ``par``: residual tolerance, tracking range and step
    cap, region units), in place. The ``first`` call evaluates every node where it is,
    from its starting feet. Returns the number of nodes left waiting."""
    tol, far, max_step = par[0], par[1], par[2]
    n = xs.shape[0]
    col, alt = np.full(20, np.nan), np.full(20, np.nan)
    ng = np.empty(6)
    nh = np.empty(4)
    pt, foot, jet = np.empty((2, 1)), np.empty((2, 1)), np.empty((3, 2))
    waiting = 0
    for i in range(n):
        phase = RUN if first else ist[i, 0]
        if first:  # the node where it is
            ist[i, 1] = 0
            qx, qy = xs[i, 0], xs[i, 1]
            _start(sides, inner, starts, rows, qx, qy, tio, i, pend[i], col, alt, pt, foot, jet)
            _field(sides, r, i, qx, qy, col, ng, nh)
            nres = math.sqrt(ng[0] * ng[0] + ng[3] * ng[3])
            _accept(i, qx, qy, nres, col, ng, nh, xs, res, fs, g)
            phase = RUN
        elif phase == RESUME:  # the trial point with the caller's feet
            for k in range(4):
                if sides[k, 0] == 2.0:
                    for c in (k, 8 + 2 * k, 9 + 2 * k, 16 + k):
                        col[c] = pend[i, c]
            lam = st[i, 3]
            qx, qy = st[i, 4], st[i, 5]
            _field(sides, r, i, qx, qy, col, ng, nh)
            nres = math.sqrt(ng[0] * ng[0] + ng[3] * ng[3])
            if nres < res[i] * (1.0 - 1e-4 * lam) + tol:
                _accept(i, qx, qy, nres, col, ng, nh, xs, res, fs, g)
                phase = RUN
            else:
                ist[i, 2] += 1
                st[i, 3] = 0.5 * lam
                phase = STEP if ist[i, 2] < _BACKTRACKS else RUN
        while phase != DONE and phase != WAIT:
            if phase == RUN:
                if not res[i] > tol or ist[i, 1] == iters:
                    phase = DONE
                    break
                ist[i, 1] += 1
                phase = _step(sides, i, r, fs, g, xs, res, st, ist, tol, max_step)
                continue
            # backtracking on the residual from damping st[i, 3]
            lam = st[i, 3]
            qx, qy = xs[i, 0] + lam * st[i, 0], xs[i, 1] + lam * st[i, 1]
            _track(sides, inner, starts, rows, qx, qy, fs[i], col, pt, foot, jet)
            if lam * st[i, 2] > far:
                # feet are tracked for small moves only: a long step may cross the place
                # where a foot jumps to another part of its side, which only a global
                # query sees (the caller's)
                for c in range(20):
                    pend[i, c] = col[c]  # (NaN on untracked sides)
                st[i, 4], st[i, 5] = qx, qy
                phase = WAIT
                break
            _field(sides, r, i, qx, qy, col, ng, nh)
            nres = math.sqrt(ng[0] * ng[0] + ng[3] * ng[3])
            if nres < res[i] * (1.0 - 1e-4 * lam) + tol:
                _accept(i, qx, qy, nres, col, ng, nh, xs, res, fs, g)
                phase = RUN
                continue
            ist[i, 2] += 1
            st[i, 3] = 0.5 * lam
            if ist[i, 2] == _BACKTRACKS:  # no acceptable step: left as it was
                phase = RUN
        ist[i, 0] = phase
        if phase == WAIT:
            waiting += 1
        else:  # done: the feet and distances out
            for k in range(4):
                if sides[k, 0] == 2.0:
                    tio[k, i], tio[4 + k, i] = fs[i, k], fs[i, 4 + k]
    return waiting


@njit(**HELPER)
def _accept(
    i: int,
    x: float,
    y: float,
    r: float,
    col: FloatArray,
    ng: FloatArray,
    nh: FloatArray,
    xs: FloatArray,
    res: FloatArray,
    fs: FloatArray,
    g: FloatArray,
) -> None:
    """Node ``i`` moves to ``(x, y)`` with residual ``r``, feet ``col`` (20,), equations
    ``ng`` and Hessian bounds ``nh``."""
    xs[i, 0], xs[i, 1], res[i] = x, y, r
    for r_ in range(20):
        fs[i, r_] = col[r_]
    for k in range(4):
        fs[i, 20 + k] = nh[k]
    for r_ in range(6):
        g[i, r_] = ng[r_]


@njit(**HELPER)
def _step(
    sides: FloatArray,
    i: int,
    r: FloatArray,
    fs: FloatArray,
    g: FloatArray,
    xs: FloatArray,
    res: FloatArray,
    st: FloatArray,
    ist: np.ndarray,
    tol: float,
    max_step: float,
) -> int:
    """The Newton step of node ``i`` (capped at ``max_step``) into ``st``; taken without
    evaluation where its remainder is bounded below ``tol / 2`` (see
    :func:`medax.mesh.free_field.newton_free`): returns the next phase."""
    ga, gax, gay, gb, gbx, gby = g[i, 0], g[i, 1], g[i, 2], g[i, 3], g[i, 4], g[i, 5]
    det = gax * gby - gay * gbx
    safe = det if abs(det) > 1e-300 else 1e-300
    sx = (gay * gb - gby * ga) / safe
    sy = (gbx * ga - gax * gb) / safe
    norm = math.sqrt(sx * sx + sy * sy)
    cap = min(1.0, max_step / max(norm, 1e-300))
    sx *= cap
    sy *= cap
    h0, h1, h2, h3 = fs[i, 20], fs[i, 21], fs[i, 22], fs[i, 23]
    top = _nmax(_nmax(h0, h1), _nmax(h2, h3))
    half = 0.5 * norm * norm
    ra, rb = r[0, i], r[1, i]
    bound = 2.0 * math.hypot(half * ((1.0 - ra) * h0 + ra * h2), half * ((1.0 - rb) * h1 + rb * h3))
    if cap == 1.0 and norm * top <= _LOCAL and bound <= 0.5 * tol:
        # unevaluated: the feet stay (distances to their points, upper bounds)
        x, y = xs[i, 0] + sx, xs[i, 1] + sy
        xs[i, 0], xs[i, 1], res[i] = x, y, bound
        for k in range(4):
            fx, fy = fs[i, 8 + 2 * k], fs[i, 9 + 2 * k]
            if sides[k, 0] == 2.0:
                rx, ry = x - fx, y - fy
                fs[i, 4 + k] = math.sqrt(rx * rx + ry * ry)
        return RUN
    st[i, 0], st[i, 1], st[i, 2], st[i, 3] = sx, sy, norm, 1.0
    ist[i, 2] = 0
    return STEP


def warm_up() -> None:
    """Compile (or load from the cache) the kernel for the argument types medax uses."""
    sides = np.zeros((4, 13))
    sides[:, 0] = (2.0, 0.0, 1.0, 2.0)
    sides[:, 2] = 1e-6
    inner, starts = np.array([0.5]), np.array([0.0, 0.5])
    rows = np.ones((4, 2, 2))
    tio = np.full((8, 1), 0.5)
    tio[4:] = np.nan
    free_newton(
        sides, inner, starts, rows, np.zeros((1, 2)), np.full((2, 1), 0.5), tio,
        np.empty((1, 24)), np.empty((1, 20)), np.empty((1, 6)), np.empty(1), np.empty((1, 6)),
        np.empty((1, 3), dtype=np.int64), np.array([1e-9, 1e-3, 1.0]), 2, True,
    )  # fmt: skip


__all__ = ["DONE", "RESUME", "RUN", "STEP", "WAIT", "arc_term", "free_newton", "segment_term"]
