"""A merged face over a cylinder as a field ``P(s, z)``: cylinder coordinates, radial-line
intersections in closed form, and the fit of the face's points on one knot grid.

A cylindrical supporting face merged with blend halves (fillets along its rulings or round
its foot, on a partial cylinder or all the way round) is a field over the cylinder: at the
arc length ``s = R (theta - theta0)`` and the axial coordinate ``z`` the face lies on the
radial line from the axis, at the radial offset ``h(s, z)`` off the cylinder (zero on the
support, the blend's distance beyond or before it on a half). Its points are

``P(s, z) = o + z a + (R + h(s, z)) (cos theta e1 + sin theta e2)``, ``theta = theta0 + s / R``.

Curvature jumps (where a half meets the support or another half) lie along the edges of
the pieces; those along iso-lines (rulings: ``s = const``, circles: ``z = const``) are C1
knot lines of the fit, so it converges at its full order on both sides.

The three coordinates of ``P`` are fitted together, on the same knots, by a cubic
tensor-product B-spline (:class:`PointFitter`; periodic in ``theta`` when the face goes all
the way round: :mod:`medax.geometry.periodic_fit`). Why points and not the exact rational
form ``(R + h) d(theta)``: that form has degree 5 in a rational circle parameter, not in
``s``, so ``h`` would have to be fitted in that parameter and its knots merged with the
circle's; the cubic of the points converges as ``R (ds / R)^4`` on the circle, far inside
the tolerance at the spans the blend needs (its radius is the smaller), and its error is
measured on the check grid with everything else: the surface is a plain cubic like the plane
and ring routes' (OCCT's integrators and the rebuild treat them alike).

numpy and scipy only (no OCP).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline

from medax.geometry._types import FloatArray
from medax.geometry.tensor_fit import (
    CHECK_PER_SPAN,
    DEGREE,
    MAX_COEFFICIENTS,
    SAMPLES_PER_SPAN,
    UNIFORM_PROBES,
    HeightFn,
    _coefficient_count,
    curved_intervals,
    knot_vector,
    probe_lines,
    refine_both,
    solve_masked,
    span_samples,
)

PERIOD = 2.0 * np.pi
#: Heights are taken where the member's normal is within this angle of the radial line.
MAX_SLOPE_ANGLE = np.radians(70.0)

#: ``points(S, Z) -> (P, defined, inside)``: points (..., 3) on a grid (S, Z of one shape),
#: where they are defined (data of the fit) and where the error counts (the face itself).
PointFn = Callable[[FloatArray, FloatArray], tuple[FloatArray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class CylinderFrame:
    """Cylinder coordinates: ``origin`` on the axis, unit ``axis`` ``a``, ``e1``, ``e2``
    with ``e1 x e2 = a``, ``radius`` ``R`` and ``theta0``, the angle where ``s = 0``."""

    origin: FloatArray
    axis: FloatArray
    e1: FloatArray
    e2: FloatArray
    radius: float
    theta0: float = 0.0

    @classmethod
    def make(
        cls, origin: FloatArray, axis: FloatArray, e1: FloatArray, radius: float
    ) -> CylinderFrame:
        """A frame from possibly unnormalised ``axis`` and ``e1`` (``e1`` made normal to it)."""
        a = np.asarray(axis, float) / np.linalg.norm(axis)
        x = np.asarray(e1, float) - (np.asarray(e1, float) @ a) * a
        x /= np.linalg.norm(x)
        return cls(np.asarray(origin, float), a, x, np.cross(a, x), float(radius))

    def angle(self, x: FloatArray) -> FloatArray:
        """Angles (m,) of points ``x`` (m, 3) round the axis, in (-pi, pi]."""
        w = np.asarray(x, float) - self.origin
        return np.asarray(np.arctan2(w @ self.e2, w @ self.e1))

    def direction(self, s: FloatArray) -> FloatArray:
        """Unit radial directions (m, 3) at arc lengths ``s`` (m,)."""
        th = self.theta0 + np.asarray(s, float).ravel() / self.radius
        return np.outer(np.cos(th), self.e1) + np.outer(np.sin(th), self.e2)

    def point(self, s: FloatArray, z: FloatArray, h: FloatArray | float = 0.0) -> FloatArray:
        """Points (m, 3) at ``(s, z, h)`` (raveled, broadcast)."""
        s = np.asarray(s, float).ravel()
        z = np.broadcast_to(np.asarray(z, float).ravel(), s.shape)
        hh = np.broadcast_to(np.asarray(h, float).ravel(), s.shape)
        return (
            self.origin + np.outer(z, self.axis) + (self.radius + hh)[:, None] * self.direction(s)
        )

    def coords(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(s, z, h)`` of points ``x`` (m, 3), ``s`` in ``[0, 2 pi R)``."""
        w = np.asarray(x, float) - self.origin
        z = w @ self.axis
        rho = np.linalg.norm(w - np.outer(z, self.axis), axis=1)
        s = self.radius * np.mod(self.angle(x) - self.theta0, PERIOD)
        return s, z, rho - self.radius

    def unwrapped(self, x: FloatArray) -> FloatArray:
        """Arc lengths (m,) of consecutive points ``x`` (m, 3) along a curve, continuous
        (a loop round the axis ends ``2 pi R`` from where it began), the first in
        ``[0, 2 pi R)``."""
        th = np.unwrap(self.angle(x) - self.theta0)
        th = th - PERIOD * np.floor(th[0] / PERIOD)
        return np.asarray(self.radius * th)


def largest_gap(theta: FloatArray) -> tuple[float, float]:
    """(start, width) of the largest angular gap between the angles ``theta`` (radians,
    any range): where a face that does not go round the axis is not."""
    t = np.sort(np.mod(np.asarray(theta, float).ravel(), PERIOD))
    gaps = np.diff(np.append(t, t[0] + PERIOD))
    k = int(np.argmax(gaps))
    return float(t[k]), float(gaps[k])


def radial_heights(
    frame: CylinderFrame,
    kind: str,
    s: FloatArray,
    z: FloatArray,
    centre: FloatArray,
    axis: FloatArray,
    radius: float,
    major: float = 0.0,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Radial offsets ``h`` (m,) where the radial lines at ``(s, z)`` (m,) meet a surface
    in closed form, and where they do with the surface's normal within
    ``MAX_SLOPE_ANGLE`` of the line (``ok``). ``kind``: ``"plane"`` (``centre`` a point,
    ``axis`` the normal), ``"cylinder"`` (any axis), ``"sphere"`` (``axis`` unused) or
    ``"torus"`` coaxial with the frame (``radius`` the minor radius, ``major`` the major).
    Of two roots the one nearest the cylinder (smallest ``|h|``), on the ray (``R + h > 0``)."""
    s = np.asarray(s, float).ravel()
    z = np.asarray(z, float).ravel()
    d = frame.direction(s)
    p = frame.origin + np.outer(z, frame.axis)  # the lines' points on the axis
    big = frame.radius
    cos_max = np.cos(MAX_SLOPE_ANGLE)
    c = np.asarray(centre, float)
    ax = np.asarray(axis, float)
    if kind == "plane":
        den = d @ ax
        ok = np.abs(den) >= cos_max
        t = np.where(ok, ((c - p) @ ax) / np.where(ok, den, 1.0), 0.0)
        return t - big, ok & (t > 0)
    if kind == "torus":
        zr = (p - c) @ ax
        disc = radius**2 - zr**2
        root = np.sqrt(np.maximum(disc, 0.0))
        cand = np.stack([major + root, major - root], axis=1)
        cand = np.where(cand > 0, cand, np.inf)
        pick = np.argmin(np.abs(cand - big), axis=1)
        t = cand[np.arange(len(s)), pick]
        ok = (disc >= 0) & np.isfinite(t)
        t = np.where(ok, t, big)
        x = p + t[:, None] * d
        core = c + major * d  # the tube's centre circle in the line's meridian plane
        normal = (x - core) / max(radius, 1e-300)
        return t - big, ok & (np.abs(np.einsum("ij,ij->i", normal, d)) >= cos_max)
    w = p - c
    dd = d
    if kind == "cylinder":
        w = w - np.outer(w @ ax, ax)
        dd = d - np.outer(d @ ax, ax)
    elif kind != "sphere":
        raise ValueError(f"no closed form for a {kind}")
    qa = np.einsum("ij,ij->i", dd, dd)
    qb = np.einsum("ij,ij->i", w, dd)
    qc = np.einsum("ij,ij->i", w, w) - radius**2
    disc = qb * qb - qa * qc
    good = (disc >= 0) & (qa > 1e-24)
    root = np.sqrt(np.maximum(disc, 0.0))
    qa_safe = np.where(qa > 1e-24, qa, 1.0)
    cand = np.stack([(-qb - root) / qa_safe, (-qb + root) / qa_safe], axis=1)
    cand = np.where(cand > 0, cand, np.inf)
    pick = np.argmin(np.abs(cand - big), axis=1)
    t = cand[np.arange(len(s)), pick]
    ok = good & np.isfinite(t)
    t = np.where(ok, t, big)
    x = w + t[:, None] * dd
    normal = x / np.maximum(np.linalg.norm(x, axis=1), 1e-300)[:, None]
    return t - big, ok & (np.abs(np.einsum("ij,ij->i", normal, d)) >= cos_max)


@dataclass(frozen=True)
class PointFit:
    """``P(s, z) = sum_ij c_ij Bs_i(s) Bz_j(z)``: clamped cubic knot vectors ``ts``, ``tz``
    (with repeats), coefficients ``coef`` (ns, nz, 3), measured ``error`` (largest distance
    to the exact points on the check grid inside the face, length unit), the ``spacing``
    used and ``volume``: the signed volume between the fit and the exact points over the
    face, positive where the fit lies farther from the axis (length unit cubed)."""

    ts: FloatArray
    tz: FloatArray
    coef: FloatArray
    error: float
    spacing: float
    volume: float = 0.0

    def __call__(self, s: FloatArray, z: FloatArray) -> FloatArray:
        """Points on the tensor grid ``s`` (n,) by ``z`` (m,), shape (n, m, 3)."""
        bs = BSpline.design_matrix(np.asarray(s, float), self.ts, DEGREE)
        bz = BSpline.design_matrix(np.asarray(z, float), self.tz, DEGREE)
        ns, nz = self.coef.shape[:2]
        along = np.asarray(bs @ self.coef.reshape(ns, -1)).reshape(-1, nz, 3)
        return np.einsum("mj,njk->nmk", bz.toarray(), along)


def signed_volume(
    fit: Callable[[FloatArray, FloatArray], FloatArray],
    u: FloatArray,
    z: FloatArray,
    pts: FloatArray,
    use: np.ndarray,
    weights: tuple[FloatArray, FloatArray],
    axis_pt: FloatArray,
    axis: FloatArray,
    u_range: tuple[float, float] | None = None,
) -> float:
    """``sum (F - P) . (F_u x F_z) du dz`` over the samples ``use`` of the grid ``u`` (n,)
    by ``z`` (m,), ``pts`` (n, m, 3) the exact points and ``weights`` the cells' sizes in
    each direction; ``F`` the fit (its derivatives by central differences, kept inside
    ``u_range`` and the z samples' span), the normal oriented away from the axis (through
    ``axis_pt`` along ``axis``): positive where the fit lies outside the exact points."""
    e = 1e-6 * max(float(np.ptp(u)), 1e-300)
    ez = 1e-6 * max(float(np.ptp(z)), 1e-300)
    uu = u if u_range is None else np.clip(u, u_range[0] + e, u_range[1] - e)
    p = fit(u, z)
    pu = (fit(uu + e, z) - fit(uu - e, z)) / (2 * e)
    pz = (fit(u, z + ez) - fit(u, z - ez)) / (2 * ez)
    normal = np.cross(pu, pz)
    w = p - axis_pt
    radial = w - np.einsum("nmk,k->nm", w, axis)[..., None] * axis
    flip = np.sign(np.einsum("nmk,nmk->nm", normal, radial))
    dens = np.einsum("nmk,nmk->nm", p - pts, normal) * np.where(flip == 0, 1.0, flip)
    return float(np.sum(np.where(use, dens, 0.0) * np.outer(weights[0], weights[1])))


class PointFitter:
    """The fits of the points ``P(s, z)`` of a merged face over a partial cylinder (see
    the module): on ``s_range`` x ``z_range`` (length unit), C1 knots at ``s_breaks``
    (rulings) and ``z_breaks`` (circles) where the curvature jumps, spans of at most
    ``spacing`` (halved by :func:`refine_both`); in ``z`` one span where the radial offset
    ``height(S, Z) -> (h, defined, inside)`` is linear (the points are then linear in
    ``z``), in ``s`` fine spans everywhere (the circle). ``frame``: for the volume's sign.
    ``probes``: ``s`` (1-D array) of more lines along which the offset is probed for
    curvature in ``z``, besides 41 uniform ones (lines through the curved pieces)."""

    def __init__(
        self,
        s_range: tuple[float, float],
        z_range: tuple[float, float],
        s_breaks: Sequence[float],
        z_breaks: Sequence[float],
        points: PointFn,
        height: HeightFn,
        spacing: float,
        frame: CylinderFrame,
        probes: FloatArray | None = None,
    ) -> None:
        (s0, s1), (z0, z1) = s_range, z_range
        self.s_range, self.z_range, self.points, self.spacing = s_range, z_range, points, spacing
        self.frame = frame
        self.sb = sorted(b for b in set(s_breaks) if s0 < b < s1)
        self.fine_s = [True] * (len(self.sb) + 1)
        zb = sorted(b for b in set(z_breaks) if z0 < b < z1)
        lines = np.linspace(s0, s1, UNIFORM_PROBES)
        if probes is not None:  # and through the curved pieces (a thin one fits between)
            lines = probe_lines(lines, probes[(probes >= s0) & (probes <= s1)], spacing)
        self.zb, self.fine_z = curved_intervals(z0, z1, zb, height, lines, 1, spacing)
        self._fits: dict[tuple[float, float], PointFit | None] = {}

    def fit_at(self, ss: float, sz: float) -> PointFit | None:
        """The fit with spans of at most ``ss``, ``sz``; None when too large to solve."""
        key = (ss, sz)
        if key not in self._fits:
            (s0, s1), (z0, z1) = self.s_range, self.z_range
            ns = _coefficient_count(s0, s1, self.sb, self.fine_s, ss)
            nz = _coefficient_count(z0, z1, self.zb, self.fine_z, sz)
            self._fits[key] = self._fit_once(ss, sz) if ns * nz <= MAX_COEFFICIENTS else None
        return self._fits[key]

    def fit(self, tol: float, levels: int = 5) -> PointFit | None:
        """The best fit of the refinement from ``spacing`` to ``tol`` (length unit), at most
        ``levels`` levels; None when even the first is too large."""
        return refine_both(self.fit_at, self.spacing, tol, levels)

    def _fit_once(self, ss: float, sz: float) -> PointFit:
        ts = knot_vector(self.s_range[0], self.s_range[1], self.sb, self.fine_s, ss)
        tz = knot_vector(self.z_range[0], self.z_range[1], self.zb, self.fine_z, sz)
        xs, zs = span_samples(ts, SAMPLES_PER_SPAN), span_samples(tz, SAMPLES_PER_SPAN)
        grid = np.meshgrid(xs, zs, indexing="ij")
        pts, ok, _ = self.points(*grid)
        bs = BSpline.design_matrix(xs, ts, DEGREE).tocsr()
        bz = BSpline.design_matrix(zs, tz, DEGREE).tocsr()
        # outside the face (no data) the points return to the cylinder itself
        on_cylinder = self.frame.point(grid[0].ravel(), grid[1].ravel()).reshape(pts.shape)
        coef = solve_masked(bs, bz, ok, pts, on_cylinder)  # (pts without data: replaced)
        fit = PointFit(ts, tz, coef, 0.0, min(ss, sz))
        sc, zc = span_samples(ts, CHECK_PER_SPAN), span_samples(tz, CHECK_PER_SPAN)
        pc, okc, inside = self.points(*np.meshgrid(sc, zc, indexing="ij"))
        use = inside & okc
        if np.any(inside & ~okc):
            return replace(fit, error=float("inf"))  # data missing inside the face
        dist = np.linalg.norm(fit(sc, zc) - pc, axis=2)
        error = float(dist[use].max(initial=0.0))
        ws = np.repeat(np.diff(np.unique(ts)) / CHECK_PER_SPAN, CHECK_PER_SPAN)
        wz = np.repeat(np.diff(np.unique(tz)) / CHECK_PER_SPAN, CHECK_PER_SPAN)
        vol = signed_volume(
            fit,
            sc,
            zc,
            pc,
            use,
            (ws, wz),
            self.frame.origin,
            self.frame.axis,
            (float(ts[0]), float(ts[-1])),
        )
        # (F_s x F_z has length ~ (R + h) / R per unit s and z: dA in the arc-length frame)
        return replace(fit, error=error, volume=vol)
