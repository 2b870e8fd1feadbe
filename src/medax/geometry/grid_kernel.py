"""Compiled (numba) kernels of structured quad grids: the mesh quality pass
(:func:`medax.mesh.untangle.smooth_grid`) and its measures.

All work in place on a structured grid ``g`` (n2 + 1, n1 + 1, 2), node ``(i, j)`` at
``g[j, i]``, quad ``(i, j)`` with corners ``g[j, i], g[j, i + 1], g[j + 1, i + 1],
g[j + 1, i]`` (counter-clockwise); boundary nodes (first and last row and column) never
move:

* :func:`grid_quality` - every quad's scaled Jacobian and largest corner cosine (the
  quality pass's measures, and the untangling stage's check);
* :func:`winslow_sweeps` - Winslow's equations ``g22 x_ss - 2 g12 x_st + g11 x_tt = 0`` by
  Gauss-Seidel sweeps in row order, over-relaxed;
* :func:`optimise_nodes` - a local optimisation of listed nodes: per node one Newton step
  (gradient and Hessian by finite differences on 5 points around it) on the sum of the
  condition numbers ``(|a|^2 + |b|^2) / (2 a x b)`` of the 16 corners of its 4 quads,
  halved until the sum falls, taken only when the 4 quads' smallest scaled Jacobian and
  smallest angle do not fall: the grid's minimum scaled Jacobian and minimum angle never
  fall.

Compiled with ``cache=True`` like :mod:`medax.geometry.kernels`, which announces and warms
them up with the others (:func:`warm_up`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from medax.geometry._jit import HELPER, KERNEL
from medax.geometry._types import FloatArray, IntArray

#: halvings of a refused step before the node stays
_HALVINGS = 6
#: finite-difference step (x the node's shortest edge)
_FD_STEP = 1e-4


@njit(**HELPER)
def _corner(g: FloatArray, j: int, i: int, k: int) -> tuple[float, float, float, float]:
    """Edge vectors ``a`` (to the next corner) and ``b`` (to the previous) of corner ``k``
    of quad ``(i, j)``, as ``(ax, ay, bx, by)``."""
    if k == 0:
        pj, pi, nj, ni, qj, qi = j, i, j, i + 1, j + 1, i
    elif k == 1:
        pj, pi, nj, ni, qj, qi = j, i + 1, j + 1, i + 1, j, i
    elif k == 2:
        pj, pi, nj, ni, qj, qi = j + 1, i + 1, j + 1, i, j, i + 1
    else:
        pj, pi, nj, ni, qj, qi = j + 1, i, j, i, j + 1, i + 1
    ax = g[nj, ni, 0] - g[pj, pi, 0]
    ay = g[nj, ni, 1] - g[pj, pi, 1]
    bx = g[qj, qi, 0] - g[pj, pi, 0]
    by = g[qj, qi, 1] - g[pj, pi, 1]
    return ax, ay, bx, by


@njit(**HELPER)
def _quad(g: FloatArray, j: int, i: int) -> tuple[float, float]:
    """Quad ``(i, j)``'s scaled Jacobian (its smallest corner sine; 0 where an edge has
    zero length) and the largest cosine of its corners (its smallest angle; 2 where a
    corner is not convex)."""
    sj, cmax = 2.0, -2.0
    for k in range(4):
        ax, ay, bx, by = _corner(g, j, i, k)
        d = np.sqrt((ax * ax + ay * ay) * (bx * bx + by * by))
        if d > 0.0:
            s = (ax * by - ay * bx) / d
            c = (ax * bx + ay * by) / d
        else:
            s, c = 0.0, 2.0
        sj = min(sj, s)
        cmax = max(cmax, c if s > 0.0 else 2.0)
    return sj, cmax


@njit(**HELPER)
def _local_quality(g: FloatArray, j: int, i: int) -> tuple[float, float]:
    """The smallest scaled Jacobian of the 4 quads around node ``(i, j)`` and the largest
    cosine of their corners (see :func:`_quad`)."""
    sj, cmax = 2.0, -2.0
    for jj in range(j - 1, j + 1):
        for ii in range(i - 1, i + 1):
            s, c = _quad(g, jj, ii)
            sj = min(sj, s)
            cmax = max(cmax, c)
    return sj, cmax


@njit(**KERNEL)
def grid_quality(g: FloatArray, sj: FloatArray, cmax: FloatArray) -> None:
    """Per quad ``(i, j)`` of ``g`` (n2 + 1, n1 + 1, 2), into ``sj[j, i]`` and
    ``cmax[j, i]`` (each (n2, n1)): its scaled Jacobian and its largest corner cosine (see
    :func:`_quad`)."""
    for j in range(g.shape[0] - 1):
        for i in range(g.shape[1] - 1):
            sj[j, i], cmax[j, i] = _quad(g, j, i)


@njit(**HELPER)
def _condition(g: FloatArray, j: int, i: int) -> float:
    """Sum of the condition numbers of the 16 corners of the 4 quads around node
    ``(i, j)``; inf where a corner is not convex."""
    f = 0.0
    for jj in range(j - 1, j + 1):
        for ii in range(i - 1, i + 1):
            for k in range(4):
                ax, ay, bx, by = _corner(g, jj, ii, k)
                cr = ax * by - ay * bx
                if not cr > 0.0:
                    return np.inf
                f += 0.5 * (ax * ax + ay * ay + bx * bx + by * by) / cr
    return f


@njit(**KERNEL)
def winslow_sweeps(g: FloatArray, sweeps: int, omega: float, tol: float) -> int:
    """At most ``sweeps`` Gauss-Seidel sweeps (row order, over-relaxed by ``omega``) of
    Winslow's equations on the interior nodes of ``g`` (n2 + 1, n1 + 1, 2), in place, until
    no node moves by more than ``tol`` (length); returns the sweeps done."""
    n2, n1 = g.shape[0] - 1, g.shape[1] - 1
    for sweep in range(sweeps):
        largest = 0.0
        for j in range(1, n2):
            for i in range(1, n1):
                sx = 0.5 * (g[j, i + 1, 0] - g[j, i - 1, 0])
                sy = 0.5 * (g[j, i + 1, 1] - g[j, i - 1, 1])
                tx = 0.5 * (g[j + 1, i, 0] - g[j - 1, i, 0])
                ty = 0.5 * (g[j + 1, i, 1] - g[j - 1, i, 1])
                a = tx * tx + ty * ty
                c = sx * sx + sy * sy
                b = sx * tx + sy * ty
                den = 2.0 * (a + c)
                if not den > 0.0:
                    continue
                for d in range(2):
                    cross = g[j + 1, i + 1, d] - g[j + 1, i - 1, d] - g[j - 1, i + 1, d]
                    cross += g[j - 1, i - 1, d]
                    new = a * (g[j, i + 1, d] + g[j, i - 1, d])
                    new += c * (g[j + 1, i, d] + g[j - 1, i, d]) - 0.5 * b * cross
                    move = omega * (new / den - g[j, i, d])
                    g[j, i, d] += move
                    largest = max(largest, abs(move))
        if largest <= tol:
            return sweep + 1
    return sweeps


@njit(**KERNEL)
def optimise_nodes(g: FloatArray, nodes: IntArray, sweeps: int, tol: float) -> int:
    """At most ``sweeps`` passes over ``nodes`` (flat indices ``j (n1 + 1) + i`` of interior
    nodes of ``g`` (n2 + 1, n1 + 1, 2)), in place: each node takes a Newton step on the
    condition-number sum of its 4 quads (halved until the sum falls), kept only when their
    smallest scaled Jacobian and smallest angle do not fall; stops when no node moves by
    more than ``tol`` (length). Returns the passes done."""
    w = g.shape[1]
    fv = np.empty((3, 3))
    for sweep in range(sweeps):
        largest = 0.0
        for node in nodes:
            j, i = node // w, node % w
            ox, oy = g[j, i, 0], g[j, i, 1]
            f0 = _condition(g, j, i)
            if not np.isfinite(f0):
                continue
            h = np.inf
            for dj, di in ((0, 1), (0, -1), (1, 0), (-1, 0)):
                h = min(h, np.hypot(g[j + dj, i + di, 0] - ox, g[j + dj, i + di, 1] - oy))
            h *= _FD_STEP
            for u, v in ((0, 1), (2, 1), (1, 0), (1, 2), (2, 2)):  # the 5 points used
                g[j, i, 0] = ox + (u - 1) * h
                g[j, i, 1] = oy + (v - 1) * h
                fv[u, v] = _condition(g, j, i)
            g[j, i, 0], g[j, i, 1] = ox, oy
            gx = (fv[2, 1] - fv[0, 1]) / (2.0 * h)
            gy = (fv[1, 2] - fv[1, 0]) / (2.0 * h)
            hxx = (fv[2, 1] - 2.0 * f0 + fv[0, 1]) / (h * h)
            hyy = (fv[1, 2] - 2.0 * f0 + fv[1, 0]) / (h * h)
            hxy = (fv[2, 2] - fv[2, 1] - fv[1, 2] + f0) / (h * h)
            det = hxx * hyy - hxy * hxy
            if not (np.isfinite(det) and det > 0.0 and hxx > 0.0):
                continue
            dx = -(hyy * gx - hxy * gy) / det
            dy = -(hxx * gy - hxy * gx) / det
            s0, c0 = _local_quality(g, j, i)
            taken = False
            for _ in range(_HALVINGS):
                g[j, i, 0], g[j, i, 1] = ox + dx, oy + dy
                if _condition(g, j, i) < f0:
                    s1, c1 = _local_quality(g, j, i)
                    if s1 >= s0 and c1 <= c0:
                        taken = True
                        break
                dx *= 0.5
                dy *= 0.5
            if taken:
                largest = max(largest, abs(dx), abs(dy))
            else:
                g[j, i, 0], g[j, i, 1] = ox, oy
        if largest <= tol:
            return sweep + 1
    return sweeps


def warm_up() -> None:
    """Compile (or load from the cache) the kernels for the argument types medax uses."""
    g = np.zeros((3, 3, 2))
    g[..., 0], g[..., 1] = np.meshgrid(np.arange(3.0), np.arange(3.0))
    winslow_sweeps(g, 1, 1.0, 0.0)
    grid_quality(g, np.empty((2, 2)), np.empty((2, 2)))
    optimise_nodes(g, np.array([4], dtype=np.int64), 1, 0.0)


__all__ = ["grid_quality", "optimise_nodes", "warm_up", "winslow_sweeps"]
