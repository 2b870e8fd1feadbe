"""Exact start and end points: the root of the field along a start/end side."""

from __future__ import annotations

import logging

import numpy as np
from scipy.optimize import brentq

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

    def h(t: float) -> float:
        return float(field(side.evaluate(np.array([t]))).g[0])

    root = float(brentq(h, s[i], s[i + 1], xtol=1e-17, rtol=8.9e-16, maxiter=200))
    return root, side.evaluate(np.array([root]))[0]
