"""Compiled (numba) primitives of the polynomial jet tables (B-splines in the power basis,
several curves stacked): the span of a stacked parameter and one piece's jet, shared by
:mod:`medax.geometry.kernels` and :mod:`medax.geometry.track_kernel`."""

from __future__ import annotations

from numba import njit

from medax.geometry._jit import HELPER
from medax.geometry._types import FloatArray


@njit(**HELPER)
def table_span(inner: FloatArray, u: float) -> int:
    """The span of stacked parameter ``u``: the number of ``inner`` breaks ``<= u`` (binary
    search; a NaN ``u`` counts as above them all, as numpy's ``searchsorted`` has it)."""
    lo = 0
    hi = inner.size
    while lo < hi:
        mid = (lo + hi) >> 1
        if inner[mid] <= u or u != u:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(**HELPER)
def table_jet1(rows: FloatArray, span: int, s: float, out: FloatArray) -> None:
    """Into ``out`` (3, dim): value, first and second derivative of the piece ``span`` of
    ``rows`` (degree + 1, dim, spans; value coefficients, highest power first) at local
    parameter ``s``, by Horner's rule; the derivatives' coefficients ``p a_p`` and
    ``(p - 1) p a_p`` are formed from the value's (the numbers :meth:`BSpline._pack` forms)."""
    k = rows.shape[0] - 1
    dim = rows.shape[1]
    for d in range(dim):
        for order in range(3):
            top = k - order  # the highest power of this order
            if top < 0:
                out[order, d] = 0.0
                continue
            w = 0.0
            for p in range(top + 1):
                a = rows[p, d, span]  # coefficient p (0: highest power) of this order
                for q in range(order):
                    a *= k - p - q
                w = a if p == 0 else w * s + a
            out[order, d] = w
