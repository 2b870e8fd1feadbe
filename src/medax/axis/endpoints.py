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
    """Parameter ``s`` and point ``side(s)`` (2,) where the field vanishes on ``side``
    (:func:`end_points` for one side)."""
    (s,), (p,) = end_points(field, (side,), (side_name,))
    return s, p


def end_points(
    field: DistanceField, sides: tuple[Curve, ...], names: tuple[str, ...]
) -> tuple[list[float], list[FloatArray]]:
    """Parameters ``s`` and points ``side(s)`` (2,) where the field vanishes on each side,
    all sides scanned and solved together (one field evaluation per step for all).

    The field changes sign along a start/end side (it is ``> 0`` at the corner on ``A2`` and
    ``< 0`` at the corner on ``A1``); the sign change is bracketed on a scan of the side and
    solved to machine precision (:func:`_roots_on_sides`). Several sign changes (a side that
    wanders back and forth across the axis) take the one nearest the side's middle.
    """
    s = np.linspace(0.0, 1.0, _SCAN)
    g_all = field(np.concatenate([side.evaluate(s) for side in sides])).g.reshape(len(sides), -1)
    params: list[float | None] = []
    brackets = []
    for side, name, g in zip(sides, names, g_all, strict=True):
        sg = np.sign(g)
        zero = np.nonzero(sg == 0.0)[0]
        if zero.size:  # an exact root on a sample
            params.append(float(s[int(zero[np.argmin(np.abs(s[zero] - 0.5))])]))
            continue
        change = np.nonzero(sg[:-1] * sg[1:] < 0.0)[0]
        if change.size == 0:
            raise TraceError(
                f"region '{field.region.name}': the axis does not meet {name} "
                f"(d1 - d2 keeps one sign along it)"
            )
        if change.size > 1:
            log.warning("%s: %d candidate axis ends; using the middle one", name, change.size)
        i = int(change[np.argmin(np.abs(s[change] - 0.5))])
        params.append(None)
        brackets.append((side, float(s[i]), float(s[i + 1]), float(g[i]), float(g[i + 1])))
    roots = iter(_roots_on_sides(field, brackets)) if brackets else iter(())
    out = [p if p is not None else float(next(roots)) for p in params]
    pts = [side.evaluate(np.array([t]))[0] for side, t in zip(sides, out, strict=True)]
    return out, pts


def _roots_on_sides(
    field: DistanceField, brackets: list[tuple[Curve, float, float, float, float]]
) -> FloatArray:
    """Roots (k,) of ``h(t) = g(side(t))`` in the sign-change brackets ``(side, a, b, g(a),
    g(b))``: Newton with the exact slope ``h' = grad g . side'``, kept inside the shrinking
    bracket (bisection when a step leaves it); quadratic, so a few field evaluations
    instead of Brent's ~25, one for all brackets per step."""
    sides = [b[0] for b in brackets]
    a, b, ga, gb = (np.array([br[j] for br in brackets]) for j in (1, 2, 3, 4))
    t = a + (b - a) * ga / (ga - gb)  # regula falsi start
    done = np.zeros(len(t), dtype=bool)
    for _ in range(100):
        rows = np.flatnonzero(~done)
        if rows.size == 0:
            return t
        tt = [t[r : r + 1] for r in rows]
        fs = field(np.concatenate([sides[r].evaluate(x) for r, x in zip(rows, tt, strict=True)]))
        der = np.concatenate([sides[r].derivative(x) for r, x in zip(rows, tt, strict=True)])
        slope = np.einsum("ij,ij->i", fs.grad, der)
        for j, r in enumerate(rows.tolist()):  # two sides: scalar bracket logic per root
            h = float(fs.g[j])
            if h == 0.0:
                done[r] = True
                continue
            if (h < 0.0) == (ga[r] < 0.0):
                a[r], ga[r] = t[r], h
            else:
                b[r], gb[r] = t[r], h
            step = h / slope[j] if slope[j] != 0.0 else np.inf
            if abs(step) <= 4e-16 * max(1.0, abs(t[r])):  # at round-off: t is the root
                t[r], done[r] = float(np.clip(t[r] - step, a[r], b[r])), True
                continue
            new = t[r] - step
            if not a[r] < new < b[r]:
                new = 0.5 * (a[r] + b[r])
            t[r] = new
            done[r] = b[r] - a[r] <= 4e-16
    for k in np.flatnonzero(~done).tolist():
        log.warning("end point on %s: Newton did not settle; bracket %.3g", sides[k], b[k] - a[k])
    return t
