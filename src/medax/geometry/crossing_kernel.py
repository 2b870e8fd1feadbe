"""Compiled (numba) crossing tests of sampled polylines: the region's side checks.

Segments are grouped in chunks of :data:`CHUNK` consecutive ones; only chunks whose
bounding boxes overlap (to ``eps``) are compared segment by segment, and two segments cross
properly where each one's ends lie strictly on opposite sides of the other's line
(orientation products below ``-eps^2``). The orientation is ``(q - p) x (r - p)`` in the
order of operations of the numpy tables it replaces, so the answers are theirs to the last
bit. Compiled with ``cache=True`` like :mod:`medax.geometry.kernels`, which announces and
warms it up with the others.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from medax.geometry._types import FloatArray

#: segments per bounding box
CHUNK = 16


@njit(cache=True, error_model="numpy")
def _orient(px: float, py: float, qx: float, qy: float, rx: float, ry: float) -> float:
    """``(q - p) x (r - p)``: > 0 where ``r`` is left of the line from ``p`` to ``q``."""
    return (qx - px) * (ry - py) - (qy - py) * (rx - px)


@njit(cache=True, error_model="numpy")
def _cross(a: FloatArray, i: int, b: FloatArray, j: int, tol: float) -> bool:
    """Whether segment ``a[i] a[i+1]`` properly crosses ``b[j] b[j+1]`` (products of
    orientations below ``-tol``)."""
    a0x, a0y, a1x, a1y = a[i, 0], a[i, 1], a[i + 1, 0], a[i + 1, 1]
    b0x, b0y, b1x, b1y = b[j, 0], b[j, 1], b[j + 1, 0], b[j + 1, 1]
    o1 = _orient(a0x, a0y, a1x, a1y, b0x, b0y)
    o2 = _orient(a0x, a0y, a1x, a1y, b1x, b1y)
    o3 = _orient(b0x, b0y, b1x, b1y, a0x, a0y)
    o4 = _orient(b0x, b0y, b1x, b1y, a1x, a1y)
    return o1 * o2 < -tol and o3 * o4 < -tol


@njit(cache=True, error_model="numpy")
def _boxes(p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Bounding boxes lo, hi (chunks, 2) of the chunks of segments of polyline ``p``
    (n, 2), n >= 2: chunk ``c`` holds segments ``c CHUNK ..`` (its points up to
    ``(c + 1) CHUNK``, or the last)."""
    nseg = p.shape[0] - 1
    nc = (nseg + CHUNK - 1) // CHUNK
    lo = np.empty((nc, 2))
    hi = np.empty((nc, 2))
    for c in range(nc):
        first = c * CHUNK
        last = min(first + CHUNK, nseg)  # the chunk's last point
        for d in range(2):
            mn = p[first, d]
            mx = p[first, d]
            for k in range(first + 1, last + 1):
                v = p[k, d]
                if v < mn:
                    mn = v
                if v > mx:
                    mx = v
            lo[c, d] = mn
            hi[c, d] = mx
    return lo, hi


@njit(cache=True, error_model="numpy")
def _overlap(
    alo: FloatArray, ahi: FloatArray, i: int, blo: FloatArray, bhi: FloatArray, j: int, eps: float
) -> bool:
    """Whether box ``i`` of ``a`` and box ``j`` of ``b`` overlap to ``eps``."""
    for d in range(2):
        if not (alo[i, d] <= bhi[j, d] + eps and blo[j, d] <= ahi[i, d] + eps):
            return False
    return True


@njit(cache=True, error_model="numpy")
def polylines_cross(a: FloatArray, b: FloatArray, eps: float) -> bool:
    """Whether polylines ``a`` (n, 2) and ``b`` (m, 2) properly cross (to ``eps``)."""
    if a.shape[0] < 2 or b.shape[0] < 2:
        return False
    alo, ahi = _boxes(a)
    blo, bhi = _boxes(b)
    na, nb = a.shape[0] - 1, b.shape[0] - 1
    tol = eps * eps
    for ci in range(alo.shape[0]):
        for cj in range(blo.shape[0]):
            if not _overlap(alo, ahi, ci, blo, bhi, cj, eps):
                continue
            for i in range(ci * CHUNK, min((ci + 1) * CHUNK, na)):
                for j in range(cj * CHUNK, min((cj + 1) * CHUNK, nb)):
                    if _cross(a, i, b, j, tol):
                        return True
    return False


@njit(cache=True, error_model="numpy")
def self_crossing(p: FloatArray, eps: float) -> bool:
    """Whether polyline ``p`` (n, 2) properly crosses itself: segments that are not
    neighbours (to ``eps``)."""
    if p.shape[0] < 4:
        return False
    lo, hi = _boxes(p)
    ns = p.shape[0] - 1
    tol = eps * eps
    for ci in range(lo.shape[0]):
        for cj in range(ci, lo.shape[0]):
            if not _overlap(lo, hi, ci, lo, hi, cj, eps):
                continue
            for i in range(ci * CHUNK, min((ci + 1) * CHUNK, ns)):
                for j in range(max(cj * CHUNK, i + 2), min((cj + 1) * CHUNK, ns)):
                    if _cross(p, i, p, j, tol):
                        return True
    return False
