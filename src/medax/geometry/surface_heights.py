"""Heights of a NURBS surface over a plane: where lines along the plane's normal meet it.

The fitted merge needs the heights of a freeform blend piece at 10^4 - 10^5 grid points;
OCCT's per-point intersections would cost a Python loop over them. Here every point starts
from the nearest projected sample of a grid over the piece's parameter box and is solved by
a batched 2 x 2 Newton iteration on the in-plane coordinates, with the surface and its
derivatives from :meth:`medax.geometry.surfaces.NurbsSurface.jet`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from medax.geometry import kernels
from medax.geometry._types import FloatArray
from medax.geometry.nurbs_kernel import heights_newton
from medax.geometry.surfaces import NurbsSurface

#: Newton iterations at most, and the start grid's samples per direction.
NEWTON_STEPS, START_SAMPLES = 30, 48
#: Above 16x this many points, every SEED_EVERY-th is solved first as a start for the rest.
SEED_EVERY = 16
#: The surface is continued by this share of its domain on each side (see graph_heights).
CONTINUE = 0.02


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
    continued by ``CONTINUE`` of its size when ``surf.extrapolate``: the polygons that
    give points to a piece are chord approximations of its edges) and the surface's unit
    normals (m, 3) there.
    """
    o, ex, ey, n = frame
    b0, b1, c0, c1 = surf.bounds
    if surf.extrapolate:
        mu, mv = CONTINUE * (b1 - b0), CONTINUE * (c1 - c0)
        b0, b1, c0, c1 = b0 - mu, b1 + mu, c0 - mv, c1 + mv
    lo, hi = np.array([b0, c0]), np.array([b1, c1])
    if len(xy) > 16 * SEED_EVERY:
        # seeds: every SEED_EVERY-th point solved first (from the start grid); the others
        # start from their nearest seed's foot moved by the inverse in-plane Jacobian there
        # (one Newton step from a nearby solution), so most of them take one or two
        # iterations instead of four
        seed = np.arange(0, len(xy), SEED_EVERY)
        start = _grid_start(surf, frame, xy[seed], uv_box)
        suv, (_, su, sv) = _newton(surf, frame, xy[seed], start, lo, hi, tol)
        a, b, c, d = su @ ex, sv @ ex, su @ ey, sv @ ey
        det = a * d - b * c
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        _, k = cKDTree(xy[seed]).query(xy)
        dx, dy = xy[:, 0] - xy[seed[k], 0], xy[:, 1] - xy[seed[k], 1]
        move = np.column_stack([(d[k] * dx - b[k] * dy) / det[k], (a[k] * dy - c[k] * dx) / det[k]])
        uv = np.clip(suv[k] + move, lo, hi)
    else:
        uv = _grid_start(surf, frame, xy, uv_box)
    uv, (s, su, sv) = _newton(surf, frame, xy, uv, lo, hi, tol)
    res = _residual(s, frame, xy)
    again = np.flatnonzero(res > tol)
    if again.size and len(xy) > 16 * SEED_EVERY:
        # a seed's neighbour on a steep or strongly curved stretch can start outside
        # Newton's basin: solve those again from the grid (the rational B-spline of a
        # round stored as a revolution left 6 of 369 points unsolved from their seeds)
        start = _grid_start(surf, frame, xy[again], uv_box)
        uv2, (s2, su2, sv2) = _newton(surf, frame, xy[again], start, lo, hi, tol)
        better = _residual(s2, frame, xy[again]) < res[again]
        rows = again[better]
        uv[rows], s[rows], su[rows], sv[rows] = uv2[better], s2[better], su2[better], sv2[better]
        res[rows] = _residual(s[rows], frame, xy[rows])
    q = s - o
    normal = np.cross(su, sv)
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    return q @ n, res <= tol, normal


def _residual(
    s: FloatArray, frame: tuple[FloatArray, FloatArray, FloatArray, FloatArray], xy: FloatArray
) -> FloatArray:
    """In-plane distance (m,) of surface points ``s`` (m, 3) from their targets ``xy``."""
    o, ex, ey, _ = frame
    q = s - o
    return np.asarray(np.hypot(q @ ex - xy[:, 0], q @ ey - xy[:, 1]))


def _grid_start(
    surf: NurbsSurface,
    frame: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    xy: FloatArray,
    uv_box: tuple[float, float, float, float],
) -> FloatArray:
    """Start parameters (m, 2): the nearest projected sample of a grid over ``uv_box``."""
    o, ex, ey, _ = frame
    u0, u1, v0, v1 = uv_box
    gu, gv = np.meshgrid(
        np.linspace(u0, u1, START_SAMPLES), np.linspace(v0, v1, START_SAMPLES), indexing="ij"
    )
    gq = surf.evaluate(np.column_stack([gu.ravel(), gv.ravel()])) - o
    _, k = cKDTree(np.column_stack([gq @ ex, gq @ ey])).query(xy)
    return np.column_stack([gu.ravel()[k], gv.ravel()[k]])


def _newton(
    surf: NurbsSurface,
    frame: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    xy: FloatArray,
    uv: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    tol: float,
) -> tuple[FloatArray, tuple[FloatArray, FloatArray, FloatArray]]:
    """Newton on the in-plane coordinates from ``uv`` (m, 2), each row until its residual
    is below ``0.01 tol``; the parameters kept within ``lo``, ``hi`` (2,). Returns the
    parameters and the surface's jet (points, d/du, d/dv, each (m, 3)) there: a row's last
    evaluation, the one that found it converged, or one more for the rows still moving
    after ``NEWTON_STEPS``. Compiled, point by point
    (:func:`medax.geometry.nurbs_kernel.heights_newton`)."""
    o, ex, ey, _ = frame
    kernels.announce_compile()
    uv, s, su, sv, _ = heights_newton(
        surf.kernel_args,
        np.array([o, ex, ey], dtype=np.float64),
        np.ascontiguousarray(xy, dtype=np.float64),
        np.ascontiguousarray(uv, dtype=np.float64),
        np.array([lo[0], hi[0], lo[1], hi[1]], dtype=np.float64),
        float(tol),
        NEWTON_STEPS,
    )
    return uv, (s, su, sv)
