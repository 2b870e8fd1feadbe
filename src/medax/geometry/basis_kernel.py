"""Compiled (numba) B-spline basis: values and first derivatives of the non-zero basis
functions by the Cox-de Boor recursion, for the high-degree surfaces whose power basis
would lose digits (a degree-13 rolling-ball blend). Compiled with ``cache=True`` like the
kernels of :mod:`medax.geometry.kernels`, which announces and warms it up with them.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from medax.geometry._types import FloatArray


@njit(cache=True, error_model="numpy")
def basis_rows(kn: FloatArray, p: int, t: FloatArray, span: np.ndarray):  # type: ignore[no-untyped-def]
    """Values and first derivatives (n, p+1) of the non-zero basis functions
    ``N_{s-p..s}`` at ``t`` (n,) in spans ``span`` (n,) of the full knot vector ``kn``:
    the Cox-de Boor recursion (The NURBS Book, A2.2 and A2.3) point by point, in the order
    of operations of the vectorised recursion it replaces (its results to the last bit)."""
    n = t.size
    values = np.empty((n, p + 1))
    ders = np.zeros((n, p + 1))
    left = np.zeros(p + 1)
    right = np.zeros(p + 1)
    ndu = np.zeros((p + 1, p + 1))
    for i in range(n):
        s, u = span[i], t[i]
        ndu[0, 0] = 1.0
        for j in range(1, p + 1):
            left[j] = u - kn[s + 1 - j]
            right[j] = kn[s + j] - u
            saved = 0.0
            for r in range(j):
                ndu[j, r] = right[r + 1] + left[j - r]  # knot differences
                denom = ndu[j, r]
                temp = ndu[r, j - 1] / denom if denom != 0.0 else 0.0
                ndu[r, j] = saved + right[r + 1] * temp
                saved = left[j - r] * temp
            ndu[j, j] = saved
        for r in range(p + 1):
            values[i, r] = ndu[r, p]
        if p > 0:  # N'_{k,p} = p (N_{k,p-1} / (u_{k+p} - u_k) - N_{k+1,p-1} / (...))
            for r in range(p + 1):
                k = s - p + r
                acc = 0.0
                if r >= 1:
                    d = kn[k + p] - kn[k]
                    acc += ndu[r - 1, p - 1] / d if d != 0.0 else 0.0
                if r <= p - 1:
                    d = kn[k + p + 1] - kn[k + 1]
                    acc -= ndu[r, p - 1] / d if d != 0.0 else 0.0
                ders[i, r] = p * acc
    return values, ders
