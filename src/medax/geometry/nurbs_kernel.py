"""Compiled (numba) NURBS surface jets and the per-point Newton of
:func:`medax.geometry.surface_heights.graph_heights`.

A surface is passed as plain arguments ``hom, ukn, ucoef, vkn, vcoef, extrapolate``
(``NurbsSurface.kernel_args``): its homogeneous poles ``hom`` (nu, nv, 4) (``w x, w y, w z,
w``), each direction's knots and span polynomials of
:func:`medax.geometry.basis_kernel.basis_at` (empty: Cox-de Boor; the degrees follow from
the knot and pole counts) and whether it is continued past its domain (nested tuples of
arrays and scalars compiled slowly). One compiled kernel, :func:`heights_newton`, with the
jet inlined (a call per point took 40 % longer); :func:`jet_rows` is it without a
Newton step. Compiled with ``cache=True``, announced and warmed up with
:mod:`medax.geometry.kernels`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray
from medax.geometry.basis_kernel import basis_at


@njit(**HELPER)
def _work(hom: FloatArray, ukn: FloatArray, vkn: FloatArray):  # type: ignore[no-untyped-def]
    """Work arrays of :func:`_jet1` for the surface of ``hom``, ``ukn``, ``vkn``."""
    pu, pv = ukn.size - hom.shape[0] - 1, vkn.size - hom.shape[1] - 1
    q = max(pu, pv) + 1
    return (
        np.zeros((q, q)), np.zeros(q), np.zeros(q),
        np.zeros(pu + 1), np.zeros(pu + 1), np.zeros(pv + 1), np.zeros(pv + 1),
        np.zeros(12),
    )  # fmt: skip


@njit(**HELPER, inline="always")
def _jet1(  # type: ignore[no-untyped-def]
    hom: FloatArray, ukn: FloatArray, ucoef: FloatArray, vkn: FloatArray, vcoef: FloatArray,
    extrapolate: bool, u: float, v: float, work, x: FloatArray, du: FloatArray, dv: FloatArray,
) -> None:  # fmt: skip
    """The point ``x`` (3,) and its derivatives ``du``, ``dv`` (3,) at ``(u, v)``: the
    homogeneous sums over the (pu+1, pv+1) poles of the point's span (over v first, values
    and derivatives together, then over u) and the quotient rule; ``work``: :func:`_work`."""
    ndu, left, right, nu, dnu, nv, dnv, acc = work
    pu, pv = nu.size - 1, nv.size - 1
    su = basis_at(ukn, ucoef, pu, extrapolate, u, ndu, left, right, nu, dnu)
    sv = basis_at(vkn, vcoef, pv, extrapolate, v, ndu, left, right, nv, dnv)
    for c in range(12):
        acc[c] = 0.0  # h (4), h_u (4), h_v (4)
    for a in range(pu + 1):
        row = su - pu + a
        t0 = t1 = t2 = t3 = 0.0  # sum over v of N_v * hom
        d0 = d1 = d2 = d3 = 0.0  # sum over v of N_v' * hom
        for b in range(pv + 1):
            col = sv - pv + b
            n, dn = nv[b], dnv[b]
            h0, h1, h2, h3 = hom[row, col, 0], hom[row, col, 1], hom[row, col, 2], hom[row, col, 3]
            t0 += n * h0
            t1 += n * h1
            t2 += n * h2
            t3 += n * h3
            d0 += dn * h0
            d1 += dn * h1
            d2 += dn * h2
            d3 += dn * h3
        n, dn = nu[a], dnu[a]
        acc[0] += n * t0
        acc[1] += n * t1
        acc[2] += n * t2
        acc[3] += n * t3
        acc[4] += dn * t0
        acc[5] += dn * t1
        acc[6] += dn * t2
        acc[7] += dn * t3
        acc[8] += n * d0
        acc[9] += n * d1
        acc[10] += n * d2
        acc[11] += n * d3
    w = acc[3]
    for c in range(3):
        x[c] = acc[c] / w
    for c in range(3):
        du[c] = (acc[4 + c] - acc[7] * x[c]) / w
        dv[c] = (acc[8 + c] - acc[11] * x[c]) / w


def jet_rows(
    hom: FloatArray, ukn: FloatArray, ucoef: FloatArray, vkn: FloatArray, vcoef: FloatArray,
    extrapolate: bool, uv: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:  # fmt: skip
    """Points, d/du and d/dv (n, 3) each at ``uv`` (n, 2; C-contiguous): :func:`_jet1`
    point by point, as :func:`heights_newton` without a step (one compiled kernel for both:
    a second one with the jet inlined took 1.2 s more to compile)."""
    n = uv.shape[0]
    _, x, du, dv, _, _ = heights_newton(
        hom, ukn, ucoef, vkn, vcoef, extrapolate, _NO_FRAME, uv, uv, np.zeros(n, np.bool_),
        _NO_BOX, 0.0, 0,
    )  # fmt: skip
    return x, du, dv


#: the plane and parameter box of :func:`jet_rows`' call (unused without a step)
_NO_FRAME, _NO_BOX = np.eye(3), np.zeros(4)


@njit(**HELPER)
def _plane_jacobian(  # type: ignore[no-untyped-def]
    du: FloatArray, dv: FloatArray, ex: FloatArray, ey: FloatArray
):
    """The in-plane Jacobian ``(a, b, c, d)`` = ``(du.ex, dv.ex, du.ey, dv.ey)``."""
    a = du[0] * ex[0] + du[1] * ex[1] + du[2] * ex[2]
    b = dv[0] * ex[0] + dv[1] * ex[1] + dv[2] * ex[2]
    c = du[0] * ey[0] + du[1] * ey[1] + du[2] * ey[2]
    d = dv[0] * ey[0] + dv[1] * ey[1] + dv[2] * ey[2]
    return a, b, c, d


@njit(**KERNEL)
def heights_newton(  # type: ignore[no-untyped-def]
    hom: FloatArray, ukn: FloatArray, ucoef: FloatArray, vkn: FloatArray, vcoef: FloatArray,
    extrapolate: bool, frame: FloatArray, xy: FloatArray, uv: FloatArray, chain: np.ndarray,
    box: FloatArray, tol: float, steps: int,
):  # fmt: skip
    """Newton on the in-plane coordinates, point by point: from ``uv`` (m, 2), or where
    ``chain`` (m,) from the previous point's solution moved by the inverse in-plane
    Jacobian there (one Newton step from a nearby solution), until the
    in-plane distance of ``S(u, v)`` from ``xy`` (m, 2) is below ``0.01 tol``, at most
    ``steps`` steps, the parameters clamped to ``box`` = (u0, u1, v0, v1). ``frame`` (3, 3)
    holds the plane's origin, ``ex``, ``ey``. Returns the parameters (m, 2), the jet there
    (points, d/du, d/dv, each (m, 3): the evaluation that found a row converged, or one
    more after the last step), the unit normals ``d/du x d/dv`` normalised (m, 3) and the
    in-plane distances (m,)."""
    m = xy.shape[0]
    out = uv.copy()
    x, du, dv = np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3))
    res = np.empty(m)
    normal = np.empty((m, 3))
    work = _work(hom, ukn, vkn)
    o, ex, ey = frame[0], frame[1], frame[2]
    for i in range(m):
        u, v = uv[i, 0], uv[i, 1]
        if chain[i] and i > 0:
            a, b, c, d = _plane_jacobian(du[i - 1], dv[i - 1], ex, ey)
            det = a * d - b * c
            if not abs(det) > 1e-300:
                det = 1e-300
            dx, dy = xy[i, 0] - xy[i - 1, 0], xy[i, 1] - xy[i - 1, 1]
            u = min(max(out[i - 1, 0] + (d * dx - b * dy) / det, box[0]), box[1])
            v = min(max(out[i - 1, 1] + (a * dy - c * dx) / det, box[2]), box[3])
        xi, dui, dvi = x[i], du[i], dv[i]
        for k in range(steps + 1):
            _jet1(hom, ukn, ucoef, vkn, vcoef, extrapolate, u, v, work, xi, dui, dvi)
            q0, q1, q2 = xi[0] - o[0], xi[1] - o[1], xi[2] - o[2]
            fx = q0 * ex[0] + q1 * ex[1] + q2 * ex[2] - xy[i, 0]
            fy = q0 * ey[0] + q1 * ey[1] + q2 * ey[2] - xy[i, 1]
            res[i] = math.hypot(fx, fy)
            if res[i] < 0.01 * tol or k == steps:
                break
            a, b, c, d = _plane_jacobian(dui, dvi, ex, ey)
            det = a * d - b * c
            if not abs(det) > 1e-300:
                det = 1e-300
            u = min(max(u - (d * fx - b * fy) / det, box[0]), box[1])
            v = min(max(v - (a * fy - c * fx) / det, box[2]), box[3])
        out[i, 0], out[i, 1] = u, v
        n0 = dui[1] * dvi[2] - dui[2] * dvi[1]
        n1 = dui[2] * dvi[0] - dui[0] * dvi[2]
        n2 = dui[0] * dvi[1] - dui[1] * dvi[0]
        size = max(math.sqrt(n0 * n0 + n1 * n1 + n2 * n2), 1e-300)
        normal[i, 0], normal[i, 1], normal[i, 2] = n0 / size, n1 / size, n2 / size
    return out, x, du, dv, normal, res
