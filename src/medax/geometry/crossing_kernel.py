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

from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray

#: segments per bounding box
CHUNK = 16


@njit(**HELPER)
def _cross(a: FloatArray, i: int, b: FloatArray, j: int, tol: float) -> bool:
    """Whether segment ``a[i] a[i+1]`` properly crosses ``b[j] b[j+1]``: the products of
    the orientations ``(q - p) x (r - p)`` of each one's ends against the other's line are
    below ``-tol``."""
    a0x, a0y, a1x, a1y = a[i, 0], a[i, 1], a[i + 1, 0], a[i + 1, 1]
    b0x, b0y, b1x, b1y = b[j, 0], b[j, 1], b[j + 1, 0], b[j + 1, 1]
    o1 = (a1x - a0x) * (b0y - a0y) - (a1y - a0y) * (b0x - a0x)
    o2 = (a1x - a0x) * (b1y - a0y) - (a1y - a0y) * (b1x - a0x)
    o3 = (b1x - b0x) * (a0y - b0y) - (b1y - b0y) * (a0x - b0x)
    o4 = (b1x - b0x) * (a1y - b0y) - (b1y - b0y) * (a1x - b0x)
    return o1 * o2 < -tol and o3 * o4 < -tol


@njit(**HELPER)
def _boxes(p: FloatArray) -> FloatArray:
    """Bounding boxes (chunks, 4: lo x, lo y, hi x, hi y) of the chunks of segments of
    polyline ``p`` (n, 2), n >= 2: chunk ``c`` holds segments ``c CHUNK ..`` (its points
    up to ``(c + 1) CHUNK``, or the last)."""
    nseg = p.shape[0] - 1
    nc = (nseg + CHUNK - 1) // CHUNK
    box = np.empty((nc, 4))
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
            box[c, d] = mn
            box[c, 2 + d] = mx
    return box


@njit(**KERNEL)
def crossing(a: FloatArray, b: FloatArray, eps: float, itself: bool) -> bool:
    """Whether polylines ``a`` (n, 2) and ``b`` (m, 2) properly cross (to ``eps``), or with
    ``itself`` (``b`` is ``a``) whether ``a`` crosses itself: segments that are not
    neighbours. Chunk pairs whose boxes do not overlap (to ``eps``) are skipped."""
    if a.shape[0] < (4 if itself else 2) or b.shape[0] < 2:
        return False
    ba = _boxes(a)
    bb = ba if itself else _boxes(b)
    na, nb = a.shape[0] - 1, b.shape[0] - 1
    tol = eps * eps
    for ci in range(ba.shape[0]):
        for cj in range(ci if itself else 0, bb.shape[0]):
            if not (
                ba[ci, 0] <= bb[cj, 2] + eps
                and bb[cj, 0] <= ba[ci, 2] + eps
                and ba[ci, 1] <= bb[cj, 3] + eps
                and bb[cj, 1] <= ba[ci, 3] + eps
            ):
                continue
            for i in range(ci * CHUNK, min((ci + 1) * CHUNK, na)):
                j0 = max(cj * CHUNK, i + 2) if itself else cj * CHUNK
                for j in range(j0, min((cj + 1) * CHUNK, nb)):
                    if _cross(a, i, b, j, tol):
                        return True
    return False


def polylines_cross(a: FloatArray, b: FloatArray, eps: float) -> bool:
    """Whether polylines ``a`` (n, 2) and ``b`` (m, 2) properly cross (to ``eps``)."""
    return bool(crossing(np.ascontiguousarray(a), np.ascontiguousarray(b), float(eps), False))


def self_crossing(p: FloatArray, eps: float) -> bool:
    """Whether polyline ``p`` (n, 2) properly crosses itself (to ``eps``)."""
    q = np.ascontiguousarray(p)
    return bool(crossing(q, q, float(eps), True))
