"""Row-wise helpers on small arrays, with fewer numpy calls than their library forms (the
axis tracer's arrays have 1 - 200 rows: the per-call overhead is the cost)."""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray


def points2d(p: FloatArray) -> FloatArray:
    """``p`` as float64 rows: ``np.atleast_2d`` of a point (dim,) or points (n, dim)."""
    a = np.asarray(p, dtype=np.float64)
    return a if a.ndim >= 2 else a.reshape(1, -1)


def row_norms(v: FloatArray) -> FloatArray:
    """Euclidean norms (n,) of the rows of ``v`` (n, dim): ``np.linalg.norm(v, axis=1)``
    to the last bit (the same products and reduction), without its argument handling."""
    return np.sqrt(np.add.reduce(v * v, axis=1))


def step_norms(v: FloatArray) -> FloatArray:
    """Norms (n - 1,) of the differences of consecutive rows of ``v`` (n, dim)."""
    d = v[1:] - v[:-1]
    return np.sqrt(np.add.reduce(d * d, axis=1))
