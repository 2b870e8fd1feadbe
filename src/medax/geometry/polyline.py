"""Polyline, parametrised by normalised arc length."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from medax.errors import CurveError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, Curve

_CHUNK = 4096  # rows per block in the segment-distance table, to bound memory
#: vertices looked at first per point on polylines of more than twice as many segments
_NEAR = 16


class Polyline(Curve):
    """Points ``(m, dim)``, ``m >= 2``; ``t`` is the arc-length fraction."""

    def __init__(self, points: FloatArray) -> None:
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[0] < 2 or pts.shape[1] not in (2, 3):
            raise CurveError(f"polyline needs (m >= 2, 2|3) points, got shape {pts.shape}")
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(seg == 0.0):
            i = int(np.argmin(seg))
            raise CurveError(f"polyline has repeated consecutive points at index {i}")
        self.points = pts
        cum = np.concatenate(([0.0], np.cumsum(seg)))
        self._total = float(cum[-1])
        self._tk = cum / self._total
        self._vertex_tree: cKDTree | None = None  # of the vertices (built on first use)
        self._half_segment = 0.0

    @property
    def dim(self) -> int:
        return int(self.points.shape[1])

    def breaks(self) -> FloatArray:
        return self._tk[1:-1].copy()

    def complexity(self) -> int:
        return self.points.shape[0] - 1

    def _locate(self, t: FloatArray) -> tuple[np.ndarray, FloatArray]:
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0)
        i = np.clip(np.searchsorted(self._tk, t, side="right") - 1, 0, self.points.shape[0] - 2)
        u = (t - self._tk[i]) / (self._tk[i + 1] - self._tk[i])
        return i, u

    def evaluate(self, t: FloatArray) -> FloatArray:
        i, u = self._locate(t)
        p = self.points
        return p[i] + u[:, None] * (p[i + 1] - p[i])

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        i, _ = self._locate(t)
        if order != 1:
            return np.zeros((i.size, self.dim))
        p = self.points
        return (p[i + 1] - p[i]) / (self._tk[i + 1] - self._tk[i])[:, None]

    def reversed(self) -> Polyline:
        return Polyline(self.points[::-1])

    def transformed(self, offset: FloatArray, scale: float) -> Polyline:
        return Polyline((self.points - offset) / scale)

    def length(self, n: int = 0) -> float:
        return self._total

    def closest(self, points: FloatArray) -> Closest:
        """Exact. Few segments: the distance to every segment (blocks of rows), the smallest
        wins. Many (> ``2 _NEAR``): a point's nearest segment has a vertex within ``r = dv +
        L / 2`` of it (``dv`` its nearest vertex's distance, ``L`` the longest segment: every
        point of a segment is within ``L / 2`` of one of its ends), so the segments at its
        ``_NEAR`` nearest vertices (a k-d tree) settle it when the last of those is farther
        than ``r``; the other rows take every segment."""
        x = np.asarray(points, dtype=np.float64)
        m = self.points.shape[0] - 1
        if m <= 2 * _NEAR or len(x) < 8:
            t_out = self._closest_all(x)
        else:
            if self._vertex_tree is None:
                seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
                self._vertex_tree, self._half_segment = cKDTree(self.points), 0.5 * float(seg.max())
            dist, v = self._vertex_tree.query(x, k=_NEAR)
            r = dist[:, 0] * (1.0 + 1e-12) + self._half_segment
            j = np.concatenate((np.maximum(v - 1, 0), np.minimum(v, m - 1)), axis=1)
            t_out, _ = self._closest_of(x, j)
            loose = np.flatnonzero(dist[:, -1] <= r)  # (more vertices within r)
            if loose.size:
                t_out[loose] = self._closest_all(x[loose])
        foot = self.evaluate(t_out)
        return Closest(t=t_out, foot=foot, distance=np.linalg.norm(x - foot, axis=1))

    def _closest_of(self, x: FloatArray, j: np.ndarray) -> tuple[FloatArray, FloatArray]:
        """Nearest points of ``x`` (n, dim) on the segments ``j`` (n, k): parameters (n,) and
        squared distances (n,)."""
        a, d = self.points[j], self.points[j + 1] - self.points[j]  # (n, k, dim)
        rel = x[:, None, :] - a
        u = np.einsum("nkj,nkj->nk", rel, d) / np.einsum("nkj,nkj->nk", d, d)
        u = np.clip(u, 0.0, 1.0)
        diff = rel - u[:, :, None] * d
        dist2 = np.einsum("nkj,nkj->nk", diff, diff)
        best = np.argmin(dist2, axis=1)
        rows = np.arange(len(x))
        jb, ub = j[rows, best], u[rows, best]
        return self._tk[jb] + ub * (self._tk[jb + 1] - self._tk[jb]), dist2[rows, best]

    def _closest_all(self, x: FloatArray) -> FloatArray:
        """Parameters (n,) of the nearest points: every segment (blocks of rows)."""
        a, b = self.points[:-1], self.points[1:]
        d = b - a
        dd = np.einsum("ij,ij->i", d, d)
        t_out = np.empty(len(x))
        for s in range(0, len(x), _CHUNK):
            xs = x[s : s + _CHUNK]
            rel = xs[:, None, :] - a[None, :, :]
            u = np.clip(np.einsum("nmj,mj->nm", rel, d) / dd[None, :], 0.0, 1.0)
            diff = rel - u[:, :, None] * d[None, :, :]
            dist2 = np.einsum("nmj,nmj->nm", diff, diff)
            j = np.argmin(dist2, axis=1)
            uj = u[np.arange(len(xs)), j]
            t_out[s : s + _CHUNK] = self._tk[j] + uj * (self._tk[j + 1] - self._tk[j])
        return t_out

    def closest_in(
        self, points: FloatArray, lo: FloatArray, hi: FloatArray, start: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Exact: the segments that meet ``[lo, hi]`` (n,), each clipped to it, the nearest
        wins (all rows at once; a bracketed Newton would bisect at every vertex)."""
        x = np.asarray(points, dtype=np.float64)
        n, tk, p = len(x), self._tk, self.points
        i0, _ = self._locate(lo)
        i1, _ = self._locate(hi)
        width = int((i1 - i0).max(initial=0)) + 1
        t_best, d_best = np.asarray(lo, dtype=np.float64).copy(), np.full(n, np.inf)
        for k in range(width):  # (a bracket covers few segments: a loop over them)
            j = np.minimum(i0 + k, i1)
            a, b = tk[j], tk[j + 1]
            ua = (np.maximum(lo, a) - a) / (b - a)
            ub = (np.minimum(hi, b) - a) / (b - a)
            d = p[j + 1] - p[j]
            rel = x - p[j]
            u = np.einsum("ij,ij->i", rel, d) / np.einsum("ij,ij->i", d, d)
            u = np.minimum(np.maximum(u, ua), ub)
            r = rel - u[:, None] * d
            dist = np.einsum("ij,ij->i", r, r)
            better = dist < d_best
            t_best = np.where(better, a + u * (b - a), t_best)
            d_best = np.where(better, dist, d_best)
        return t_best, self.evaluate(t_best)
