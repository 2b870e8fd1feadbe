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
import scipy.sparse as sp

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
    return _along(rows_v, vf, kinks[:, cu], err_u.T, measured)


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

    Most points take the centred stencil of their interval, the same for every column: a
    banded (m, n + 1) map of the rows of ``values`` (and of the stencils' bounds and
    ``carry``); the few in a cell whose stencil is shifted off a kink are redone one by
    one."""
    n, r = values.shape[0] - 1, values.shape[1]
    cross = blocked[:-2] | blocked[1:-1] | blocked[2:]  # stencil s crosses: (n - 2, r)
    cell = np.minimum((x * n).astype(np.int64), n - 1)
    b = np.clip(cell - 1, 0, n - 3)  # (m,) the centred stencils
    *w, factor = _weights(x * n - b)
    taps = [b + k for k in range(4)]
    values = np.ascontiguousarray(values)
    out = _banded(taps, w, n + 1) @ values.reshape(n + 1, -1)
    out = out.reshape(x.size, *values.shape[1:])
    # the error: factor x the stencil's bound, then the carried errors through the absolute
    # weights (summed in this order), from the bounds and ``carry`` stacked
    sources = np.empty((n - 2 + (0 if carry is None else n + 1), r))
    bound = _stencil_bounds(values[..., :measured], cross, blocked, sources[: n - 2])
    cols, terms = [b], [factor]
    if carry is not None:
        sources[n - 2 :] = carry
        cols += [n - 2 + t for t in taps]
        terms += [np.abs(wk) for wk in w]
    err = _banded(cols, terms, sources.shape[0]) @ sources
    to_left, to_right = _shifted(cross)  # (n, r)
    redo = np.flatnonzero((to_left | to_right)[cell])  # flat (m, r)
    if redo.size:
        pi = redo // r
        pr = redo - pi * r
        # (a shift clipped at an end gives the centred stencil back: one taken is unclipped)
        bb = np.where(to_left.ravel()[cell[pi] * r + pr], b[pi] - 1, b[pi] + 1)
        held = None if carry is None else sources[n - 2 :]
        o, e = _pointwise(values, x[pi] * n - bb, bb * r + pr, bound, held)
        out.reshape(-1, out.shape[-1])[redo], err.ravel()[redo] = o, e
    err[np.isnan(err)] = np.inf  # 0 x inf (a node next to a kink)
    return out, err


def _stencil_bounds(
    values: FloatArray, cross: np.ndarray, blocked: np.ndarray, out: FloatArray
) -> FloatArray:
    """Bound (n - 2, r), into ``out``, of ``h^4 P''''`` on each stencil ``s`` (nodes
    ``s .. s + 3``) of ``values`` (n + 1, r, d): the larger of the 4th differences (norms)
    of the stencil extended by a node on either side, one crossing a kink cell left out
    (``blocked`` (n, r)), inf if both do or the stencil itself crosses one (``cross``
    (n - 2, r))."""
    norm = _d4_norms(values)  # norm[s]: nodes s .. s + 4 (n - 3, r)
    norm[cross[:-1] | blocked[3:]] = np.inf
    out[0], out[-1] = norm[0], norm[-1]  # (the one 4th difference at either end)
    inner = np.maximum(norm[:-1], norm[1:], out=out[1:-1])
    np.minimum(norm[:-1], norm[1:], out=inner, where=np.isinf(inner))  # one left out: the other
    out[cross] = np.inf
    return out


def _d4_norms(values: FloatArray) -> FloatArray:
    """Norms (n - 3, r) of the 4th differences along axis 0 of ``values`` (n + 1, r, d),
    equal to ``np.linalg.norm``'s (which sums fewer than 8 squares in order) without its
    slow reduction over a short last axis or a temporary per operation."""
    v = values
    if v.shape[-1] >= 8:
        return np.linalg.norm(
            v[4:] - 4.0 * v[3:-1] + 6.0 * v[2:-2] - 4.0 * v[1:-3] + v[:-4], axis=-1
        )
    total = np.empty((v.shape[0] - 4, *v.shape[1:-1]))
    diff, tmp = np.empty_like(total), np.empty_like(total)
    for k in range(v.shape[-1]):
        vk = v[..., k]
        np.multiply(vk[3:-1], 4.0, out=diff)
        np.subtract(vk[4:], diff, out=diff)
        diff += np.multiply(vk[2:-2], 6.0, out=tmp)
        diff -= np.multiply(vk[1:-3], 4.0, out=tmp)
        diff += vk[:-4]
        if k == 0:
            np.multiply(diff, diff, out=total)
        else:
            total += np.multiply(diff, diff, out=diff)
    return np.sqrt(total, out=total)


def _shifted(cross: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where (bool (n, r)) in each of the ``n`` cells and ``r`` columns the centred stencil
    crosses a kink cell (``cross`` (n - 2, r)) and the one shifted left does not, and where
    the left one does too but the one shifted right does not."""
    n = cross.shape[0] + 2
    centred, left, right = (np.clip(np.arange(n) - 1 + s, 0, n - 3) for s in (0, -1, 1))
    bad = cross[centred]
    to_left = bad & ~cross[left]
    return to_left, bad & ~to_left & ~cross[right]


def _banded(cols: list[np.ndarray], weights: list[FloatArray], width: int) -> sp.csr_array:
    """The sparse (m, width) map whose row ``p`` holds ``weights[k][p]`` (each (m,)) at
    column ``cols[k][p]``, increasing in ``k``: its products are summed in that order."""
    m, k = weights[0].size, len(weights)
    data = np.stack(weights, axis=1).ravel()
    return sp.csr_array(
        (data, np.stack(cols, axis=1).ravel(), np.arange(0, k * m + 1, k)), shape=(m, width)
    )


def _pointwise(
    values: FloatArray,
    s: FloatArray,
    at: np.ndarray,
    bound: FloatArray,
    carry: FloatArray | None,
) -> tuple[FloatArray, FloatArray]:
    """Values (p, d) and error bounds (p,) of single points at ``s`` (p,) spacings from
    the first nodes ``at`` (p,) of their stencils, flat indices into the rows of
    ``values`` (n + 1, r, d) (those of their columns follow ``r`` apart) and of ``bound``
    and ``carry`` (see :func:`_along`)."""
    r = values.shape[1]
    flat = values.reshape(-1, values.shape[-1])
    *w, factor = _weights(s)
    out = flat[at] * w[0][:, None]
    for k in range(1, 4):
        out += flat[at + k * r] * w[k][:, None]
    with np.errstate(invalid="ignore"):
        err = factor * bound.ravel()[at]
        if carry is not None:
            carried = carry.ravel()
            for k in range(4):
                err += np.abs(w[k]) * carried[at + k * r]
    return out, err
