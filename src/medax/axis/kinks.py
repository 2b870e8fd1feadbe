"""Kinks of the axis: points where a foot point jumps between two branches of a constraint.

A kink is equidistant from three things: the two branches of the jumping constraint and
the other constraint. It is found by Newton's method on those two equations in the
parameter plane, with local (branch-restricted) distances, so it lands on the exact corner
of the axis instead of a bisection's approximation of it.
"""

from __future__ import annotations

import numpy as np

from medax.axis.field import DistanceField, FieldSample
from medax.geometry._rows import row_norms, step_norms
from medax.geometry._types import FloatArray

#: a foot point moving this many times faster than the axis point marks a kink
KINK_SPEED = 25.0
#: ... and is worth a Newton attempt (most kinks then show on the tracer's sparse points,
#: before refinement piles points up around them; a failed attempt only costs rows of the
#: round's vectorised Newton)
KINK_TRY = 4.0
#: half-width (curve parameter) of the branch bracket for local distances
BRANCH_WIDTH = 0.02


def kink_intervals(s: FieldSample, scale: float, speed: float = KINK_SPEED) -> np.ndarray:
    """Intervals ``i`` (between points i and i+1) across which a foot point moves more than
    ``speed`` times as far as the axis point (it jumps)."""
    dx, jump = _moves(s)
    return np.nonzero((jump > speed * dx) & (jump > 1e-6 * scale))[0]


def kink_intervals2(
    s: FieldSample, scale: float, speeds: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`kink_intervals` at two speeds from one measurement of the moves."""
    dx, jump = _moves(s)
    far = jump > 1e-6 * scale
    return tuple(np.nonzero((jump > v * dx) & far)[0] for v in speeds)  # type: ignore[return-value]


def _moves(s: FieldSample) -> tuple[FloatArray, FloatArray]:
    """How far the axis point (n - 1,) and the farther moving foot point (n - 1,) move
    between consecutive points of ``s``."""
    return step_norms(s.x), np.maximum(step_norms(s.q1), step_norms(s.q2))


def locate_kinks(
    field: DistanceField,
    s: FieldSample,
    p: FloatArray,
    intervals: list[int],
    tol: float,
    iters: int = 40,
    speed: float = KINK_TRY,
) -> tuple[list[tuple[int, FloatArray]], FieldSample]:
    """The kinks ``(i, q)`` (``q`` (2,)) confirmed by Newton between axis points ``p[i]``,
    ``p[i+1]`` (parameter plane) for ``i`` of ``intervals`` (an interval without one is
    simply refined), ordered along each interval, and the global field at them (one row
    per kink: the sample of the confirming check). The foot that jumps is that of the
    constraint that moves more, and the other's too where it also moves ``speed`` times as
    far as the axis point (both feet jumping in one interval: two kinks, e.g. near a corner
    of the wavy region).

    All kinks of a round are solved in one Newton batch (:func:`_solve`): each row's three
    distances (the jumping constraint's two branches, the other constraint) are local,
    branch-bracketed queries, one stacked query per step for all rows. The other
    constraint's foot starts from its foot at either end of the interval (one row each:
    where both feet jump it is that of one end or the other, by the kinks' order); a kink
    is kept only where the global field confirms it (``2|g| <= tol``). A kink that no local
    row confirms is solved again with global queries of the other constraint, as the
    tracer did before the batch (a foot of the other constraint that jumps too)."""
    if not intervals:
        return [], FieldSample.empty(field.a1.dim)
    idx = np.asarray(intervals, dtype=np.int64)
    dx = row_norms(s.x[idx + 1] - s.x[idx])
    j1 = row_norms(s.q1[idx + 1] - s.q1[idx])
    j2 = row_norms(s.q2[idx + 1] - s.q2[idx])
    jumps_a1 = j1 >= j2
    both = (j1 > speed * dx) & (j2 > speed * dx)
    # groups (interval, jumping constraint); rows: each group from either end's other foot
    g_int = np.concatenate((idx[jumps_a1 | both], idx[~jumps_a1 | both]))
    g_on2 = np.repeat([False, True], [int(np.sum(jumps_a1 | both)), int(np.sum(~jumps_a1 | both))])
    n_g = g_int.size
    group = np.tile(np.arange(n_g), 2)
    ii, on2 = g_int[group], g_on2[group]
    end = ii + np.repeat([0, 1], n_g)  # the end whose other foot starts the row
    q0 = _start(p, s, ii)
    ok, q, fs = _solve(field, s, ii, on2, end, q0, tol, iters, global_other=False)
    first = np.full(n_g, -1, dtype=np.int64)  # the first confirmed row of each group
    for r in np.flatnonzero(ok)[::-1].tolist():
        first[group[r]] = r
    rows = first[first >= 0]
    found = [(int(ii[r]), q[r]) for r in rows.tolist()]
    samples = [fs.take(rows)]
    again = np.flatnonzero(first < 0)
    if again.size:  # global queries of the other constraint for the groups not confirmed
        ok2, q2, fs2 = _solve(
            field, s, g_int[again], g_on2[again], g_int[again], q0[again], tol, iters, True
        )
        rows2 = np.flatnonzero(ok2)
        found += [(int(g_int[again[r]]), q2[r]) for r in rows2.tolist()]
        samples.append(fs2.take(rows2))
    ids = np.array([f[0] for f in found], dtype=np.int64)
    along = _along(p, ids, np.array([f[1] for f in found]).reshape(-1, 2))
    js = np.flatnonzero(np.isfinite(along))
    js = js[np.lexsort((along[js], ids[js]))]  # by interval, then along it
    kept: list[tuple[int, FloatArray]] = []
    keep: list[int] = []
    for j in js.tolist():  # (two kinks of one interval that coincide are one)
        i, qk = found[j]
        if (
            kept
            and kept[-1][0] == i
            and np.linalg.norm(qk - kept[-1][1]) <= 1e-12 * (np.linalg.norm(p[i + 1] - p[i]))
        ):
            continue
        kept.append((i, qk))
        keep.append(j)
    return kept, FieldSample.concat(samples).take(np.array(keep, dtype=np.int64))


def _start(p: FloatArray, s: FieldSample, ii: np.ndarray) -> FloatArray:
    """Newton starts (k, 2) for kinks in the intervals ``ii`` (k,): the crossing of the
    axis tangents at the interval's ends (each side of a kink is a smooth bisector, so the
    crossing is off by the square of the interval), or the interval's middle where the
    tangents are nearly parallel or cross outside it."""
    a, b = p[ii], p[ii + 1]
    ga, gb = s.grad[ii], s.grad[ii + 1]
    ta = np.column_stack((ga[:, 1], -ga[:, 0]))  # tangents: the gradients turned by -90 deg
    tb = np.column_stack((gb[:, 1], -gb[:, 0]))
    ta /= np.maximum(row_norms(ta), 1e-300)[:, None]
    tb /= np.maximum(row_norms(tb), 1e-300)[:, None]
    ab = b - a
    det = ta[:, 0] * (-tb[:, 1]) - ta[:, 1] * (-tb[:, 0])  # [ta, -tb] [u, v] = b - a
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (ab[:, 0] * (-tb[:, 1]) - ab[:, 1] * (-tb[:, 0])) / det
        v = (ta[:, 0] * ab[:, 1] - ta[:, 1] * ab[:, 0]) / det
        h = row_norms(ab)
        ok = (np.abs(det) > 1e-3) & (u > 0.0) & (v > 0.0) & (u < 2.0 * h) & (v < 2.0 * h)
    u = np.where(ok, u, 0.0)  # (NaN where det = 0: not carried into the product)
    return np.where(ok[:, None], a + u[:, None] * ta, 0.5 * (a + b))


def _solve(
    field: DistanceField,
    s: FieldSample,
    ii: np.ndarray,
    on2: np.ndarray,
    end: np.ndarray,
    q0: FloatArray,
    tol: float,
    iters: int,
    global_other: bool,
) -> tuple[np.ndarray, FloatArray, FieldSample]:
    """Newton on ``wj d_a - wo d_o = wj d_b - wo d_o = 0`` for rows (k,) in intervals ``ii``
    whose jumping constraint is A2 where ``on2`` (else A1): ``d_a``, ``d_b`` the distances
    to its branches at the feet ``t[ii]``, ``t[ii + 1]``, ``d_o`` to the other constraint,
    local from its foot at point ``end`` (or global with ``global_other``), from ``q0``
    (k, 2). Returns the rows confirmed (bool (k,): converged, a kink of the global field,
    distinct branches), the points (k, 2) and the global field there (k rows; meaningful
    where confirmed)."""
    emb = field.region.embedding
    r = field.ratio
    k = ii.size
    # the feet of each row's queries: the two branches, then the other constraint (rows of
    # tt (3, k)), each on A2 where ``side`` (3, k)
    tt = np.array((
        np.where(on2, s.t2[ii], s.t1[ii]),
        np.where(on2, s.t2[ii + 1], s.t1[ii + 1]),
        np.where(on2, s.t1[end], s.t2[end]),
    ))  # fmt: skip
    m = 2 if global_other else 3  # local queries per row (the other constraint: global)
    side = np.array((on2, on2, ~on2)[:m])
    wj = np.where(on2, r, 1.0 - r)[:, None]  # weights of the jumping / other distance
    wo = np.where(on2, 1.0 - r, r)[:, None]
    q = np.array(q0, dtype=np.float64, copy=True)
    conv = np.zeros(k, dtype=bool)
    act = np.arange(k)
    for _ in range(iters):
        x = emb.evaluate(q[act])
        n = act.size
        # the local queries of all rows in one call
        c = field.closest_near(side[:, act].ravel(), np.concatenate((x,) * m), tt[:m, act].ravel(),
                               BRANCH_WIDTH)  # fmt: skip
        tt[:m, act] = c.t.reshape(m, n)
        feet = c.foot.reshape(m, n, -1)
        dist = c.distance.reshape(m, n)
        if global_other:
            c1, c2 = field.closest(x)
            o2 = on2[act]
            feet = np.concatenate((feet, np.where(o2[:, None], c1.foot, c2.foot)[None]))
            dist = np.concatenate((dist, np.where(o2, c1.distance, c2.distance)[None]))
        u = (x - feet) / np.maximum(dist, 1e-300)[:, :, None]  # unit vectors (3, n, dim)
        wja, woa = wj[act], wo[act]
        # both equations at once: values (2, n) and gradients (2, n, dim)
        ff = wja[:, 0] * dist[:2] - woa[:, 0] * dist[2]
        gg = wja * u[:2] - woa * u[2]
        if not emb.is_identity:
            gg = np.einsum("kmi,mij->kmj", gg, emb.jacobian(q[act]))
        f0, f1, ga, gb = ff[0], ff[1], gg[0], gg[1]
        done = 2.0 * np.abs(ff).max(axis=0) <= tol
        conv[act[done]] = True
        det = ga[:, 0] * gb[:, 1] - ga[:, 1] * gb[:, 0]
        move = ~done & (det != 0.0) & np.isfinite(det)  # singular rows: no kink
        f0, f1, ga, gb = f0[move], f1[move], ga[move], gb[move]
        step = np.array((f0 * gb[:, 1] - f1 * ga[:, 1], ga[:, 0] * f1 - gb[:, 0] * f0)).T
        q[act[move]] -= step / det[move, None]
        act = act[move]
        if act.size == 0:
            break
    ok = conv & (np.abs(tt[0] - tt[1]) >= 1e-9)
    # the kink must be on the axis of the full (global) field (one query for all rows:
    # the unconfirmed ones ride along)
    fs = field(q)
    ok &= fs.error <= tol
    return ok, q, fs


def _along(p: FloatArray, ii: np.ndarray, q: FloatArray) -> FloatArray:
    """Where the points ``q`` (k, 2) lie along the intervals ``p[ii]``, ``p[ii + 1]`` (their
    projections' fractions, (k,)), NaN where one is not on this piece of the axis (Newton
    can also find a crossing of the two branches' fields far away)."""
    a = p[ii]
    ab = p[ii + 1] - a
    aq = q - a
    along = np.add.reduce(aq * ab, axis=1) / np.add.reduce(ab * ab, axis=1)
    near = row_norms(aq - along[:, None] * ab) <= row_norms(ab)
    return np.where((along > 1e-9) & (along < 1.0 - 1e-9) & near, along, np.nan)
