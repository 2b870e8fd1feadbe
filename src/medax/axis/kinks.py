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
from medax.geometry.curve import closest_near

#: a foot point moving this many times faster than the axis point marks a kink
KINK_SPEED = 25.0
#: half-width (curve parameter) of the branch bracket for local distances
BRANCH_WIDTH = 0.02


def kink_intervals(s: FieldSample, scale: float) -> np.ndarray:
    """Intervals ``i`` (between points i and i+1) across which a foot point jumps."""
    dx = np.linalg.norm(np.diff(s.x, axis=0), axis=1)
    jump = np.maximum(
        np.linalg.norm(np.diff(s.q1, axis=0), axis=1), np.linalg.norm(np.diff(s.q2, axis=0), axis=1)
    )
    return np.nonzero((jump > KINK_SPEED * dx) & (jump > 1e-6 * scale))[0]


def locate_kink(
    field: DistanceField, s: FieldSample, p: FloatArray, i: int, tol: float, iters: int = 40
) -> FloatArray | None:
    """The kink (2,) between axis points ``p[i]``, ``p[i+1]`` (parameter plane), or ``None``
    when Newton does not confirm one (then the interval is simply refined).

    Called once per detected kink (a handful per axis), so a small loop is fine here.
    """
    jumps_a1 = np.linalg.norm(s.q1[i + 1] - s.q1[i]) >= np.linalg.norm(s.q2[i + 1] - s.q2[i])
    jumping, other = (field.a1, field.a2) if jumps_a1 else (field.a2, field.a1)
    t_par = s.t1 if jumps_a1 else s.t2
    ta, tb = np.array([t_par[i]]), np.array([t_par[i + 1]])
    r = field.ratio
    wj, wo = (1.0 - r, r) if jumps_a1 else (r, 1.0 - r)  # weights of jumping / other distance
    emb = field.region.embedding
    q = 0.5 * (p[i] + p[i + 1])
    for _ in range(iters):
        x = emb.evaluate(q[None, :])
        ca = closest_near(jumping, x, ta, BRANCH_WIDTH)
        cb = closest_near(jumping, x, tb, BRANCH_WIDTH)
        co = other.closest(x)
        ta, tb = ca.t, cb.t
        da, db, do = ca.distance[0], cb.distance[0], co.distance[0]
        ua, ub, uo = ((x - c.foot)[0] / max(c.distance[0], 1e-300) for c in (ca, cb, co))
        f = np.array([wj * da - wo * do, wj * db - wo * do])
        jac = emb.jacobian(q[None, :])[0]
        m = np.array([(wj * ua - wo * uo) @ jac, (wj * ub - wo * uo) @ jac])
        if np.max(np.abs(f)) * 2.0 <= tol:
            break
        try:
            step = np.linalg.solve(m, f)
        except np.linalg.LinAlgError:
            return None
        q = q - step
    else:
        return None
    if abs(ta[0] - tb[0]) < 1e-9:  # both branches converged to one: no kink after all
        return None
    # it must lie in its interval: Newton can also find a crossing of the two branches'
    # fields far away (not on this piece of the axis)
    ab = p[i + 1] - p[i]
    along = float((q - p[i]) @ ab / (ab @ ab))
    if not (1e-9 < along < 1.0 - 1e-9) or np.linalg.norm(q - p[i] - along * ab) > np.linalg.norm(
        ab
    ):
        return None
    # the kink must be on the axis of the full (global) field
    if field(q[None, :]).error[0] > tol:
        return None
    return q
