"""Tracing insertion points from B1 to B2 (paper steps 2-5).

Two predictors: the moving frame (default) steps along the axis tangent, perpendicular to
the field gradient, with a step that adapts to the turning of the axis; the paper's rule
steps along ``e1 + e2`` (the constraints' tangents at the foot points) by shortest side / 5.
"""

from __future__ import annotations

import math

import numpy as np

from medax.axis.correct import correct_newton, correct_paper
from medax.axis.field import DistanceField, FieldSample
from medax.errors import TraceError
from medax.geometry._rows import row_norms
from medax.geometry._types import FloatArray

#: target turn of the axis tangent per step (radians) for the adaptive step
TARGET_TURN = math.radians(8.0)
#: a step turning more than this is retried with half the step
MAX_TURN = math.radians(25.0)
#: a predicted point moved by more than this fraction of the step is retried smaller
MAX_CORRECTION = 0.35
#: cap on the number of insertion points before giving up
MAX_STEPS = 20000


def tangent(sample: FieldSample) -> FloatArray:
    """Unit axis tangents (n, 2) in the parameter plane: the gradient turned by -90 degrees,
    which points from B1 towards B2 when A1 is on the right... of the gradient."""
    gx, gy = sample.grad[:, 0], sample.grad[:, 1]
    t = np.column_stack((gy, -gx))
    return t / np.maximum(row_norms(t), 1e-300)[:, None]


def _space_speed(field: DistanceField, p: FloatArray, v: FloatArray) -> FloatArray:
    """Length in space of parameter-plane vectors ``v`` (n, 2) at ``p`` (n, 2)."""
    emb = field.region.embedding
    if emb.is_identity:
        return row_norms(v)
    return row_norms(np.einsum("nij,nj->ni", emb.jacobian(p), v))


def _length(v: FloatArray) -> float:
    """``np.linalg.norm`` of a vector (dim,) to the last bit (the same dot product), without
    its argument handling (the frame trace measures two per step)."""
    return math.sqrt(float(v.dot(v)))


class TraceStats:
    """Mutable counters filled while tracing."""

    def __init__(self) -> None:
        self.steps = 0
        self.corrector_iterations = 0


def trace_frame(
    field: DistanceField,
    start: FloatArray,
    end: FloatArray,
    h0: float,
    h_min: float,
    h_max: float,
    tol: float,
    stats: TraceStats,
) -> FloatArray:
    """Insertion points (n, 2) from ``start`` to ``end`` (both included) by the moving frame.

    ``h0``, ``h_min``, ``h_max`` are step lengths in space; ``tol`` the absolute
    equidistance tolerance of each point.
    """
    pts = [np.asarray(start, dtype=np.float64)]
    p = pts[0][None, :]
    s = field(p)
    t = tangent(s)
    x_end = field.region.embedding.evaluate(np.asarray(end, dtype=np.float64)[None, :])[0]
    h = h0
    while True:
        stats.steps += 1
        if stats.steps > MAX_STEPS:
            raise TraceError(
                f"region '{field.region.name}': no arrival at B2 after {MAX_STEPS} steps"
            )
        chord = _length(x_end - s.x[0])
        if chord <= 1.5 * h:
            break
        speed = float(_space_speed(field, p, t)[0])
        pred = p + (h / speed) * t
        q, sq, ok, it = correct_newton(field, pred, tol)
        stats.corrector_iterations += it
        tq = tangent(sq)
        turn = float(np.arccos(min(max(float(np.dot(t[0], tq[0])), -1.0), 1.0)))
        moved = _length(sq.x[0] - field.region.embedding.evaluate(pred)[0])
        inside = bool(field.region.contains(q)[0])
        good = ok[0] and inside and turn <= MAX_TURN and moved <= MAX_CORRECTION * h
        if not good and h > h_min:
            h = max(0.5 * h, h_min)
            continue
        if not (ok[0] and inside):
            raise TraceError(
                f"region '{field.region.name}': lost the axis near {p[0].tolist()} "
                f"(step {h:.3g}); the region may have no single axis between this pair"
            )
        p, s, t = q, sq, tq
        pts.append(p[0])
        grow = TARGET_TURN / max(turn, 1e-12)
        h = float(np.clip(h * min(max(grow, 0.5), 2.0), h_min, h_max))
    pts.append(np.asarray(end, dtype=np.float64))
    return np.array(pts)


def trace_paper(
    field: DistanceField,
    start: FloatArray,
    end: FloatArray,
    delta: float,
    b2_distance,
    stats: TraceStats,
) -> FloatArray:
    """Insertion points by the paper's rules: direction ``e1 + e2``, step ``delta`` (space),
    the ``|d1 - d2| / 2n`` correction to ``0.99 < d1/d2 < 1.01``; stop when the next point is
    within ``delta`` of B2 (``b2_distance(p) -> (n,)``), then append the exact end point."""
    reg = field.region
    pts = [np.asarray(start, dtype=np.float64)]
    p = pts[0][None, :]
    a1, a2 = reg.sides[field.roles.a1], reg.sides[field.roles.a2]
    while True:
        stats.steps += 1
        if stats.steps > MAX_STEPS:
            raise TraceError(f"region '{reg.name}': paper method did not reach B2")
        s = field(p)
        # constraint tangents at the foot points, oriented from B1 to B2 (A2 runs backwards)
        e1 = a1.derivative(s.t1)
        e2 = -a2.derivative(s.t2)
        e = e1 / np.linalg.norm(e1) + e2 / np.linalg.norm(e2)
        e /= max(float(np.linalg.norm(e)), 1e-300)
        speed = float(_space_speed(field, p, e)[0])
        pred = p + (delta / speed) * e
        if float(b2_distance(pred)[0]) < delta:
            break
        q, _, it = correct_paper(field, pred)
        stats.corrector_iterations += it
        p = q
        pts.append(p[0])
    pts.append(np.asarray(end, dtype=np.float64))
    return np.array(pts)
