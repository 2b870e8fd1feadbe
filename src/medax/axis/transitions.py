"""Transitions of the axis: points where a foot point reaches an end of its constraint, or
a corner of it (a C0 joint of a B-spline or polyline constraint, e.g. a traced axis with a
kink used as a side).

Past a constraint's end (or onto a corner) the nearest point of that constraint stays there,
and the axis changes from one kind of curve to another (e.g. from a line to a parabola): it
is only C1 there. A cubic spline through points on both sides converges slowly across
such a point, so the refinement would pile points up around it. Locating it exactly and
making it a break of the fit keeps each piece smooth.

The transition at the vertex ``c = C(e)`` (``e`` = 0, 1 or a corner) of a constraint ``C``
is where the axis crosses the plane through ``c`` normal to the one-sided tangent ``C'(e)``
of the piece the foot leaves: the root of

    g(p) = 0,   h(p) = (E(p) - c) . C'(e) = 0,

solved by Newton's method on both equations at once for all transitions of a round.
"""

from __future__ import annotations

import numpy as np

from medax.axis.field import DistanceField, FieldSample
from medax.geometry._types import FloatArray

#: a foot parameter this close to a vertex is at the vertex
AT_VERTEX = 1e-12


def transition_intervals(
    s: FieldSample, breaks: tuple[FloatArray, FloatArray] = (np.zeros(0), np.zeros(0))
) -> list[tuple[int, int, float, int]]:
    """``(i, constraint, vertex, side)``: the foot on constraint 1 or 2 reaches a vertex
    (0.0, 1.0 or one of the constraint's ``breaks``) between points ``i`` and ``i + 1``,
    coming from the piece before it (``side = -1``) or after it (``+1``)."""
    out = []
    for k, t, inner in ((1, s.t1, breaks[0]), (2, s.t2, breaks[1])):
        for e in (0.0, *np.asarray(inner).tolist(), 1.0):
            at = np.abs(t - e) <= AT_VERTEX
            for i in np.nonzero(at[:-1] != at[1:])[0]:
                off = t[i + 1] if at[i] else t[i]  # the foot not at the vertex
                out.append((int(i), k, float(e), -1 if off < e else 1))
    return out


def locate_transitions(
    field: DistanceField,
    pts: FloatArray,
    s: FieldSample,
    found: list[tuple[int, int, float, int]],
    tol: float,
    iters: int = 12,
) -> tuple[np.ndarray, FloatArray, FieldSample]:
    """Transition points for the intervals ``found`` (from :func:`transition_intervals`):
    indices ``i`` (m,) of the intervals where one was confirmed, the points (m, 2) in the
    parameter plane (equidistance within ``tol`` and strictly between the interval's ends)
    and the field there."""
    if not found:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2)), FieldSample.empty(field.a1.dim)
    idx = np.array([f[0] for f in found], dtype=np.int64)
    curves = [field.a1 if k == 1 else field.a2 for _, k, _, _ in found]
    ends = [np.array([e]) for _, _, e, _ in found]
    # one-sided tangent of the piece the foot leaves (a hair inside it)
    sides = [np.clip(np.array([e + 1e-12 * side]), 0.0, 1.0) for _, _, e, side in found]
    c = np.array([cv.evaluate(e)[0] for cv, e in zip(curves, ends, strict=True)])
    d = np.array([cv.derivative(e)[0] for cv, e in zip(curves, sides, strict=True)])
    d /= np.linalg.norm(d, axis=1)[:, None]
    emb = field.region.embedding
    a, b = pts[idx], pts[idx + 1]
    ha = np.einsum("ij,ij->i", s.x[idx] - c, d)
    hb = np.einsum("ij,ij->i", s.x[idx + 1] - c, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.clip(np.nan_to_num(ha / (ha - hb), nan=0.5), 0.0, 1.0)
    q = a + w[:, None] * (b - a)
    active = np.arange(len(q))
    for _ in range(iters):
        qa, ca, da = q[active], c[active], d[active]
        fs = field(qa)
        h = np.einsum("ij,ij->i", fs.x - ca, da)
        grad_h = np.einsum("nij,ni->nj", emb.jacobian(qa), da)
        m = np.stack((fs.grad, grad_h), axis=1)  # (n, 2, 2)
        det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
        ok = np.abs(det) > 1e-300
        rhs = np.column_stack((fs.g, h))
        step = np.zeros_like(qa)
        step[ok] = np.linalg.solve(m[ok], rhs[ok][:, :, None])[:, :, 0]
        q[active] = qa - step
        # quadratic convergence: after a step of 1e-8 (x diagonal) the point is off by
        # ~1e-16 K (K the ratio of the field's curvature to its gradient, of order one)
        active = active[ok & (np.linalg.norm(step, axis=1) > 1e-8 * field.region.diagonal)]
        if active.size == 0:
            break
    fs = field(q)
    # strictly inside the interval (projection onto the chord) and on the axis
    along = np.einsum("ij,ij->i", q - a, b - a) / np.einsum("ij,ij->i", b - a, b - a)
    good = (fs.error <= tol) & (along > 1e-9) & (along < 1.0 - 1e-9) & np.all(np.isfinite(q), 1)
    return idx[good], q[good], fs.take(np.flatnonzero(good))
