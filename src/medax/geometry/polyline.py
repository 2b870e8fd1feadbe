"""Polyline, parametrised by normalised arc length."""

from __future__ import annotations

import numpy as np

from medax.errors import CurveError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, Curve

_CHUNK = 4096  # rows per block in the segment-distance table, to bound memory


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
        """Exact: distance to every segment (blocks of rows), the smallest wins."""
        x = np.asarray(points, dtype=np.float64)
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
        foot = self.evaluate(t_out)
        return Closest(t=t_out, foot=foot, distance=np.linalg.norm(x - foot, axis=1))

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
