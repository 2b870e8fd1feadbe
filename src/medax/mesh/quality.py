"""Verdict quality metrics of linear quads, vectorised over all quads.

Definitions follow the Verdict library (Stimpson, Ernst, Knupp, Pébay, Thompson, *The Verdict
Geometric Quality Library*, SAND2007-1751), for a quad ``P0 P1 P2 P3`` with edges
``L0 = P1 - P0, L1 = P2 - P1, L2 = P3 - P2, L3 = P0 - P3`` and principal axes
``X1 = P1 + P2 - P3 - P0``, ``X2 = P2 + P3 - P0 - P1``:

- corner area ``a_k = n . (L_{k-1} x L_k)`` (``n`` = +z for planar quads, the unit normal
  ``X1 x X2`` for quads in space);
- scaled Jacobian ``min_k a_k / (|L_{k-1}| |L_k|)`` in [-1, 1] (1 for a rectangle, < 0 inverted);
- aspect ratio ``max|L| * sum|L| / (2 (|L0 x L1| + |L2 x L3|))`` in [1, inf);
- skew ``|X1 . X2| / (|X1| |X2|)`` in [0, 1];
- minimum and maximum interior angle in degrees; the maximum is ``360 - max`` when a corner
  area is negative (a reflex or inverted corner), as Verdict does.

Degenerate quads (an edge of zero length) get scaled Jacobian 0, aspect ratio inf.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from medax.errors import MeshError
from medax.geometry._types import FloatArray, IntArray

METRICS = ("scaled_jacobian", "aspect_ratio", "skew", "min_angle", "max_angle")
"""The metrics computed, in the order of [QuadQuality][medax.mesh.quality.QuadQuality]'s
fields."""
POOR_SCALED_JACOBIAN = 0.5
"""A quad with scaled Jacobian below this counts as poor in the summary."""


@dataclass(frozen=True)
class QuadQuality:
    """Verdict metrics per quad, each of shape ``(m,)``.

    Attributes
    ----------
    scaled_jacobian : ndarray
        In [-1, 1]: 1 for a rectangle, < 0 inverted.
    aspect_ratio : ndarray
        In [1, inf).
    skew : ndarray
        In [0, 1].
    min_angle, max_angle : ndarray
        Interior angles (degrees).
    """

    scaled_jacobian: FloatArray
    aspect_ratio: FloatArray
    skew: FloatArray
    min_angle: FloatArray
    max_angle: FloatArray

    def as_dict(self) -> dict[str, FloatArray]:
        """The metrics by name (for cell data)."""
        return {name: getattr(self, name) for name in METRICS}

    def summary(self) -> dict[str, Any]:
        """Summary statistics, see [summarize][medax.mesh.quality.summarize]."""
        return summarize(self)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross products of (..., 3) vectors, or z-components (...,) for (..., 2) vectors."""
    if a.shape[-1] == 2:
        return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return np.cross(a, b)


def _corners(points: FloatArray, quads: IntArray) -> FloatArray:
    pts = np.asarray(points, dtype=np.float64)
    q = np.asarray(quads)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise MeshError(f"quality: points must be (n, 2|3), got shape {pts.shape}")
    if q.ndim != 2 or q.shape[1] != 4:
        raise MeshError(f"quality: quads must be (m, 4), got shape {q.shape}")
    if q.size and (q.min() < 0 or q.max() >= pts.shape[0]):
        raise MeshError(f"quality: quad node index out of range 0..{pts.shape[0] - 1}")
    return pts[q]  # (m, 4, dim)


def quad_quality(points: FloatArray, quads: IntArray) -> QuadQuality:
    """Measure the Verdict quality metrics of quads, all at once.

    Parameters
    ----------
    points : ndarray
        Nodes (n, 2) or (n, 3).
    quads : ndarray
        Node indices (m, 4) into ``points``.

    Returns
    -------
    QuadQuality
        The metrics per quad ([QuadQuality][medax.mesh.quality.QuadQuality]).

    Raises
    ------
    MeshError
        Arrays of the wrong shape, or a node index out of range.
    """
    p = _corners(points, quads)
    edges = np.roll(p, -1, axis=1) - p  # L_k = P_{k+1} - P_k, (m, 4, dim)
    prev = np.roll(edges, 1, axis=1)  # L_{k-1}
    length = np.linalg.norm(edges, axis=2)  # (m, 4)
    x1 = p[:, 1] + p[:, 2] - p[:, 3] - p[:, 0]
    x2 = p[:, 2] + p[:, 3] - p[:, 0] - p[:, 1]
    corner = _cross(prev, edges)  # (m, 4) planar, (m, 4, 3) in space
    if p.shape[2] == 3:
        normal = np.cross(x1, x2)
        nn = np.linalg.norm(normal, axis=1, keepdims=True)
        normal = np.divide(normal, nn, out=np.zeros_like(normal), where=nn > 0)
        area = np.einsum("mkd,md->mk", corner, normal)
        cross_len = np.linalg.norm(corner, axis=2)
    else:
        area = corner
        cross_len = np.abs(corner)
    degenerate = np.any(length <= np.finfo(float).tiny, axis=1)
    lprev = np.roll(length, 1, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        sj = np.min(area / (lprev * length), axis=1)
        denom = cross_len[:, 1] + cross_len[:, 3]  # |L0 x L1| + |L2 x L3|
        ar = 0.5 * length.max(axis=1) * length.sum(axis=1) / denom
        n1, n2 = np.linalg.norm(x1, axis=1), np.linalg.norm(x2, axis=1)
        skew = np.abs(np.einsum("md,md->m", x1, x2)) / (n1 * n2)
        cosang = -np.einsum("mkd,mkd->mk", prev, edges) / (lprev * length)
    sj = np.where(degenerate, 0.0, sj)
    ar = np.where(degenerate | ~(denom > 0), np.inf, ar)
    skew = np.where((n1 > 0) & (n2 > 0), skew, 0.0)
    ang = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
    amin = np.where(degenerate, 360.0, ang.min(axis=1))
    amax = ang.max(axis=1)
    amax = np.where(np.any(area < 0.0, axis=1), 360.0 - amax, amax)
    amax = np.where(degenerate, 0.0, amax)
    return QuadQuality(sj, ar, skew, amin, amax)


def summarize(q: QuadQuality) -> dict[str, Any]:
    """Summarise per-quad metrics over the finite values.

    Parameters
    ----------
    q : QuadQuality
        The metrics per quad.

    Returns
    -------
    dict
        For each metric: ``min``, ``p5`` (5th percentile), ``mean``, ``p95``, ``max`` (NaN
        when no value is finite); plus ``n_quads``, ``n_inverted`` (scaled Jacobian <= 0)
        and ``n_sj_below_0_5`` (scaled Jacobian <
        [POOR_SCALED_JACOBIAN][medax.mesh.quality.POOR_SCALED_JACOBIAN]). Plain Python floats
        and ints (JSON-ready).
    """
    out: dict[str, Any] = {"n_quads": int(q.scaled_jacobian.size)}
    for name, values in q.as_dict().items():
        v = values[np.isfinite(values)]
        if v.size == 0:
            out[name] = dict.fromkeys(("min", "p5", "mean", "p95", "max"), float("nan"))
            continue
        p5, p95 = np.percentile(v, [5.0, 95.0])
        out[name] = {
            "min": float(v.min()),
            "p5": float(p5),
            "mean": float(v.mean()),
            "p95": float(p95),
            "max": float(v.max()),
        }
    sj = q.scaled_jacobian
    out["n_inverted"] = int(np.count_nonzero(sj <= 0.0))
    out["n_sj_below_0_5"] = int(np.count_nonzero(sj < POOR_SCALED_JACOBIAN))
    return out
