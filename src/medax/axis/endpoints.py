"""Exact start and end points: the root of the field along a start/end side."""

from __future__ import annotations

import logging

import numpy as np

from medax.axis.field import DistanceField
from medax.errors import TraceError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve

log = logging.getLogger(__name__)
_SCAN = 257  # samples of the side scanned for sign changes


def end_point(field: DistanceField, side: Curve, side_name: str) -> tuple[float, FloatArray]:
    """Parameter ``s`` and point ``side(s)`` (2,) where the field vanishes on ``side``.

    The field changes sign along a start/end side (it is ``> 0`` at the corner on ``A2`` and
    ``< 0`` at the corner on ``A1``); the sign change is bracketed on a scan of the side and
    solved to machine precision with Brent's method. Several sign changes (a side that
    wanders back and forth across the axis) take the one nearest the side's middle.
    """
    s = np.linspace(0.0, 1.0, _SCAN)
    g = field(side.evaluate(s)).g
    sg = np.sign(g)
    zero = np.nonzero(sg == 0.0)[0]
    if zero.size:  # an exact root on a sample
        i = int(zero[np.argmin(np.abs(s[zero] - 0.5))])
        return float(s[i]), side.evaluate(s[i : i + 1])[0]
    change = np.nonzero(sg[:-1] * sg[1:] < 0.0)[0]
    if change.size == 0:
        raise TraceError(
            f"region '{field.region.name}': the axis does not meet {side_name} "
            f"(d1 - d2 keeps one sign along it)"
        )
    if change.size > 1:
        log.warning("%s: %d candidate axis ends; using the middle one", side_name, change.size)
    i = int(change[np.argmin(np.abs(s[change] - 0.5))])

    root = _root_on_side(field, side, float(s[i]), float(s[i + 1]), float(g[i]), float(g[i + 1]))
    return root, side.evaluate(np.array([root]))[0]


def _root_on_side(
    field: DistanceField, side: Curve, a: float, b: float, ga: float, gb: float
) -> float:
    """Root of ``h(t) = g(side(t))`` in the sign-change bracket ``[a, b]``: Newton with the
    exact slope ``h' = grad g . side'``, kept inside the shrinking bracket (bisection when a
    step leaves it); quadratic, so a few field evaluations instead of Brent's ~25."""
    t = a + (b - a) * ga / (ga - gb)  # regula falsi start
    for _ in range(100):
        tt = np.array([t])
        fs = field(side.evaluate(tt))
        h = float(fs.g[0])
        if h == 0.0:
            return t
        if (h < 0.0) == (ga < 0.0):
            a, ga = t, h
        else:
            b, gb = t, h
        slope = float(fs.grad[0] @ side.derivative(tt)[0])
        step = h / slope if slope != 0.0 else np.inf
        if abs(step) <= 4e-16 * max(1.0, abs(t)):  # at round-off: t is the root
            return float(np.clip(t - step, a, b))
        new = t - step
        if not a < new < b:
            new = 0.5 * (a + b)
        if b - a <= 4e-16:
            return new
        t = new
    log.warning("end point on %s: Newton did not settle; bracket %.3g", side, b - a)
    return t
