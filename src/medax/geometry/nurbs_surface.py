"""Tensor-product NURBS surfaces evaluated for many parameters at once, and their heights
over a plane (where a line along the plane's normal meets the surface).

Written here rather than taken from a library because the fitted merge needs one vectorised
job, the heights of a freeform blend piece at 10^4 - 10^5 grid points: scipy's ``BSpline``
gives the basis functions (and their derivatives) as dense matrices, and the rational
surface and its first derivatives follow by two ``einsum`` calls; a batched 2 x 2 Newton
solve then finds each point's parameters. OCCT's per-point intersections would cost a Python
loop over the points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline
from scipy.spatial import cKDTree

FloatArray = NDArray[np.float64]

#: Newton iterations for the heights, and the start grid's samples per direction.
NEWTON_STEPS, START_SAMPLES = 30, 48


@dataclass(frozen=True)
class NurbsSurface:
    """``poles`` (nu, nv, 3), ``weights`` (nu, nv), full clamped knot vectors ``tu``
    (nu + pu + 1,) and ``tv`` (nv + pv + 1,), degrees ``pu``, ``pv``."""

    poles: FloatArray
    weights: FloatArray
    tu: FloatArray
    tv: FloatArray
    pu: int
    pv: int

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(u0, u1, v0, v1) of the parameter domain."""
        return (
            float(self.tu[self.pu]),
            float(self.tu[-self.pu - 1]),
            float(self.tv[self.pv]),
            float(self.tv[-self.pv - 1]),
        )

    def _basis(self, t: FloatArray, k: int, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        n = len(t) - k - 1
        spl = BSpline(t, np.eye(n), k, extrapolate=True)
        return spl(x), spl.derivative()(x)

    def jet(self, u: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Points, d/du and d/dv at parameter pairs ``(u[i], v[i])``: three (m, 3) arrays."""
        bu, du = self._basis(self.tu, self.pu, np.asarray(u, float))
        bv, dv = self._basis(self.tv, self.pv, np.asarray(v, float))
        hw = np.concatenate([self.poles * self.weights[..., None], self.weights[..., None]], 2)
        nu, nv = self.weights.shape
        flat = hw.reshape(nu, nv * 4)
        rows, rows_u = (bu @ flat).reshape(-1, nv, 4), (du @ flat).reshape(-1, nv, 4)
        a = np.einsum("mjd,mj->md", rows, bv)
        au = np.einsum("mjd,mj->md", rows_u, bv)
        av = np.einsum("mjd,mj->md", rows, dv)
        w = a[:, 3:]
        s = a[:, :3] / w
        return s, (au[:, :3] - s * au[:, 3:]) / w, (av[:, :3] - s * av[:, 3:]) / w


def graph_heights(
    surf: NurbsSurface,
    frame: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    xy: FloatArray,
    uv_box: tuple[float, float, float, float],
    tol: float,
) -> tuple[FloatArray, NDArray[np.bool_], FloatArray]:
    """Heights of ``surf`` over the plane of ``frame`` = (origin, ex, ey, n) at points ``xy``
    (m, 2) of the plane: ``t`` (m,) with ``origin + x ex + y ey + t n`` on the surface.

    Each point starts from the nearest projected sample of a grid over ``uv_box`` (the
    piece's parameter box) and is solved by Newton on the 2 x 2 system of its in-plane
    coordinates. Returns ``t``, ``ok`` (converged to ``tol`` inside the surface's domain,
    continued by 2 % of its size)
    and the surface's unit normals (m, 3) there.
    """
    o, ex, ey, n = frame
    u0, u1, v0, v1 = uv_box
    gu, gv = np.meshgrid(
        np.linspace(u0, u1, START_SAMPLES), np.linspace(v0, v1, START_SAMPLES), indexing="ij"
    )
    gs, _, _ = surf.jet(gu.ravel(), gv.ravel())
    gq = gs - o
    _, k = cKDTree(np.column_stack([gq @ ex, gq @ ey])).query(xy)
    u, v = gu.ravel()[k].copy(), gv.ravel()[k].copy()
    # the polygon that gave a point to this piece is a chord approximation of its edges:
    # like the analytic pieces, the surface is continued a little past its domain
    b0, b1, c0, c1 = surf.bounds
    mu, mv = 0.02 * (b1 - b0), 0.02 * (c1 - c0)
    b0, b1, c0, c1 = b0 - mu, b1 + mu, c0 - mv, c1 + mv
    live = np.arange(len(xy))  # points still moving
    for _ in range(NEWTON_STEPS):
        s, su, sv = surf.jet(u[live], v[live])
        q = s - o
        fx, fy = q @ ex - xy[live, 0], q @ ey - xy[live, 1]
        a, b, c, d = su @ ex, sv @ ex, su @ ey, sv @ ey
        det = a * d - b * c
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        u[live] = np.clip(u[live] - (d * fx - b * fy) / det, b0, b1)
        v[live] = np.clip(v[live] - (a * fy - c * fx) / det, c0, c1)
        live = live[np.hypot(fx, fy) >= 0.01 * tol]
        if live.size == 0:
            break
    s, su, sv = surf.jet(u, v)
    q = s - o
    res = np.hypot(q @ ex - xy[:, 0], q @ ey - xy[:, 1])
    normal = np.cross(su, sv)
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    return q @ n, res <= tol, normal
