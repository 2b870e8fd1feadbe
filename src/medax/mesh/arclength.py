"""Points at equal arc length along a curve: the boundary nodes of the ratio grid."""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.arc import Arc
from medax.geometry.curve import Curve
from medax.geometry.line import Line

_PIECES = 16  # Gauss-Legendre pieces per smooth piece of the curve
_GAUSS = np.polynomial.legendre.leggauss(10)


def _length_between(curve: Curve, a: FloatArray, b: FloatArray) -> FloatArray:
    """Arc lengths (n,) of ``curve`` between parameters ``a`` and ``b`` (each (n,)), by
    10-point Gauss-Legendre quadrature of the speed ``|C'(t)|``."""
    x, w = _GAUSS
    half = 0.5 * (b - a)
    t = (half[:, None] * x[None, :] + 0.5 * (a + b)[:, None]).ravel()
    speed = _speed(curve, t).reshape(a.size, x.size)
    return np.asarray(half * (speed @ w))


def _speed(curve: Curve, t: FloatArray) -> FloatArray:
    """``|C'(t)|`` (n,): from the component-row jets where the curve has them."""
    rows = curve.jet_rows(t)
    if rows is None:
        return np.asarray(np.linalg.norm(curve.derivative(t), axis=1))
    dim = rows.shape[0] // 3
    d = rows[dim : 2 * dim]
    return np.asarray(np.sqrt(np.einsum("ij,ij->j", d, d)))


def arclength_at(curve: Curve, t: FloatArray) -> FloatArray:
    """Arc lengths (n,) of ``curve`` from its start to parameters ``t`` (n,, in ``[0, 1]``):
    the same Gauss-Legendre pieces as :func:`arclength_params`."""
    t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0)
    pieces = _PIECES * max(curve.complexity(), 1)
    edges = np.linspace(0.0, 1.0, pieces + 1)
    cum = np.concatenate(([0.0], np.cumsum(_length_between(curve, edges[:-1], edges[1:]))))
    k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, pieces - 1)
    return np.asarray(cum[k] + _length_between(curve, edges[k], t))


def arclength_params(curve: Curve, fractions: FloatArray) -> FloatArray:
    """Parameters ``t`` (n,) where the arc length from the start of ``curve`` is
    ``fractions`` (n,, in ``[0, 1]``) of its length. Lines and arcs: ``t = fractions``
    (constant speed). Other curves: the length on ``16 x complexity()`` Gauss-Legendre pieces,
    then Newton steps on ``s(t) - s`` inside each piece to ``|dt| <= 1e-15``."""
    f = np.asarray(fractions, dtype=np.float64)
    if isinstance(curve, (Line, Arc)):
        return f.copy()
    pieces = _PIECES * max(curve.complexity(), 1)
    edges = np.linspace(0.0, 1.0, pieces + 1)
    cum = np.concatenate(([0.0], np.cumsum(_length_between(curve, edges[:-1], edges[1:]))))
    target = f * cum[-1]
    k = np.clip(np.searchsorted(cum, target, side="right") - 1, 0, pieces - 1)
    lo, hi = edges[k], edges[k + 1]
    rest = target - cum[k]  # arc length still to go inside piece k
    span = np.maximum(cum[k + 1] - cum[k], np.finfo(float).tiny)
    t = lo + (hi - lo) * np.clip(rest / span, 0.0, 1.0)
    inner = (f > 0.0) & (f < 1.0)
    for _ in range(30):
        rows = np.flatnonzero(inner)
        if rows.size == 0:
            break
        s = _length_between(curve, lo[rows], t[rows])
        speed = _speed(curve, t[rows])
        step = (s - rest[rows]) / np.maximum(speed, np.finfo(float).tiny)
        t[rows] = np.clip(t[rows] - step, lo[rows], hi[rows])
        inner[rows] = np.abs(step) > 1e-15
    t[f <= 0.0], t[f >= 1.0] = 0.0, 1.0
    return t
