"""Kinks of the axis: points where a foot point jumps between two branches of a constraint.

A kink is equidistant from three things: the two branches of the jumping constraint and
the other constraint. It is found by Newton's method on those two equations in the
parameter plane, with local (branch-restricted) distances, so it lands on the exact corner
of the axis instead of a bisection's approximation of it.
"""

from __future__ import annotations

import numpy as np

from medax.axis.field import DistanceField, FieldSample
from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, closest_near

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
    dx = np.linalg.norm(np.diff(s.x, axis=0), axis=1)
    jump = np.maximum(
        np.linalg.norm(np.diff(s.q1, axis=0), axis=1), np.linalg.norm(np.diff(s.q2, axis=0), axis=1)
    )
    return np.nonzero((jump > speed * dx) & (jump > 1e-6 * scale))[0]


def locate_kinks(
    field: DistanceField,
    s: FieldSample,
    p: FloatArray,
    intervals: list[int],
    tol: float,
    iters: int = 40,
    speed: float = KINK_TRY,
) -> list[tuple[int, FloatArray]]:
    """The kinks ``(i, q)`` (``q`` (2,)) confirmed by Newton between axis points ``p[i]``,
    ``p[i+1]`` (parameter plane) for ``i`` of ``intervals`` (an interval without one is
    simply refined). All kinks of a round are solved at once, grouped by the constraint
    whose foot jumps: the one that moves more, and the other too where it also moves
    ``speed`` times as far as the axis point (both feet jumping in one interval: two kinks,
    e.g. near a corner of the wavy region), ordered along each interval."""
    out: list[tuple[int, float, FloatArray]] = []
    if not intervals:
        return []
    idx = np.asarray(intervals, dtype=np.int64)
    dx = np.linalg.norm(s.x[idx + 1] - s.x[idx], axis=1)
    j1 = np.linalg.norm(s.q1[idx + 1] - s.q1[idx], axis=1)
    j2 = np.linalg.norm(s.q2[idx + 1] - s.q2[idx], axis=1)
    jumps_a1 = j1 >= j2
    both = (j1 > speed * dx) & (j2 > speed * dx)
    emb = field.region.embedding
    r = field.ratio
    for flag in (True, False):
        rows = np.flatnonzero((jumps_a1 == flag) | both)
        if rows.size == 0:
            continue
        ii = idx[rows]
        jumping, other = (field.a1, field.a2) if flag else (field.a2, field.a1)
        t_par = s.t1 if flag else s.t2
        ta, tb = t_par[ii].copy(), t_par[ii + 1].copy()
        wj, wo = (1.0 - r, r) if flag else (r, 1.0 - r)  # weights of jumping / other distance
        q = 0.5 * (p[ii] + p[ii + 1])
        conv = np.zeros(len(ii), dtype=bool)
        act = np.arange(len(ii))
        for _ in range(iters):
            x = emb.evaluate(q[act])
            nb = len(act)  # both branches in one query
            cab = closest_near(
                jumping, np.concatenate((x, x)), np.concatenate((ta[act], tb[act])), BRANCH_WIDTH
            )
            ca, cb = (
                Closest(cab.t[sl], cab.foot[sl], cab.distance[sl])
                for sl in (slice(0, nb), slice(nb, None))
            )
            co = other.closest(x)
            ta[act], tb[act] = ca.t, cb.t
            ua, ub, uo = (
                (x - c.foot) / np.maximum(c.distance, 1e-300)[:, None] for c in (ca, cb, co)
            )
            f0 = wj * ca.distance - wo * co.distance
            f1 = wj * cb.distance - wo * co.distance
            jac = emb.jacobian(q[act])
            ga = np.einsum("mi,mij->mj", wj * ua - wo * uo, jac)
            gb = np.einsum("mi,mij->mj", wj * ub - wo * uo, jac)
            done = 2.0 * np.maximum(np.abs(f0), np.abs(f1)) <= tol
            conv[act[done]] = True
            det = ga[:, 0] * gb[:, 1] - ga[:, 1] * gb[:, 0]
            move = ~done & (det != 0.0) & np.isfinite(det)  # singular rows: no kink
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.column_stack(
                    (f0 * gb[:, 1] - f1 * ga[:, 1], ga[:, 0] * f1 - gb[:, 0] * f0)
                )
                step /= det[:, None]
            q[act[move]] -= step[move]
            act = act[move]
            if act.size == 0:
                break
        good = np.flatnonzero(conv)
        if good.size == 0:
            continue
        # the kink must be on the axis of the full (global) field
        on_axis = field(q[good]).error <= tol
        for j, ok in zip(good.tolist(), on_axis.tolist(), strict=True):
            i = int(ii[j])
            along = _along(p, i, q[j])
            if ok and along is not None and abs(ta[j] - tb[j]) >= 1e-9:
                out.append((i, along, q[j]))
    out.sort(key=lambda k: (k[0], k[1]))
    kept: list[tuple[int, FloatArray]] = []
    for i, _, q in out:  # (two kinks of one interval that coincide are one)
        if (
            kept
            and kept[-1][0] == i
            and np.linalg.norm(q - kept[-1][1]) <= 1e-12 * (np.linalg.norm(p[i + 1] - p[i]))
        ):
            continue
        kept.append((i, q))
    return kept


def _along(p: FloatArray, i: int, q: FloatArray) -> float | None:
    """Where ``q`` (2,) lies along the interval ``p[i]``, ``p[i+1]`` (its projection's
    fraction), or ``None`` if it is not on this piece of the axis (Newton can also find a
    crossing of the two branches' fields far away)."""
    ab = p[i + 1] - p[i]
    along = float((q - p[i]) @ ab / (ab @ ab))
    near = bool(np.linalg.norm(q - p[i] - along * ab) <= np.linalg.norm(ab))
    return along if 1e-9 < along < 1.0 - 1e-9 and near else None
