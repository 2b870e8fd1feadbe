"""Interpolation of a node grid from a coarser one (cubic, kink-avoiding stencils), with an
error estimate.

A grid solved at ``c1 x c2`` divisions samples the node map ``P(u, v)`` (``u = i / c1``,
``v = j / c2``) on a uniform grid; a finer grid of the same map is taken from it by cubic
Lagrange interpolation, along ``u`` on every coarse row and then along ``v``. The map has
kinks (where a foot jumps to another part of a side, turns fast near a focal point, or
reaches a side's end) and is smooth between them; the cells a kink passes through are known
from the feet (``kinks``, see :func:`~medax.mesh.ratio_grid._kink_cells`), and each point
takes, of the three 4-node stencils around its interval, the centred one unless it crosses
such a cell, else a shifted one that does not (essentially non-oscillatory): the error
stays high only in the kink's own cells, not in the two on either side.

The error of cubic interpolation along one direction is ``P''''(xi) / 24 * prod(x - x_k)``
(``0.0234 h^4 |P''''|`` at the middle of the central interval, 0 at a node), with
``h^4 P''''`` estimated by the 4th differences of the stencil extended by a node on either
side (the larger of the two, one crossing a kink cell left out); the error of the rows
interpolated along ``u`` is carried through the absolute weights along ``v``. A point whose
every stencil crosses a kink cell gets an infinite estimate (it is solved, not
interpolated).
"""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray


def interpolate(
    grid: FloatArray,
    uf: FloatArray,
    vf: FloatArray,
    kinks: np.ndarray | None = None,
    error: FloatArray | None = None,
    measured: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The coarse ``grid`` (c2 + 1, c1 + 1, d) interpolated at ``vf x uf`` (len(vf),
    len(uf), d), both in [0, 1] (``c1, c2 >= 4``), and a bound (len(vf), len(uf)) of the
    error at each point, in the grid's units: the interpolation's, plus the errors ``error``
    (c2 + 1, c1 + 1) of the coarse nodes through the absolute weights. ``kinks`` (c2, c1):
    coarse cells that hold a kink of the map (no stencil crosses them). Only the first
    ``measured`` (default: all) of the ``d`` values enter the error estimate; the others
    are interpolated with the same stencils and weights."""
    c2, c1 = grid.shape[0] - 1, grid.shape[1] - 1
    if kinks is None:
        kinks = np.zeros((c2, c1), dtype=bool)
    # along u on coarse row j, interval i borders cells (j - 1, i) and (j, i)
    pad = np.zeros((1, c1), dtype=bool)
    rows_blocked = np.concatenate((kinks, pad)) | np.concatenate((pad, kinks))  # (c2 + 1, c1)
    carry = None if error is None else np.ascontiguousarray(error.T)
    rows, err_u = _along(np.swapaxes(grid, 0, 1), uf, rows_blocked.T, carry, measured)
    # rows: (len(uf), c2 + 1, d); along v at fine column u, interval j is cell (j, cell(u));
    # the error of the rows interpolated along u is carried through the weights along v
    cu = np.minimum((uf * c1).astype(np.int64), c1 - 1)
    rows_v = np.ascontiguousarray(np.swapaxes(rows, 0, 1))
    return _along(rows_v, vf, kinks[:, cu], np.ascontiguousarray(err_u.T), measured)


def _weights(s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Cubic Lagrange weights on nodes 0 .. 3 at positions ``s`` (any shape, in spacings
    from node 0), and the error factor ``|prod(s - k)| / 24``."""
    s1, s2, s3 = s - 1.0, s - 2.0, s - 3.0
    w = (-s1 * s2 * s3 / 6.0, s * s2 * s3 / 2.0, -s * s1 * s3 / 2.0, s * s1 * s2 / 6.0)
    return (*w, np.abs(s * s1 * s2 * s3) / 24.0)


def _along(
    values: FloatArray,
    x: FloatArray,
    blocked: np.ndarray,
    carry: FloatArray | None = None,
    measured: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """``values`` (n + 1, r, d), uniform along axis 0 on ``k / n``, interpolated at ``x``
    (m,) for each of the ``r`` columns, no stencil crossing a ``blocked`` (n, r) interval
    where another does not: values (m, r, d) and error bounds (m, r), including the errors
    ``carry`` (n + 1, r) of the values taken through the absolute weights (the estimate
    from the first ``measured`` values only).

    Most points take the centred stencil of their interval, the same for every column: those
    are rows of ``values`` combined; the few next to a kink are redone one by one."""
    n = values.shape[0] - 1
    cross = blocked[:-2] | blocked[1:-1] | blocked[2:]  # stencil s crosses: (n - 2, r)
    vm = values[..., :measured]
    d4 = np.linalg.norm(  # d4[s]: nodes s .. s + 4 (n - 3, r)
        vm[4:] - 4.0 * vm[3:-1] + 6.0 * vm[2:-2] - 4.0 * vm[1:-3] + vm[:-4], axis=-1
    )
    d4 = np.where(cross[:-1] | blocked[3:], np.inf, d4)
    cell = np.minimum((x * n).astype(np.int64), n - 1)
    b = np.clip(cell - 1, 0, n - 3)  # (m,) the centred stencils
    *w, factor = _weights(x * n - b)
    out = values[b] * w[0][:, None, None]
    for k in range(1, 4):
        out += values[b + k] * w[k][:, None, None]
    with np.errstate(invalid="ignore"):  # 0 x inf (a node next to a kink): NaN, taken as inf
        err = factor[:, None] * _d4_bound(d4[np.clip(b - 1, 0, n - 4)], d4[np.clip(b, 0, n - 4)])
    if carry is not None:
        with np.errstate(invalid="ignore"):
            for k in range(4):
                err += np.abs(w[k])[:, None] * carry[b + k]
    bad = cross[b]  # (m, r): the centred stencil crosses a kink cell
    if bad.any():
        pi, pr = np.nonzero(bad)
        bb = b[pi]
        for shift in (-1, 1):
            alt = np.clip(cell[pi] - 1 + shift, 0, n - 3)
            use = cross[bb, pr] & ~cross[alt, pr]
            bb = np.where(use, alt, bb)
        *ww, ff = _weights(x[pi] * n - bb)
        o = values[bb, pr] * ww[0][:, None]
        for k in range(1, 4):
            o += values[bb + k, pr] * ww[k][:, None]
        out[pi, pr] = o
        with np.errstate(invalid="ignore"):
            e = ff * _d4_bound(d4[np.clip(bb - 1, 0, n - 4), pr], d4[np.clip(bb, 0, n - 4), pr])
            if carry is not None:
                for k in range(4):
                    e += np.abs(ww[k]) * carry[bb + k, pr]
        e[cross[bb, pr]] = np.inf
        err[pi, pr] = e
    return out, np.where(np.isnan(err), np.inf, err)


def _d4_bound(left: FloatArray, right: FloatArray) -> FloatArray:
    """The larger of the two 4th differences (inf: crosses a kink cell), or the finite one;
    inf if neither is finite."""
    return np.where(np.isinf(left), right, np.where(np.isinf(right), left, np.maximum(left, right)))
