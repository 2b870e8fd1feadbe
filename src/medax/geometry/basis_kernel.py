"""Compiled (numba) B-spline basis: values and first derivatives of the non-zero basis
functions by the Cox-de Boor recursion, for the high-degree surfaces whose power basis
would lose digits (a degree-13 rolling-ball blend). Compiled with ``cache=True`` like the
kernels of :mod:`medax.geometry.kernels`, which announces and warms it up with them.
Per point: :func:`span_basis_rows` loops over points in Python's callers
(:class:`medax.geometry.surfaces.SpanBasis`), :mod:`medax.geometry.nurbs_kernel` calls
:func:`basis_at` in its surface jets.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray


@njit(**HELPER)
def basis_point(  # type: ignore[no-untyped-def]
    kn: FloatArray,
    p: int,
    u: float,
    s: int,
    ndu: FloatArray,
    left: FloatArray,
    right: FloatArray,
    values: FloatArray,
    ders: FloatArray,
):
    """Values and first derivatives (p+1,) of ``N_{s-p..s}`` at ``u`` into ``values`` and
    ``ders``: the Cox-de Boor recursion (The NURBS Book, A2.2 and A2.3), in the order of
    operations of the vectorised recursion it replaced (its results to the last bit).
    ``ndu`` (p+1, p+1), ``left`` and ``right`` (p+1,) are work arrays."""
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
        values[r] = ndu[r, p]
        ders[r] = 0.0
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
            ders[r] = p * acc


@njit(**HELPER)
def find_span(kn: FloatArray, p: int, t: float) -> int:
    """The span ``s`` of ``t``: the last knot index with ``kn[s] <= t``, kept within the
    domain's spans ``p .. len(kn) - p - 2`` (``np.searchsorted(kn, t, "right") - 1``
    clipped, by bisection)."""
    a, b = p, kn.size - 2 - p
    if t >= kn[b]:
        return b
    if not t >= kn[a + 1]:
        return a
    a += 1  # kn[a] <= t < kn[b]
    while b - a > 1:
        m = (a + b) // 2
        if kn[m] <= t:
            a = m
        else:
            b = m
    return a


@njit(**HELPER, inline="always")
def basis_at(  # type: ignore[no-untyped-def]
    kn: FloatArray, coef: FloatArray, p: int, extrapolate: bool, t: float, ndu: FloatArray,
    left: FloatArray, right: FloatArray, values: FloatArray, ders: FloatArray,
) -> int:  # fmt: skip
    """Span of ``t`` and the values and first derivatives (p+1,) of its non-zero basis
    functions into ``values``, ``ders``, for the knots ``kn`` of degree ``p`` (see
    :class:`medax.geometry.surfaces.SpanBasis`): ``t`` clamped to the domain
    ``[kn[p], kn[-p-1]]`` unless ``extrapolate``; the span's polynomials ``coef[s]`` (p+1
    functions, p+1 powers of the span's local coordinate; ``coef`` (spans, p+1, p+1)), or
    where ``coef`` is empty (no spans) :func:`basis_point`."""
    if not extrapolate:
        t = min(max(t, kn[p]), kn[kn.size - 1 - p])
    s = find_span(kn, p, t)
    if coef.shape[0] == 0:
        basis_point(kn, p, t, s, ndu, left, right, values, ders)
        return s
    width = kn[s + 1] - kn[s]
    tau = (t - kn[s]) / width
    for i in range(p + 1):
        val, der, pw, dpw = coef[s, i, 0], 0.0, 1.0, 0.0
        for j in range(1, p + 1):  # dpw = j tau^(j-1), pw = tau^j
            dpw = pw * j
            pw = pw * tau
            val += coef[s, i, j] * pw
            der += coef[s, i, j] * dpw
        values[i] = val
        ders[i] = der / width
    return s


@njit(**KERNEL)
def span_basis_rows(kn: FloatArray, coef: FloatArray, p: int, extrapolate: bool, t: FloatArray):  # type: ignore[no-untyped-def]
    """Spans (n,), values and first derivatives (n, p+1) at ``t`` (n,): :func:`basis_at`
    point by point."""
    n = t.size
    span = np.empty(n, dtype=np.int64)
    values = np.empty((n, p + 1))
    ders = np.empty((n, p + 1))
    ndu = np.zeros((p + 1, p + 1))
    left = np.zeros(p + 1)
    right = np.zeros(p + 1)
    for i in range(n):
        span[i] = basis_at(kn, coef, p, extrapolate, t[i], ndu, left, right, values[i], ders[i])
    return span, values, ders
