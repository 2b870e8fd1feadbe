"""Ring coordinates around a closed contact curve, and the points of a freeform blend on
their rays: the data of a fitted merged face whose blend half runs all the way round.

A fillet around a boss (or a hole) touches its supporting face along a closed curve. The
merged face (the support and the half blend) is parametrised by ``(theta, sigma)``: the
angle ``theta`` around the boss and ``sigma``, the signed distance from the contact curve
measured *in the support* (positive towards the support, negative over the blend):

- a plane: ``x = c + (rho_c(theta) + e sigma) d(theta) + h n`` (polar coordinates around a
  centre ``c`` of the contact curve, ``d(theta) = cos theta e1 + sin theta e2``);
- a cylinder: ``x = o + (s_c(theta) + e sigma) a + (R + h) d(theta)`` (its own frame: axis
  ``a``, radius ``R``);

``rho_c`` / ``s_c`` the contact curve (a periodic cubic spline in ``theta``), ``e = +-1``
the side of the support and ``h`` the height off the support (zero on it). The contact
curve is then the line ``sigma = 0``: a C1 knot line of a fit in ``(theta, sigma)``, so the
curvature jump there costs no accuracy (in the Cartesian frame of the plane it is a curve
across the knots: the fit converged only as the square of the spacing and stalled).

:func:`ray_points` finds where a NURBS blend meets given rays ``(theta, sigma)``: Newton on
the blend's ``(u, v)`` with the ``(theta, sigma)`` coordinates of its points as the
residual (from the nearest sample of a start grid), vectorised over all rays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline
from scipy.spatial import cKDTree

from medax.geometry._types import FloatArray
from medax.geometry.surfaces import NurbsSurface

PERIOD = 2.0 * np.pi
#: Newton iterations at most, start grid samples per direction.
NEWTON_STEPS, START_SAMPLES = 12, 96


def _wrap(a: FloatArray) -> FloatArray:
    """Angles into [-pi, pi)."""
    return np.asarray(np.mod(a + np.pi, PERIOD) - np.pi)


def goes_round(theta: FloatArray) -> str:
    """An empty string when the angles ``theta`` (k,) of consecutive samples of a closed
    curve (the first not repeated) go once round the axis, strictly monotone (the curve is
    star-shaped from the axis: one point per ray); else what is wrong."""
    steps = _wrap(np.diff(np.append(theta, theta[0])))
    if not (np.all(steps > 0) or np.all(steps < 0)):
        return "is not star-shaped around the axis"
    if abs(abs(float(steps.sum())) - PERIOD) > 1e-6:
        return "does not go once round the axis"
    return ""


@dataclass(frozen=True)
class RingFrame:
    """Ring coordinates over a plane (``kind == "plane"``: ``axis`` its normal ``n``) or a
    cylinder (``"cylinder"``: ``axis`` its direction ``a``, ``radius`` ``R``), origin
    ``origin`` (the centre ``c`` / a point of the axis), ``e1``, ``e2`` with
    ``e1 x e2 = axis``, the contact curve ``contact(theta)`` (``rho_c`` / ``s_c``) and
    ``sign`` (+1 when the support lies at growing ``rho`` / ``s``)."""

    kind: str
    origin: FloatArray
    e1: FloatArray
    e2: FloatArray
    axis: FloatArray
    contact: CubicSpline
    sign: float
    radius: float = 0.0

    @classmethod
    def around(
        cls,
        kind: str,
        origin: FloatArray,
        e1: FloatArray,
        axis: FloatArray,
        contact_points: FloatArray,
        sign: float,
        radius: float = 0.0,
    ) -> RingFrame | str:
        """The frame whose contact curve interpolates ``contact_points`` (k, 3), samples in
        order along a closed curve (the first not repeated); the reason (str) when the
        curve does not go once round the axis with a strictly monotone angle (not
        star-shaped from ``origin``)."""
        a = np.asarray(axis, float) / np.linalg.norm(axis)
        x = np.asarray(e1, float) - (np.asarray(e1, float) @ a) * a
        x /= np.linalg.norm(x)
        y = np.cross(a, x)
        w = np.asarray(contact_points, float) - origin
        th = np.arctan2(w @ y, w @ x)
        why = goes_round(th)
        if why:
            return f"the contact curve {why}"
        if kind == "plane":
            val = np.linalg.norm(w - np.outer(w @ a, a), axis=1)
        else:
            val = w @ a
        order = np.argsort(np.mod(th, PERIOD))
        t = np.mod(th, PERIOD)[order]
        v = val[order]
        t = np.append(t, t[0] + PERIOD)
        v = np.append(v, v[0])
        spline = CubicSpline(t, v, bc_type="periodic")
        return cls(kind, np.asarray(origin, float), x, y, a, spline, float(sign), float(radius))

    def _contact(self, theta: FloatArray, nu: int = 0) -> FloatArray:
        t0 = float(self.contact.x[0])
        return np.asarray(self.contact(t0 + np.mod(theta - t0, PERIOD), nu))

    def direction(self, theta: FloatArray) -> FloatArray:
        """``d(theta)`` (m, 3)."""
        theta = np.asarray(theta, float).ravel()
        return np.outer(np.cos(theta), self.e1) + np.outer(np.sin(theta), self.e2)

    def point(
        self, theta: FloatArray, sigma: FloatArray, h: FloatArray | float = 0.0
    ) -> FloatArray:
        """Points (m, 3) at ``(theta, sigma, h)`` (arrays of one shape, raveled)."""
        theta = np.asarray(theta, float).ravel()
        sigma = np.asarray(sigma, float).ravel()
        hh = np.broadcast_to(np.asarray(h, float).ravel(), theta.shape)
        d = self.direction(theta)
        base = self._contact(theta) + self.sign * sigma
        if self.kind == "plane":
            return self.origin + base[:, None] * d + np.outer(hh, self.axis)
        return self.origin + np.outer(base, self.axis) + (self.radius + hh)[:, None] * d

    def coords(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(theta, sigma, h)`` of points ``x`` (m, 3); ``theta`` in [0, 2 pi)."""
        w = np.asarray(x, float) - self.origin
        along = w @ self.axis
        th = np.mod(np.arctan2(w @ self.e2, w @ self.e1), PERIOD)
        rho = np.linalg.norm(w - np.outer(along, self.axis), axis=1)
        if self.kind == "plane":
            return th, self.sign * (rho - self._contact(th)), along
        return th, self.sign * (along - self._contact(th)), rho - self.radius

    def gradients(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Gradients (m, 3) of ``theta`` and ``sigma`` at points ``x`` (m, 3)."""
        w = np.asarray(x, float) - self.origin
        along = w @ self.axis
        perp = w - np.outer(along, self.axis)
        rho = np.maximum(np.linalg.norm(perp, axis=1), 1e-300)
        radial = perp / rho[:, None]
        g_theta = np.cross(self.axis, radial) / rho[:, None]
        th = np.mod(np.arctan2(w @ self.e2, w @ self.e1), PERIOD)
        slope = self._contact(th, 1)[:, None]
        first = radial if self.kind == "plane" else np.broadcast_to(self.axis, w.shape)
        return g_theta, self.sign * (first - slope * g_theta)


def ray_points(
    surf: NurbsSurface,
    frame: RingFrame,
    theta: FloatArray,
    sigma: FloatArray,
    uv_box: tuple[float, float, float, float],
    tol: float,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Points (m, 3) of ``surf`` on the rays ``(theta, sigma)`` (m,) of ``frame`` and where
    they were found (``ok``: residual below ``tol`` in length, inside the surface's domain
    (continued when ``surf.extrapolate``)). Newton on ``(u, v)``, the residual the
    ``(theta, sigma)`` of the point against the ray's (``theta`` scaled by ``R``, the start
    samples' mean distance from the axis). Starts: the nearest sample of a grid over
    ``uv_box``; above ``16 SEED_EVERY`` rays every ``SEED_EVERY``-th is solved first and the
    others start from their nearest seed moved by the inverse Jacobian there (one Newton
    step from a nearby solution: two or three iterations instead of five)."""
    theta = np.mod(np.asarray(theta, float).ravel(), PERIOD)
    sigma = np.asarray(sigma, float).ravel()
    b0, b1, c0, c1 = surf.bounds
    if surf.extrapolate:
        mu, mv = 0.02 * (b1 - b0), 0.02 * (c1 - c0)
        b0, b1, c0, c1 = b0 - mu, b1 + mu, c0 - mv, c1 + mv
    lo, hi = np.array([b0, c0]), np.array([b1, c1])
    u0, u1, v0, v1 = uv_box
    gu, gv = np.meshgrid(
        np.linspace(u0, u1, START_SAMPLES), np.linspace(v0, v1, START_SAMPLES), indexing="ij"
    )
    guv = np.column_stack([gu.ravel(), gv.ravel()])
    gx = surf.evaluate(guv)
    gth, gsig, _ = frame.coords(gx)
    w = gx - frame.origin
    scale = float(np.mean(np.linalg.norm(w - np.outer(w @ frame.axis, frame.axis), axis=1)))

    def nearest(
        keys_th: FloatArray, keys_sg: FloatArray, th_q: FloatArray, sg_q: FloatArray
    ) -> FloatArray:
        """Index of the nearest key to each query ray (theta wrapped: keys repeated a
        period on each side)."""
        keys = np.vstack(
            [np.column_stack([scale * (keys_th + k * PERIOD), keys_sg]) for k in (-1, 0, 1)]
        )
        _, idx = cKDTree(keys).query(np.column_stack([scale * th_q, sg_q]))
        return np.asarray(idx % len(keys_th))

    def solve(uv: FloatArray, th_t: FloatArray, sg_t: FloatArray) -> tuple[FloatArray, ...]:
        return _newton(surf, frame, uv, th_t, sg_t, lo, hi, scale, tol)

    if len(theta) > 16 * SEED_EVERY:
        seed = np.arange(0, len(theta), SEED_EVERY)
        start = guv[nearest(gth, gsig, theta[seed], sigma[seed])].copy()
        suv, _, _, jac = solve(start, theta[seed], sigma[seed])
        k = nearest(theta[seed], sigma[seed], theta, sigma)
        dt = _wrap(theta - theta[seed[k]])
        ds = sigma - sigma[seed[k]]
        a, b, c, d = jac[k, 0, 0], jac[k, 0, 1], jac[k, 1, 0], jac[k, 1, 1]
        det = a * d - b * c
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        move = np.column_stack([(d * dt - b * ds) / det, (a * ds - c * dt) / det])
        uv = np.clip(suv[k] + move, lo, hi)
    else:
        uv = guv[nearest(gth, gsig, theta, sigma)].copy()
    _, x, res, _ = solve(uv, theta, sigma)
    return x, res <= tol


#: Above 16x this many rays, every SEED_EVERY-th is solved first as a start for the rest.
SEED_EVERY = 16


def _newton(
    surf: NurbsSurface,
    frame: RingFrame,
    uv: FloatArray,
    theta: FloatArray,
    sigma: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    scale: float,
    tol: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Newton from ``uv`` (m, 2) until each residual is below ``1e-3 tol``: the
    parameters, points (m, 3), residuals (m,) and the Jacobians (m, 2, 2) of
    ``(theta, sigma)`` by ``(u, v)`` at the last step."""
    uv = uv.copy()
    res = np.full(len(theta), np.inf)
    x = np.zeros((len(theta), 3))
    jac = np.zeros((len(theta), 2, 2))
    jac[:, 0, 0] = jac[:, 1, 1] = 1.0
    live = np.arange(len(theta))
    for _ in range(NEWTON_STEPS):
        s, su, sv = surf.jet(uv[live])
        th, sg, _ = frame.coords(s)
        ft = _wrap(th - theta[live])
        fs = sg - sigma[live]
        x[live] = s
        res[live] = np.hypot(scale * ft, fs)
        g_t, g_s = frame.gradients(s)
        a = np.einsum("ij,ij->i", g_t, su)
        b = np.einsum("ij,ij->i", g_t, sv)
        c = np.einsum("ij,ij->i", g_s, su)
        d = np.einsum("ij,ij->i", g_s, sv)
        jac[live] = np.stack([np.column_stack([a, b]), np.column_stack([c, d])], axis=1)
        move = res[live] >= 1e-3 * tol
        live, ft, fs = live[move], ft[move], fs[move]
        if live.size == 0:
            break
        a, b, c, d = a[move], b[move], c[move], d[move]
        det = a * d - b * c
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        step = np.column_stack([(d * ft - b * fs) / det, (a * fs - c * ft) / det])
        uv[live] = np.clip(uv[live] - step, lo, hi)
    return uv, x, res, jac
