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

    Each point is solved by Newton on the 2 x 2 system of its in-plane coordinates
    (compiled, point by point). A point no farther from the one before it than the start
    grid's longest projected cell edge (the rows of the caller's sample grids) starts from
    that point's solution moved by the inverse in-plane Jacobian there (one Newton step
    from a nearby solution); the others, and every point that did not converge from there,
    from the nearest projected sample of a grid over ``uv_box`` (the piece's parameter
    box). Returns ``t``, ``ok`` (converged to ``tol`` inside the surface's domain,
    continued by ``CONTINUE`` of its size when ``surf.extrapolate``: the polygons that
    give points to a piece are chord approximations of its edges) and the surface's unit
    normals (m, 3) there.
    """
    o, ex, ey, n = frame
    b0, b1, c0, c1 = surf.bounds
    if surf.extrapolate:
        mu, mv = CONTINUE * (b1 - b0), CONTINUE * (c1 - c0)
        b0, b1, c0, c1 = b0 - mu, b1 + mu, c0 - mv, c1 + mv
    xy = np.ascontiguousarray(xy, dtype=np.float64)
    grid = _StartGrid(surf, frame, uv_box)
    chain = np.zeros(len(xy), dtype=np.bool_)
    if len(xy) > 1:
        chain[1:] = np.hypot(*np.diff(xy, axis=0).T) <= grid.reach
    start = np.zeros((len(xy), 2))
    heads = np.flatnonzero(~chain)
    start[heads] = grid.start(xy[heads])
    box = np.array([b0, b1, c0, c1])
    kernels.announce_compile()
    plane = np.array([o, ex, ey], dtype=np.float64)
    _, s, _, _, normal, res = heights_newton(
        *surf.kernel_args, plane, xy, start, chain, box, float(tol), NEWTON_STEPS
    )
    again = np.flatnonzero((res > tol) & chain)
    if again.size:
        # a neighbour on a steep or strongly curved stretch, or after a point that did not
        # converge, can start outside Newton's basin: solve those again from the grid
        # (the rational B-spline of a round stored as a revolution left 6 of 369 points
        # unsolved from nearby starts)
        _, s2, _, _, normal2, res2 = heights_newton(
            *surf.kernel_args, plane, xy[again], grid.start(xy[again]),
            np.zeros(again.size, dtype=np.bool_), box, float(tol), NEWTON_STEPS,
        )  # fmt: skip
        better = res2 < res[again]
        rows = again[better]
        s[rows], normal[rows], res[rows] = s2[better], normal2[better], res2[better]
    return (s - o) @ n, res <= tol, normal


class _StartGrid:
    """The projected samples of a ``START_SAMPLES`` x ``START_SAMPLES`` grid over
    ``uv_box``: start parameters for points (their nearest sample) and ``reach``, the
    longest projected cell edge (the farthest a start from the grid can be)."""

    def __init__(
        self,
        surf: NurbsSurface,
        frame: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
        uv_box: tuple[float, float, float, float],
    ) -> None:
        o, ex, ey, _ = frame
        u0, u1, v0, v1 = uv_box
        gu, gv = np.meshgrid(
            np.linspace(u0, u1, START_SAMPLES), np.linspace(v0, v1, START_SAMPLES), indexing="ij"
        )
        self.uv = np.column_stack([gu.ravel(), gv.ravel()])
        gq = surf.evaluate(self.uv) - o
        pxy = np.column_stack([gq @ ex, gq @ ey])
        g = pxy.reshape(START_SAMPLES, START_SAMPLES, 2)
        edges = np.concatenate(
            [
                np.hypot(*np.diff(g, axis=0).reshape(-1, 2).T),
                np.hypot(*np.diff(g, axis=1).reshape(-1, 2).T),
            ]
        )
        self.reach = float(np.max(edges)) if edges.size else 0.0
        self._pxy = pxy
        self._tree: cKDTree | None = None

    def start(self, xy: FloatArray) -> FloatArray:
        """Start parameters (m, 2) of points ``xy`` (m, 2): the nearest projected sample's."""
        if len(xy) == 0:
            return np.zeros((0, 2))
        if self._tree is None:
            self._tree = cKDTree(self._pxy)
        _, k = self._tree.query(xy)
        return np.asarray(self.uv[k])


def _residual(
    s: FloatArray, frame: tuple[FloatArray, FloatArray, FloatArray, FloatArray], xy: FloatArray
) -> FloatArray:
    """In-plane distance (m,) of surface points ``s`` (m, 3) from their targets ``xy``."""
    o, ex, ey, _ = frame
    q = s - o
    return np.asarray(np.hypot(q @ ex - xy[:, 0], q @ ey - xy[:, 1]))
