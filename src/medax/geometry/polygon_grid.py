"""Which points of a tensor grid lie inside a polygon, by scanlines.

The fitted merge labels every sample of its fit grid (10^5 - 10^6 points) with the member
face above it. A general point-in-polygon test (``matplotlib.path.Path.contains_points``)
costs points x vertices; on a grid one column's crossings with the polygon's edges answer
all its points at once: a point is inside when an odd number of crossings lie below it
(even-odd rule, as ``contains_points``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from medax.geometry._types import FloatArray


def inside_grid(xs: FloatArray, ys: FloatArray, polygon: FloatArray) -> NDArray[np.bool_]:
    """Inside mask (nx, ny) of the grid points ``(xs[i], ys[j])`` for the closed polygon
    ``polygon`` (m, 2) (the last vertex joins the first). Points on an edge may fall on
    either side (as in any floating-point point-in-polygon test)."""
    xs = np.asarray(xs, dtype=np.float64)
    ys = np.asarray(ys, dtype=np.float64)
    a = np.asarray(polygon, dtype=np.float64)
    b = np.roll(a, -1, axis=0)
    steep = a[:, 0] != b[:, 0]  # vertical edges never cross a column
    a, b = a[steep], b[steep]
    xm = xs[:, None]
    # half-open in x, so a column through a vertex counts each crossing once
    spans = ((a[:, 0] <= xm) & (xm < b[:, 0])) | ((b[:, 0] <= xm) & (xm < a[:, 0]))
    with np.errstate(invalid="ignore", divide="ignore"):
        yc = a[:, 1] + (xm - a[:, 0]) * ((b[:, 1] - a[:, 1]) / (b[:, 0] - a[:, 0]))
    yc = np.where(spans, yc, np.inf)
    yc.sort(axis=1)
    return (_ranks(yc, ys) % 2) == 1


def _ranks(yc: FloatArray, ys: FloatArray) -> NDArray[np.int64]:
    """(nx, ny): how many of column ``i``'s crossings ``yc[i]`` (sorted, ``inf`` past the
    last) lie below ``ys[j]``. One sorted search for all columns: their crossings laid end
    to end, each column's values shifted past the previous column's (a point within
    rounding of the shift of a crossing may fall on either side, as on an edge)."""
    finite = np.isfinite(yc)
    if not finite.any() or ys.size == 0:
        return np.zeros((yc.shape[0], ys.size), dtype=np.int64)
    lo = min(float(ys.min()), float(yc[finite].min()))
    hi = max(float(ys.max()), float(yc[finite].max()))
    step = 2.0 * (hi - lo) if hi > lo else 1.0  # past any column's range, at its scale
    shift = np.arange(yc.shape[0], dtype=np.float64)[:, None] * step
    keys = (yc - lo + shift)[finite]  # row by row: sorted
    count = finite.sum(axis=1)
    start = np.cumsum(count) - count
    at = np.searchsorted(keys, (ys[None, :] - lo + shift).ravel(), side="left")
    return at.reshape(yc.shape[0], ys.size) - start[:, None]
