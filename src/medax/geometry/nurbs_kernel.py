"""Compiled (numba) NURBS surface jets and the per-point Newton of
:func:`medax.geometry.surface_heights.graph_heights`.

A surface is passed as ``(hom, ubasis, vbasis)``: its homogeneous poles ``hom`` (nu, nv, 4)
(``w x, w y, w z, w``) and each direction's basis tuple of
:func:`medax.geometry.basis_kernel.basis_at` (see ``NurbsSurface.kernel_args``). Compiled
with ``cache=True``, announced and warmed up with :mod:`medax.geometry.kernels`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from medax.geometry._types import FloatArray
from medax.geometry.basis_kernel import basis_at


@njit(cache=True, error_model="numpy")
def _work(surf):  # type: ignore[no-untyped-def]
    """Work arrays of :func:`_jet1` for ``surf``."""
    pu, pv = surf[1][2], surf[2][2]
    q = max(pu, pv) + 1
    return (
        np.zeros((q, q)), np.zeros(q), np.zeros(q),
        np.zeros(pu + 1), np.zeros(pu + 1), np.zeros(pv + 1), np.zeros(pv + 1),
        np.zeros(12),
    )  # fmt: skip


@njit(cache=True, error_model="numpy", inline="always")
def _jet1(surf, u: float, v: float, work, x: FloatArray, du: FloatArray, dv: FloatArray) -> None:  # type: ignore[no-untyped-def]
    """The point ``x`` (3,) and its derivatives ``du``, ``dv`` (3,) at ``(u, v)``: the
    homogeneous sums over the (pu+1, pv+1) poles of the point's span (over v first, values
    and derivatives together, then over u) and the quotient rule."""
    hom, ub, vb = surf
    ndu, left, right, nu, dnu, nv, dnv, acc = work
    pu, pv = ub[2], vb[2]
    su = basis_at(ub, u, ndu, left, right, nu, dnu)
    sv = basis_at(vb, v, ndu, left, right, nv, dnv)
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


@njit(cache=True, error_model="numpy")
def jet_rows(surf, uv: FloatArray):  # type: ignore[no-untyped-def]
    """Points, d/du and d/dv (n, 3) each at ``uv`` (n, 2): :func:`_jet1` point by point."""
    n = uv.shape[0]
    x, du, dv = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    work = _work(surf)
    for i in range(n):
        _jet1(surf, uv[i, 0], uv[i, 1], work, x[i], du[i], dv[i])
    return x, du, dv


@njit(cache=True, error_model="numpy", inline="always")
def _plane_jacobian(  # type: ignore[no-untyped-def]
    du: FloatArray, dv: FloatArray, ex: FloatArray, ey: FloatArray
):
    """The in-plane Jacobian ``(a, b, c, d)`` = ``(du.ex, dv.ex, du.ey, dv.ey)``."""
    a = du[0] * ex[0] + du[1] * ex[1] + du[2] * ex[2]
    b = dv[0] * ex[0] + dv[1] * ex[1] + dv[2] * ex[2]
    c = du[0] * ey[0] + du[1] * ey[1] + du[2] * ey[2]
    d = dv[0] * ey[0] + dv[1] * ey[1] + dv[2] * ey[2]
    return a, b, c, d


@njit(cache=True, error_model="numpy")
def heights_newton(  # type: ignore[no-untyped-def]
    surf, frame: FloatArray, xy: FloatArray, uv: FloatArray, chain: np.ndarray, box: FloatArray,
    tol: float, steps: int,
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
    work = _work(surf)
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
            _jet1(surf, u, v, work, xi, dui, dvi)
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
