"""Whether four planar sides form one simple closed curve.

The sides are sampled (at equal parameter steps and at every break, so polyline vertices
are kept) into one closed polyline; any two of its segments that are not neighbours must
stay more than ``TOUCH_TOL x diagonal`` apart, and no segment may turn straight back on
the one before it. This refuses what a crossing test lets through: a pinched region (a
side touching another in its middle), a side doubling back over itself or running up its
neighbour and back, a side that is a closed loop (coincident corners).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from medax import tolerances
from medax.errors import RegionError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve

#: non-neighbouring parts of the boundary closer than this x diagonal touch
TOUCH_TOL = tolerances.CORNER_TOL
_SAMPLES = 200  # samples per side (plus its breaks)
_CHUNK = 16  # segments per bounding box
#: sampled gaps below this x diagonal are refined on the curves themselves
COARSE = 1e-2


def check_simple(sides: Sequence[Curve], diag: float, name: str) -> None:
    """Raise :class:`RegionError` naming the sides and the place where the boundary touches
    or folds back on itself."""
    tol = TOUCH_TOL * diag
    corners = np.array([s.start for s in sides])
    for i in range(4):
        for j in range(i + 1, 4):
            if np.linalg.norm(corners[i] - corners[j]) <= tol:
                raise RegionError(
                    f"region '{name}': corners {i} and {j} coincide at {_at(corners[i])} "
                    "(the four sides must form one simple closed curve)"
                )
    pts, side_of = _closed_polyline(sides)
    a0, a1 = pts, np.roll(pts, -1, axis=0)
    _check_turns(a0, a1, side_of, name)
    i, j, gap, where = _closest_pair(a0, a1, tol)
    if i < 0:
        i, j, gap, where = _smooth_touch(sides, tol, diag)
        side_of = np.arange(4)
    if i >= 0:
        si, sj = int(side_of[i]), int(side_of[j])
        what = f"side {si} touches itself" if si == sj else f"side {si} touches side {sj}"
        raise RegionError(
            f"region '{name}': {what} at {_at(where)} (gap {gap / diag:.1e} x diagonal; "
            "the four sides must form one simple closed curve)"
        )


def _smooth_touch(
    sides: Sequence[Curve], tol: float, diag: float
) -> tuple[int, int, float, FloatArray]:
    """Two sides touching between samples (an arc's apex on a line): the local minima of the
    distance from side i's samples to side j (below ``COARSE x diagonal``, away from a
    shared corner) refined by golden-section search; (i, j, gap, place) or (-1, ...)."""
    t = np.linspace(0.0, 1.0, _SAMPLES)
    for i in range(4):
        p = sides[i].evaluate(t)
        for j in range(4):
            if j == i:
                continue
            d = sides[j].closest(p).distance
            k = np.arange(1, _SAMPLES - 1)
            k = k[(d[k] <= d[k - 1]) & (d[k] <= d[k + 1]) & (d[k] < COARSE * diag)]
            if j == (i + 1) % 4:
                k = k[k < _SAMPLES - 3]  # not at the corner side i shares with side j
            if i == (j + 1) % 4:
                k = k[k > 2]
            for kk in k[np.argsort(d[k])][:4]:
                s, gap = _golden(sides[i], sides[j], t[kk - 1], t[kk + 1])
                if gap <= tol:
                    return i, j, gap, sides[i].evaluate(np.array([s]))[0]
    return -1, -1, np.inf, np.zeros(2)


def _golden(a: Curve, b: Curve, lo: float, hi: float, iters: int = 40) -> tuple[float, float]:
    """The parameter of ``a`` in [lo, hi] nearest to curve ``b``, and that distance."""

    def gap(s: float) -> float:
        return float(b.closest(a.evaluate(np.array([s]))).distance[0])

    r = 0.5 * (np.sqrt(5.0) - 1.0)
    x1, x2 = hi - r * (hi - lo), lo + r * (hi - lo)
    f1, f2 = gap(x1), gap(x2)
    for _ in range(iters):
        if f1 <= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - r * (hi - lo)
            f1 = gap(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + r * (hi - lo)
            f2 = gap(x2)
    return (x1, f1) if f1 <= f2 else (x2, f2)


def _at(p: FloatArray) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in p) + ")"


def _closed_polyline(sides: Sequence[Curve]) -> tuple[FloatArray, np.ndarray]:
    """Vertices of the closed boundary (each side without its end point) and the side each
    segment (from vertex k to k + 1) belongs to."""
    parts, labels = [], []
    for k, s in enumerate(sides):
        t = np.union1d(np.linspace(0.0, 1.0, _SAMPLES), s.breaks())
        p = s.evaluate(t)[:-1]
        parts.append(p)
        labels.append(np.full(len(p), k))
    return np.concatenate(parts), np.concatenate(labels)


def _check_turns(a0: FloatArray, a1: FloatArray, side_of: np.ndarray, name: str) -> None:
    """A segment running straight back along the one before it."""
    d = a1 - a0
    nxt = np.roll(d, -1, axis=0)
    dot = np.sum(d * nxt, axis=1)
    norms = np.linalg.norm(d, axis=1) * np.linalg.norm(nxt, axis=1)
    back = np.nonzero(dot <= -(1.0 - 1e-12) * norms)[0]
    if back.size:
        k = int(back[0])
        s0, s1 = int(side_of[k]), int(side_of[(k + 1) % len(side_of)])
        what = f"side {s0} doubles back"
        if s0 != s1:
            what = f"sides {s0} and {s1} fold onto each other"
        raise RegionError(
            f"region '{name}': {what} at {_at(a1[k])} "
            "(the four sides must form one simple closed curve)"
        )


def _closest_pair(a0: FloatArray, a1: FloatArray, tol: float) -> tuple[int, int, float, FloatArray]:
    """The closest two non-neighbouring segments within ``tol``: their indices, gap and a
    point of the first where they are closest; (-1, -1, inf, ...) when none is."""
    n = len(a0)
    c = -(-n // _CHUNK)
    idx = np.minimum(np.arange(c * _CHUNK), n - 1).reshape(c, _CHUNK)
    lo = np.minimum(a0[idx].min(axis=1), a1[idx].min(axis=1))
    hi = np.maximum(a0[idx].max(axis=1), a1[idx].max(axis=1))
    near = np.all((lo[:, None] <= hi[None] + tol) & (lo[None] <= hi[:, None] + tol), axis=2)
    ci, cj = np.nonzero(np.triu(near))
    best = (-1, -1, np.inf, a0[0])
    for start in range(0, len(ci), 256):  # bounded temporaries
        gi = idx[ci[start : start + 256]][:, :, None]
        gj = idx[cj[start : start + 256]][:, None, :]
        gi, gj = np.broadcast_arrays(gi, gj)
        apart = (gj - gi) % n
        keep = (apart >= 2) & (apart <= n - 2)
        if not keep.any():
            continue
        i, j = gi[keep], gj[keep]
        gap, where = _segment_gap(a0[i], a1[i], a0[j], a1[j])
        m = int(np.argmin(gap))
        if gap[m] <= tol and gap[m] < best[2]:
            best = (int(i[m]), int(j[m]), float(gap[m]), where[m])
    return best


def _segment_gap(
    a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Distance between segments a and b (rows), and the closest point found on a or b."""
    cands = [
        (_point_segment(a0, b0, b1), a0),
        (_point_segment(a1, b0, b1), a1),
        (_point_segment(b0, a0, a1), b0),
        (_point_segment(b1, a0, a1), b1),
    ]
    gaps = np.stack([g for g, _ in cands])
    pts = np.stack([p for _, p in cands])
    k = np.argmin(gaps, axis=0)
    rows = np.arange(len(a0))
    gap, where = gaps[k, rows], pts[k, rows]
    cross = _proper_cross(a0, a1, b0, b1)
    return np.where(cross, 0.0, gap), where


def _point_segment(p: FloatArray, s0: FloatArray, s1: FloatArray) -> FloatArray:
    d = s1 - s0
    t = np.clip(np.sum((p - s0) * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300), 0, 1)
    return np.asarray(np.linalg.norm(p - (s0 + t[:, None] * d), axis=1))


def _proper_cross(a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray) -> np.ndarray:
    def orient(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    ab = orient(a0, a1, b0) * orient(a0, a1, b1)
    ba = orient(b0, b1, a0) * orient(b0, b1, a1)
    return np.asarray((ab < 0) & (ba < 0))
