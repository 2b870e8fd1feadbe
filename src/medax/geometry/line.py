"""Straight segment."""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, Curve


class Line(Curve):
    """Segment ``C(t) = a + t (b - a)``; ``a``, ``b`` of shape ``(dim,)``."""

    def __init__(self, a: FloatArray, b: FloatArray) -> None:
        self.a = np.asarray(a, dtype=np.float64)
        self.b = np.asarray(b, dtype=np.float64)
        self._d = self.b - self.a

    @property
    def dim(self) -> int:
        return int(self.a.size)

    def evaluate(self, t: FloatArray) -> FloatArray:
        t = np.asarray(t, dtype=np.float64)
        return self.a[None, :] + t[:, None] * self._d[None, :]

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        t = np.asarray(t, dtype=np.float64)
        d = self._d if order == 1 else np.zeros_like(self._d)
        return np.broadcast_to(d, (t.size, self.dim)).copy()

    def reversed(self) -> Line:
        return Line(self.b, self.a)

    def transformed(self, offset: FloatArray, scale: float) -> Line:
        return Line((self.a - offset) / scale, (self.b - offset) / scale)

    def length(self, n: int = 0) -> float:
        return float(np.linalg.norm(self._d))

    def closest(self, points: FloatArray) -> Closest:
        """Closed form: project onto the segment and clamp to its ends."""
        x = np.asarray(points, dtype=np.float64)
        dd = float(self._d @ self._d)
        if dd > 0:
            t = np.minimum(np.maximum(((x - self.a) @ self._d) / dd, 0.0), 1.0)
        else:
            t = np.zeros(len(x))
        foot = self.a + t[:, None] * self._d
        r = x - foot
        dist = np.hypot(r[:, 0], r[:, 1]) if r.shape[1] == 2 else np.linalg.norm(r, axis=1)
        return Closest(t=t, foot=foot, distance=dist)
