"""Circular arc in the plane."""

from __future__ import annotations

import math

import numpy as np

from medax.errors import CurveError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, Curve


def _wrap(a: FloatArray | float) -> FloatArray:
    """Angles wrapped into ``(-pi, pi]``."""
    return np.asarray(np.pi - np.mod(np.pi - np.asarray(a), 2.0 * np.pi))


class Arc(Curve):
    """``C(t) = c + r (cos(a0 + s t), sin(a0 + s t))``: centre ``c`` (2,), radius ``r``,
    start angle ``a0`` and signed sweep ``s`` (radians, ``|s| < 2 pi``)."""

    def __init__(self, center: FloatArray, radius: float, a0: float, sweep: float) -> None:
        if not radius > 0.0 or not math.isfinite(radius):
            raise CurveError(f"arc radius must be positive and finite, got {radius}")
        if not 0.0 < abs(sweep) < 2.0 * math.pi + 1e-12:
            raise CurveError(f"arc sweep must be in (0, 2 pi), got {sweep}")
        self.center = np.asarray(center, dtype=np.float64)
        self.radius = float(radius)
        self.a0 = float(a0)
        self.sweep = float(sweep)

    @classmethod
    def from_sagitta(cls, p0: FloatArray, p1: FloatArray, sagitta: float) -> Arc:
        """Arc from ``p0`` to ``p1`` whose apex is ``sagitta`` from the chord midpoint,
        to the right of the travel direction when positive (outward for a CCW region)."""
        p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
        chord = p1 - p0
        c = float(np.linalg.norm(chord))
        if c == 0.0:
            raise CurveError("arc has coincident end points")
        if sagitta == 0.0 or not math.isfinite(sagitta):
            raise CurveError(f"arc sagitta must be non-zero and finite, got {sagitta}")
        right = np.array([chord[1], -chord[0]]) / c
        h = float(sagitta)
        r = (0.25 * c * c + h * h) / (2.0 * abs(h))
        apex = 0.5 * (p0 + p1) + h * right
        center = apex - math.copysign(r, h) * right
        a0 = math.atan2(p0[1] - center[1], p0[0] - center[0])
        a_apex = math.atan2(apex[1] - center[1], apex[0] - center[0])
        sweep = 2.0 * float(_wrap(a_apex - a0))
        return cls(center, r, a0, sweep)

    @classmethod
    def from_center(
        cls, p0: FloatArray, p1: FloatArray, center: FloatArray, radius: float, rtol: float = 1e-7
    ) -> Arc:
        """Arc about ``center`` from ``p0`` to ``p1``, the shorter way round."""
        p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
        center = np.asarray(center, dtype=np.float64)
        for name, p in (("start", p0), ("end", p1)):
            r = float(np.linalg.norm(p - center))
            if abs(r - radius) > rtol * max(radius, 1.0):
                raise CurveError(
                    f"arc {name} point {p.tolist()} is {r:.9g} from the centre, not the radius "
                    f"{radius:.9g}"
                )
        a0 = math.atan2(p0[1] - center[1], p0[0] - center[0])
        a1 = math.atan2(p1[1] - center[1], p1[0] - center[0])
        return cls(center, radius, a0, float(_wrap(a1 - a0)))

    @property
    def dim(self) -> int:
        return 2

    def complexity(self) -> int:
        return max(1, int(abs(self.sweep) / (math.pi / 4)) + 1)

    def evaluate(self, t: FloatArray) -> FloatArray:
        a = self.a0 + self.sweep * np.asarray(t, dtype=np.float64)
        return self.center[None, :] + self.radius * np.column_stack((np.cos(a), np.sin(a)))

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        a = self.a0 + self.sweep * np.asarray(t, dtype=np.float64)
        s, r = self.sweep, self.radius
        if order == 1:
            return r * s * np.column_stack((-np.sin(a), np.cos(a)))
        return -r * s * s * np.column_stack((np.cos(a), np.sin(a)))

    def reversed(self) -> Arc:
        return Arc(self.center, self.radius, self.a0 + self.sweep, -self.sweep)

    def transformed(self, offset: FloatArray, scale: float) -> Arc:
        return Arc((self.center - offset) / scale, self.radius / scale, self.a0, self.sweep)

    def length(self, n: int = 0) -> float:
        return self.radius * abs(self.sweep)

    def closest(self, points: FloatArray) -> Closest:
        """Closed form: the polar angle of the point, clamped to the arc, or an end."""
        x = np.asarray(points, dtype=np.float64)
        v = x - self.center
        rho = np.hypot(v[:, 0], v[:, 1])
        ang = np.arctan2(v[:, 1], v[:, 0])
        t = np.mod((ang - self.a0) * np.sign(self.sweep), 2.0 * np.pi) / abs(self.sweep)
        # inside the arc's angle: the radial foot, at distance |rho - r| (no trigonometry)
        scale = self.radius / np.maximum(rho, np.finfo(float).tiny)
        foot = self.center + v * scale[:, None]
        dist = np.abs(rho - self.radius)
        centre = rho == 0.0  # every point of the arc is nearest: take the one at t
        if np.any(centre):
            foot[centre] = self.evaluate(t[centre])
        out = np.flatnonzero(t > 1.0)
        if out.size:  # beyond the ends: the nearer end
            pe = self.evaluate(np.array([0.0, 1.0]))
            xo = x[out]
            d0 = np.hypot(*(xo - pe[0]).T)
            d1 = np.hypot(*(xo - pe[1]).T)
            end = (d1 < d0).astype(np.int64)
            t[out] = end.astype(np.float64)
            foot[out] = pe[end]
            dist[out] = np.minimum(d0, d1)
        return Closest(t=t, foot=foot, distance=dist)
