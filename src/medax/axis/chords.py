"""All first axis points in one batch: the roots of the field along B1, B2 and chords.

The axis crosses every chord ``A1(s) -> A2(1 - s)`` of the region (the field is ``< 0`` on
``A1``, where ``d1 = 0``, and ``> 0`` on ``A2``), and it crosses ``B1`` and ``B2`` at its
end points. So the start point, the end point and one point per chord are each the root of
the field along a curve ``c(lam)``, ``lam in [0, 1]``, with a known sign change: all of them
are solved together by a safeguarded Newton iteration (the exact slope ``grad g . c'``, kept
inside each row's shrinking bracket), one field evaluation per step for all rows, instead
of the tracer's step-by-step predictor and corrector. The chords are spaced in ``s``
finer towards ``B1`` and ``B2`` (:func:`chord_spacing`); the refinement
(:mod:`medax.axis.refine`) then adds points where the fitted spline needs them.

Preconditions, checked (``None`` otherwise, and the caller traces): exactly one sign change
(or one exact zero) of the field along each of ``B1`` and ``B2`` on the scan, all rows
converged, and the points in order along the axis (each step from one point to the next
goes forward along the axis tangent at both of its ends); chord points outside the region
are dropped.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from medax.axis.field import DistanceField, FieldSample
from medax.axis.trace import tangent
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve

log = logging.getLogger(__name__)

#: samples of B1 and B2 scanned for the sign change of the field
SCAN = 33
#: Newton iterations at most (the rows converge quadratically: 5 - 8 are used)
MAX_ITER = 60
_SCAN_LAM = np.linspace(0.0, 1.0, SCAN)  # the scan's parameters on B1 and B2


@dataclass(frozen=True)
class ChordPoints:
    """Points (n, 2) on the axis from B1 to B2 (first on B1 at parameter ``t_start``, last
    on B2 at ``t_end``), their field sample and the number of Newton steps taken."""

    points: FloatArray
    sample: FieldSample
    t_start: float
    t_end: float
    iterations: int


def chord_points(
    field: DistanceField, b1: Curve, b2: Curve, n_chords: int, tol: float
) -> ChordPoints | None:
    """The start and end points on ``b1``/``b2`` and the crossings of ``n_chords`` chords
    (parameter plane), each with equidistance error ``2|g| <= 1e-3 tol`` (absolute), or
    ``None`` where a precondition of the module docstring fails."""
    region = field.region
    roles = field.roles
    # the scan: the sign change along each start / end side, evaluated together with the
    # chords' middles (their first Newton step)
    lam = _SCAN_LAM
    s = chord_spacing(n_chords)
    p0 = region.sides[roles.a1].evaluate(s)
    dp = region.sides[roles.a2].evaluate(1.0 - s) - p0
    first = field(np.concatenate((b1.evaluate(lam), b2.evaluate(lam), p0 + 0.5 * dp)))
    g_scan = first.g[: 2 * SCAN].reshape(2, SCAN)
    sg = np.sign(g_scan)
    change = (sg[:, :-1] * sg[:, 1:] < 0.0).tolist()
    zero = (sg == 0.0).tolist()
    # rows 0 and 1: B1 and B2 in their brackets; then the chords on [0, 1] (the field's
    # values at the chord ends are only known by sign: their middles first)
    n = n_chords + 2
    t = np.full(n, 0.5)
    a = np.zeros(n)
    b = np.ones(n)
    for row in (0, 1):
        ch = [i for i, c in enumerate(change[row]) if c]
        zs = [i for i, z in enumerate(zero[row]) if z]
        if len(ch) + len(zs) != 1:
            log.debug("%s: %d axis ends on a B side; tracing", region.name, len(ch))
            return None
        # an exact root on a sample: the bracket [lam_i, lam_i] (solved at once)
        i, w = (ch[0], 1) if ch else (zs[0], 0)
        la, lb = float(lam[i]), float(lam[i + w])
        ga, gb = float(g_scan[row, i]), float(g_scan[row, i + w])
        # regula falsi in the side's bracket, oriented so that g(a) < 0 < g(b) (B1 runs
        # from A2 to A1: g falls)
        t[row] = la + (lb - la) * ga / (ga - gb) if ga != gb else 0.5 * (la + lb)
        a[row], b[row] = (lb, la) if ga > gb else (la, lb)
    goal = 1e-3 * tol
    done = np.zeros(n, dtype=bool)
    pts = np.empty((n, 2))
    lam_at = np.empty(n)  # the parameter of each row's last evaluated point
    cols = np.empty((n, first.data.shape[1]))  # each row's last field sample
    it = 0
    for it in range(1, MAX_ITER + 1):  # noqa: B007
        if it == 1:  # the chords' middles, from the scan's evaluation (the ends next step)
            rows = np.arange(2, n)
            c, dc = p0 + 0.5 * dp, dp
            fs = first.take(np.arange(2 * SCAN, 2 * SCAN + n_chords))
        else:
            rows = (~done).nonzero()[0]
            if rows.size == 0:
                break
            c, dc = _rows(rows, t, b1, b2, p0, dp)
            fs = field(c)
        cols[rows] = fs.data
        pts[rows] = c
        tr = t[rows]
        lam_at[rows] = tr
        g = fs.g
        neg = g < 0.0
        ar = np.where(neg, tr, a[rows])
        br = np.where(neg, b[rows], tr)
        a[rows], b[rows] = ar, br
        slope = np.einsum("ij,ij->i", fs.grad, dc)
        # the Newton step (NaN where the slope is 0: bisected below)
        new = tr - np.divide(g, slope, out=np.full(g.size, np.nan), where=slope != 0.0)
        lo = np.minimum(ar, br)
        hi = np.maximum(ar, br)
        inside = (new > lo) & (new < hi)  # (False for NaN)
        new = np.where(inside, new, 0.5 * (lo + hi))
        t[rows] = new
        ok = (2.0 * np.abs(g) <= goal) | (hi - lo <= 4e-16)
        done[rows[ok]] = True
    if not done.all():
        log.debug("%s: chord roots did not converge; tracing", region.name)
        return None
    # the chord points in order along the axis: inside the region, each step forward
    keep = np.concatenate(([True, True], region.contains(pts[2:])))
    order = np.concatenate(([0], 2 + np.flatnonzero(keep[2:]), [1]))
    p = pts[order]
    sp = FieldSample(cols[order], first.dim)
    tt = tangent(sp)
    step = np.diff(p, axis=0)
    fwd = np.einsum("ij,ij->i", step, tt[:-1]) > 0.0
    fwd &= np.einsum("ij,ij->i", step, tt[1:]) > 0.0
    if not fwd.all():
        log.debug("%s: chord points out of order; tracing instead", region.name)
        return None
    return ChordPoints(p, sp, float(lam_at[0]), float(lam_at[1]), it)


#: weight of the cosine spacing in :func:`chord_spacing` (0: uniform)
GRADING = 0.5


def chord_spacing(n: int) -> FloatArray:
    """Chord parameters ``s`` (n,) in (0, 1): uniform blended with the cosine spacing
    (``GRADING``), finer near B1 and B2 where the not-a-knot fit's end intervals need it."""
    x = np.linspace(0.0, 1.0, n + 2)[1:-1]
    return (1.0 - GRADING) * x + GRADING * 0.5 * (1.0 - np.cos(np.pi * x))


def _rows(
    rows: np.ndarray, t: FloatArray, b1: Curve, b2: Curve, p0: FloatArray, dp: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Points (k, 2) and slopes ``dc/dlam`` (k, 2) of the active ``rows`` (increasing) at
    ``t[rows]``: row 0 on ``b1``, row 1 on ``b2``, row ``j >= 2`` on chord ``j - 2``."""
    c = np.empty((rows.size, 2))
    dc = np.empty((rows.size, 2))
    ends = rows[:2].tolist()
    nb = sum(r < 2 for r in ends)  # the side rows come first
    j = rows[nb:] - 2
    c[nb:] = p0[j] + t[rows[nb:], None] * dp[j]
    dc[nb:] = dp[j]
    for at, k in enumerate(ends[:nb]):  # (C and C' from one jet)
        c[at], dc[at], _ = (v[0] for v in (b1, b2)[k].jet(t[k : k + 1]))
    return c, dc
