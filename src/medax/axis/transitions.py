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

A foot that crosses a vertex between two axis points without a point resting on it (many
close vertices: a polyline of hundreds) is found from the feet's pieces
(:func:`vertex_crossings`): where the vertex is convex towards the axis the foot rests on it
over a stretch of the axis, two transitions (the normal planes of both pieces); where it is
reflex the foot jumps across it at a kink, on the bisector of the two pieces' lines,
``(E(p) - c) . (C'(e-) + C'(e+)) = 0`` (unit one-sided tangents), solved the same way.
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
    out: list[tuple[int, int, float, int]] = []
    for k, t, inner in ((1, s.t1, breaks[0]), (2, s.t2, breaks[1])):
        e = np.concatenate(([0.0], np.asarray(inner, dtype=np.float64), [1.0]))
        at = np.abs(t[None, :] - e[:, None]) <= AT_VERTEX  # (vertices, points)
        vi, ii = (at[:, :-1] != at[:, 1:]).nonzero()  # by vertex, then along the axis
        if vi.size:
            off = np.where(at[vi, ii], t[ii + 1], t[ii])  # the foot not at the vertex
            ev = e[vi]
            side = np.where(off < ev, -1, 1)
            rows = zip(ii.tolist(), ev.tolist(), side.tolist(), strict=True)
            out += [(i, k, v, d) for i, v, d in rows]
    return out


#: at most this many vertices crossed by a foot between two axis points are looked for
#: (more: the foot jumps across a stretch of its constraint, a kink of :mod:`kinks`)
MAX_CROSSED = 4


def vertex_crossings(
    field: DistanceField, s: FieldSample, vertices: tuple[FloatArray, FloatArray]
) -> list[tuple[int, int, float, int]]:
    """``(i, constraint, vertex, side)`` for vertices (C0 corners ``vertices`` of A1, A2) that
    a foot crosses strictly between points ``i`` and ``i + 1``, neither foot on it: ``side``
    -1 and +1 (the two transitions) where the corner is convex towards the axis points, 0
    (the kink on the corner's bisector) where it is reflex; corners where the curve does
    not turn are skipped."""
    out: list[tuple[int, int, float, int]] = []
    for k, t, inner in ((1, s.t1, vertices[0]), (2, s.t2, vertices[1])):
        v = np.asarray(inner, dtype=np.float64)
        if v.size == 0 or t.size < 2:
            continue
        lo = np.minimum(t[:-1], t[1:]) + AT_VERTEX
        hi = np.maximum(t[:-1], t[1:]) - AT_VERTEX
        first = np.searchsorted(v, lo, side="left")
        count = np.searchsorted(v, hi, side="right") - first
        rows = np.flatnonzero((count >= 1) & (count <= MAX_CROSSED))
        if rows.size == 0:
            continue
        reps = count[rows]
        ii = np.repeat(rows, reps)
        within = np.arange(reps.sum()) - np.repeat(np.cumsum(reps) - reps, reps)
        jv = np.repeat(first[rows], reps) + within  # the crossed vertices, in order
        e = v[jv]
        curve = field.a1 if k == 1 else field.a2
        c = curve.evaluate(e)
        tm = _unit(curve.derivative(np.clip(e - 1e-12, 0.0, 1.0)))
        tp = _unit(curve.derivative(np.clip(e + 1e-12, 0.0, 1.0)))
        turn = tm[:, 0] * tp[:, 1] - tm[:, 1] * tp[:, 0]
        x = 0.5 * (s.x[ii] + s.x[ii + 1]) - c
        side = tm[:, 0] * x[:, 1] - tm[:, 1] * x[:, 0]
        if c.shape[1] != 2:  # (in space: no orientation; both transitions are tried)
            turn, side = np.ones(len(e)), -np.ones(len(e))
        rests = turn * side < 0.0
        real = np.abs(turn) > 1e-12
        for i, ek, r in zip(ii[real].tolist(), e[real].tolist(), rests[real].tolist(), strict=True):
            if r:
                out += [(i, k, ek, -1), (i, k, ek, 1)]
            else:
                out.append((i, k, ek, 0))
    return out


def _unit(v: FloatArray) -> FloatArray:
    return v / np.maximum(np.linalg.norm(v, axis=1), 1e-300)[:, None]


def locate_transitions(
    field: DistanceField,
    pts: FloatArray,
    s: FieldSample,
    found: list[tuple[int, int, float, int]],
    tol: float,
    iters: int = 12,
) -> tuple[np.ndarray, FloatArray, FieldSample, np.ndarray]:
    """Transition points for the intervals ``found`` (from :func:`transition_intervals`):
    indices ``i`` (m,) of the intervals where one was confirmed, the points (m, 2) in the
    parameter plane (equidistance within ``tol`` and strictly between the interval's ends),
    the field there and the rows of ``found`` they solve (m,)."""
    if not found:
        empty = np.zeros(0, dtype=np.int64)
        return empty, np.zeros((0, 2)), FieldSample.empty(field.a1.dim), empty
    idx = np.array([f[0] for f in found], dtype=np.int64)
    on2 = np.array([f[1] == 2 for f in found])
    e = np.array([f[2] for f in found])
    side = np.array([f[3] for f in found])
    dim = field.a1.dim
    c, d = np.empty((len(found), dim)), np.empty((len(found), dim))
    for curve, rows in ((field.a1, np.flatnonzero(~on2)), (field.a2, np.flatnonzero(on2))):
        if rows.size:
            er = e[rows]
            c[rows] = curve.evaluate(er)
            # one-sided tangent of the piece the foot leaves (a hair inside it); for a
            # reflex corner (side 0) the sum of both: the normal of the corner's bisector
            tm = _unit(curve.derivative(np.clip(er - 1e-12, 0.0, 1.0)))
            tp = _unit(curve.derivative(np.clip(er + 1e-12, 0.0, 1.0)))
            sr = side[rows][:, None]
            d[rows] = np.where(sr < 0, tm, np.where(sr > 0, tp, tm + tp))
    d = _unit(d)
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
    kept = np.flatnonzero(good)
    return idx[good], q[good], fs.take(kept), kept
