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


#: columns of the node state ``fs`` (n, WIDTH): per side ``k`` the accepted foot ``T + k``,
#: distance ``D + k``, foot point ``FOOT + 2k, FOOT + 2k + 1``, curvature term of its
#: tracking ``KAP + k`` (inf where not known) and Hessian bound ``HESS + k``; the equations
#: ``G + 0..5`` (``g_a, gax, gay, g_b, gbx, gby``); the step ``STEP + 0..5`` (``sx, sy``, its
#: uncapped length, the damping, the trial point); ``PEND + 0..19`` a trial point's feet in
#: the layout of ``T .. KAP + 3`` (and the caller's global starting feet); the residual
#: ``RES``
T, D, FOOT, KAP, HESS, G, STP, PEND, RES, WIDTH = 0, 4, 8, 16, 20, 24, 30, 36, 56, 57
_ALT = 5  # phase: tracking a node's second starts


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
    ist: np.ndarray,
    par: FloatArray,
    iters: int,
    first: bool,
) -> int:
    """The damped Newton of :func:`medax.mesh.free_field.newton_free` on the nodes ``xs``
    (n, 2; in place) not done or waiting: ratios ``r`` (2, n; side weights ``1 - r`` on
    sides 0 and 1, ``r`` on 2 and 3), feet ``tio`` (8, n: per side the starting foot, NaN:
    the caller's global one in ``fs``, then the second start, NaN: none; out: the feet and
    the distances), state ``fs`` and ``ist`` (n, 3: phase, iterations, backtracking step),
    ``par``: residual tolerance, tracking range, step cap (region units). The ``first``
    call evaluates every node where it is. Returns the number of nodes left waiting.

    One place tracks the feet (from the starts, the second starts or the accepted feet)
    and one evaluates the equations, for every purpose: the kernel compiles as one
    function (its helpers' calls cost time and compile time)."""
    tol, far, max_step = par[0], par[1], par[2]
    n = xs.shape[0]
    col, prim = np.full(20, np.nan), np.full(20, np.nan)
    pt, foot, jet = np.empty((2, 1)), np.empty((2, 1)), np.empty((3, 2))
    i0 = n - n  # (column 0 of pt: not a literal argument, which would compile _track1 again)
    ga = gax = gay = gb = gbx = gby = 0.0
    waiting = 0
    for i in range(n):
        f, si = fs[i], ist[i]
        phase = si[0]
        if first:
            phase, si[1] = RUN - 1, 0  # (-1: the start)
        while phase != DONE and phase != WAIT:
            if phase == RUN:
                if not f[RES] > tol or si[1] == iters:
                    phase = DONE
                    break
                si[1] += 1
                ga, gax, gay = f[G], f[G + 1], f[G + 2]
                gb, gbx, gby = f[G + 3], f[G + 4], f[G + 5]
                det = gax * gby - gay * gbx
                safe = det if abs(det) > 1e-300 else 1e-300
                sx = (gay * gb - gby * ga) / safe
                sy = (gbx * ga - gax * gb) / safe
                norm = math.sqrt(sx * sx + sy * sy)
                cap = min(1.0, max_step / max(norm, 1e-300))
                sx *= cap
                sy *= cap
                top = f[HESS]  # (np.maximum: NaN if any is)
                for k in range(1, 4):
                    hk = f[HESS + k]
                    top = top + hk if top != top or hk != hk else max(top, hk)
                half = 0.5 * norm * norm
                ra, rb = r[0, i], r[1, i]
                ha = (1.0 - ra) * f[HESS] + ra * f[HESS + 2]
                hb = (1.0 - rb) * f[HESS + 1] + rb * f[HESS + 3]
                bound = 2.0 * math.hypot(half * ha, half * hb)
                if cap == 1.0 and norm * top <= _LOCAL and bound <= 0.5 * tol:
                    # unevaluated (see newton_free): the feet stay, distances to them
                    x, y = xs[i, 0] + sx, xs[i, 1] + sy
                    xs[i, 0], xs[i, 1], f[RES] = x, y, bound
                    for k in range(4):
                        if sides[k, 0] == 2.0:
                            rx, ry = x - f[FOOT + 2 * k], y - f[FOOT + 2 * k + 1]
                            f[D + k] = math.sqrt(rx * rx + ry * ry)
                    continue
                f[STP], f[STP + 1], f[STP + 2], f[STP + 3] = sx, sy, norm, 1.0
                si[2] = 0
                phase = STEP
                continue
            # an evaluation: the node itself (its start, then its second starts), a
            # backtracking step's trial point, or a waiting one's with the caller's feet
            lam = f[STP + 3]
            if phase == RESUME:
                qx, qy = f[STP + 4], f[STP + 5]
                for c in range(20):
                    col[c] = f[PEND + c]
            else:
                if phase == STEP:
                    qx, qy = xs[i, 0] + lam * f[STP], xs[i, 1] + lam * f[STP + 1]
                else:
                    qx, qy = xs[i, 0], xs[i, 1]
                pt[0, 0], pt[1, 0] = qx, qy
                for k in range(4):
                    if sides[k, 0] != 2.0:
                        continue
                    t = f[T + k] if phase == STEP else tio[k if phase < RUN else 4 + k, i]
                    if t != t:
                        continue
                    t = min(max(t, 0.0), 1.0)
                    kap = 0.0
                    off, stol = sides[k, 1], sides[k, 2]
                    for it in range(_TRACK_ITERS):  # (the loop of track_table, one point)
                        span = table_span(inner, t + off)
                        table_jet1(rows, span, t - starts[span], jet)
                        t, kap, done = _track1(jet, pt, i0, t, stol, it == _TRACK_ITERS - 1, foot)
                        if done:
                            break
                    col[T + k], col[KAP + k] = t, kap
                    col[FOOT + 2 * k], col[FOOT + 2 * k + 1] = foot[0, 0], foot[1, 0]
                if phase < RUN:  # the start: global feet where none, a second start?
                    second = False
                    for k in range(4):
                        if sides[k, 0] != 2.0:
                            continue
                        if tio[k, i] != tio[k, i]:
                            col[T + k], col[KAP + k] = f[PEND + T + k], np.inf
                            col[FOOT + 2 * k] = f[PEND + FOOT + 2 * k]
                            col[FOOT + 2 * k + 1] = f[PEND + FOOT + 2 * k + 1]
                        elif tio[4 + k, i] == tio[4 + k, i]:
                            second = True
                    if second:
                        for c in range(20):
                            prim[c] = col[c]
                        phase = _ALT
                        continue
                elif phase == _ALT:  # the nearer of the two feet
                    for c in range(20):
                        t = col[c]
                        col[c] = prim[c]
                        prim[c] = t
                    for k in range(4):
                        if sides[k, 0] != 2.0 or tio[k, i] != tio[k, i]:
                            continue
                        if tio[4 + k, i] == tio[4 + k, i]:
                            ax, ay = qx - prim[FOOT + 2 * k], qy - prim[FOOT + 2 * k + 1]
                            bx, by = qx - col[FOOT + 2 * k], qy - col[FOOT + 2 * k + 1]
                            if ax * ax + ay * ay < bx * bx + by * by:
                                col[T + k], col[KAP + k] = prim[T + k], prim[KAP + k]
                                col[FOOT + 2 * k] = prim[FOOT + 2 * k]
                                col[FOOT + 2 * k + 1] = prim[FOOT + 2 * k + 1]
                elif lam * f[STP + 2] > far:
                    # feet are tracked for small moves only: a long step may cross the
                    # place where a foot jumps to another part of its side, which only a
                    # global query sees (the caller's)
                    for c in range(20):
                        f[PEND + c] = col[c]  # (NaN on untracked sides)
                    f[STP + 4], f[STP + 5] = qx, qy
                    phase = WAIT
                    break
            # the equations and the Hessian bounds at (qx, qy)
            for k in range(4):
                rk = r[k & 1, i]
                wk = 1.0 - rk if k < 2 else rk
                kind = sides[k, 0]
                if kind == 2.0:
                    rx, ry = qx - col[FOOT + 2 * k], qy - col[FOOT + 2 * k + 1]
                    d = math.sqrt(rx * rx + ry * ry)
                    inv = 1.0 / max(d, _TINY)
                    col[D + k], prim[HESS - 20 + k] = d, (col[KAP + k] + 1.0) * inv
                    wi = wk * inv
                    v, vx, vy = wk * d, rx * wi, ry * wi
                elif kind == 0.0:
                    v, vx, vy = segment_term(sides[k, 3:], qx, qy, wk)
                    prim[k] = wk / max(v, _TINY)
                else:
                    v, vx, vy = arc_term(sides[k, 3:], qx, qy, wk)
                    rho = math.hypot(qx - sides[k, 3], qy - sides[k, 4])
                    prim[k] = wk / max(v, _TINY) + 1.0 / max(rho, _TINY)
                if k == 0:
                    ga, gax, gay = v, vx, vy
                elif k == 1:
                    gb, gbx, gby = v, vx, vy
                elif k == 2:
                    ga, gax, gay = ga - v, gax - vx, gay - vy
                else:
                    gb, gbx, gby = gb - v, gbx - vx, gby - vy
            nres = math.sqrt(ga * ga + gb * gb)
            if phase == STEP or phase == RESUME:
                if not nres < f[RES] * (1.0 - 1e-4 * lam) + tol:
                    si[2] += 1
                    f[STP + 3] = 0.5 * lam
                    phase = STEP if si[2] < _BACKTRACKS else RUN
                    continue
            # accepted
            xs[i, 0], xs[i, 1], f[RES] = qx, qy, nres
            for c in range(16):
                f[c] = col[c]
            for k in range(4):
                f[KAP + k], f[HESS + k] = col[KAP + k], prim[k]
            f[G], f[G + 1], f[G + 2] = ga, gax, gay
            f[G + 3], f[G + 4], f[G + 5] = gb, gbx, gby
            phase = RUN
        si[0] = phase
        if phase == WAIT:
            waiting += 1
        else:  # done: the feet and distances out
            for k in range(4):
                if sides[k, 0] == 2.0:
                    tio[k, i], tio[4 + k, i] = f[T + k], f[D + k]
    return waiting


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
        np.empty((1, WIDTH)), np.empty((1, 3), dtype=np.int64), np.array([1e-9, 1e-3, 1.0]),
        2, True,
    )  # fmt: skip


__all__ = [
    "DONE",
    "RESUME",
    "RUN",
    "STEP",
    "WAIT",
    "WIDTH",
    "arc_term",
    "free_newton",
    "segment_term",
]
