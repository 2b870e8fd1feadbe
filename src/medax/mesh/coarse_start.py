"""The start of a grid level from the coarser one: nodes and feet interpolated, the cells
where the node map has a kink, and which nodes are solved rather than kept interpolated.

A node is kept where it was interpolated (:func:`refine_guess`,
:mod:`medax.mesh.grid_interp`) when three tests pass (:func:`hard_nodes`): its error
estimate is below ``INTERP_SHARE`` of the node tolerance; it lies neither in nor next to a
coarse cell where the feet show a kink (:func:`kink_cells`: a foot jumping to another part
of its side, turning fast near a focal point, or reaching the side's end); and the coarse
level's solve moved none of the coarse nodes of its stencil by more than ``MOVED_SHARE``
times the tolerance from their own interpolated start (a measured check of the estimate,
which near the end of a foot's jump was seen 3 - 77x low on ``wavy``). The shares were
set on ``wavy`` and three other regions (B-spline, polyline and mixed sides, tested): with
0.2 and 2 nodes came out up to 2.5x the tolerance off, with 0.05 and 0.5 at most 0.43x.
"""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray
from medax.mesh.grid_interp import interpolate

FOOT_JUMP = 0.05  # coarse-cell spread of foot parameters taken as a jump
FOOT_TURN = 8.0  # ... or this times the median spread on the side: the foot turns fast
INTERP_SHARE = 0.05  # solved above this share of the tolerance (the estimate can be low)
MOVED_SHARE = 0.5  # ... or where the coarse solve moved a stencil node by more than this
INTERP_MIN = 48  # divisions of a coarse level below which its interpolation is not trusted


def hard_nodes(
    estimate: FloatArray,
    kinks: np.ndarray,
    moved: FloatArray,
    n1: int,
    n2: int,
    node_tol: float,
) -> np.ndarray:
    """Interior nodes (bool ((n1 - 1) * (n2 - 1),)) of an ``n1 x n2`` grid to be solved:
    error ``estimate`` ((n1 - 1) * (n2 - 1),) above ``INTERP_SHARE * node_tol``, in or next
    to a coarse cell of ``kinks`` (c2, c1), or near a coarse node that the coarse solve
    ``moved`` ((c2 + 1, c1 + 1), see ``ratio_grid._Level``) by more than
    ``MOVED_SHARE * node_tol``."""
    return (
        (estimate > INTERP_SHARE * node_tol)
        | _near_kinks(kinks, n1, n2)
        | _rough(moved, n1, n2, MOVED_SHARE * node_tol)
    )


def _rough(moved: FloatArray, n1: int, n2: int, limit: float) -> np.ndarray:
    """Interior nodes (bool ((n1 - 1) * (n2 - 1),)) of an ``n1 x n2`` grid whose coarse
    cell has, among the 4 x 4 coarse nodes around it, one that the coarse level's solve
    moved by more than ``limit`` from its interpolated start (``moved`` (c2 + 1, c1 + 1)).

    A measured check of the estimate: halving the spacing divides the interpolation error
    by about 16 where the node map is smooth, by only 2 at a kink, so where the coarser
    interpolation was measured off by more than ``limit`` this one may be off by half of it.
    """
    c2, c1 = moved.shape[0] - 1, moved.shape[1] - 1
    near = _window_max(_window_max(moved, 0, c2), 1, c1)  # (c2, c1)
    ci, cj = _cells(np.arange(1, n1), n1, c1), _cells(np.arange(1, n2), n2, c2)
    return (near[cj][:, ci] > limit).ravel()


def _cells(i: np.ndarray, n: int, c: int) -> np.ndarray:
    """The coarse cell (of ``c``) of each node ``i`` of a grid of ``n`` divisions."""
    return np.minimum((i / n * c).astype(np.int64), c - 1)


def _window_max(values: FloatArray, axis: int, cells: int) -> FloatArray:
    """Max of ``values`` along ``axis`` over nodes ``k - 1 .. k + 2`` (clipped) for each
    cell ``k < cells``: the nodes of a cubic stencil around the cell."""
    v = np.moveaxis(values, axis, 0)
    idx = np.clip(np.arange(cells)[:, None] + np.arange(-1, 3), 0, v.shape[0] - 1)
    return np.moveaxis(v[idx].max(axis=1), 0, axis)


def _near_kinks(kinks: np.ndarray, n1: int, n2: int) -> np.ndarray:
    """Interior nodes (bool ((n1 - 1) * (n2 - 1),)) of an ``n1 x n2`` grid in or next to
    (one cell, diagonals included) a coarse cell of ``kinks`` (c2, c1): the feet place a
    kink only to within a cell, and the error estimate next to one is not to be trusted."""
    c2, c1 = kinks.shape
    near = kinks.copy()
    near[1:] |= kinks[:-1]
    near[:-1] |= kinks[1:]
    wide = near.copy()
    wide[:, 1:] |= near[:, :-1]
    wide[:, :-1] |= near[:, 1:]
    ci, cj = _cells(np.arange(1, n1), n1, c1), _cells(np.arange(1, n2), n2, c2)
    return wide[cj][:, ci].ravel()


def kink_cells(
    spread: list[FloatArray], feet: list[FloatArray], shape: tuple[int, ...]
) -> np.ndarray:
    """Cells (bool (c2, c1)) of a grid with nodes ``shape`` (c2 + 1, c1 + 1) where the node
    map has a kink, from the feet on each tracked side at the cell's corners (``spread``:
    :func:`feet_spread` of ``feet``): they spread over more than ``FOOT_JUMP`` (a foot jumps)
    or over more than ``FOOT_TURN`` times the side's median (it turns fast, near a focal
    point), or some are at an end of the side and some are not (a foot reaches it)."""
    out = np.zeros((shape[0] - 1, shape[1] - 1), dtype=bool)
    for sp, t in zip(spread, feet, strict=True):
        if t.size == 0:
            continue
        width, lo, hi = sp
        moving = width[width > 0.0]
        typical = float(np.median(moving)) if moving.size else 0.0
        out |= width > min(FOOT_JUMP, FOOT_TURN * typical)
        out |= ((lo <= 0.0) | (hi >= 1.0)) & (width > 0.0)
    return out


def refine_guess(
    cgrid: FloatArray,
    cfeet: list[FloatArray],
    cerror: FloatArray,
    kinks: np.ndarray,
    n1: int,
    n2: int,
) -> tuple[FloatArray, FloatArray, list[FloatArray]]:
    """Interior nodes ((n1 - 1) * (n2 - 1), 2) of an ``n1 x n2`` grid interpolated from a
    coarse grid (:func:`~medax.mesh.grid_interp.interpolate`, uniform in the ratios on
    both grids, no stencil across the ``kinks`` cells), the estimated error of each
    ((n1 - 1) * (n2 - 1),: the interpolation's and the coarse nodes' own, ``cerror``) and
    the feet ``cfeet`` (each (c2 + 1, c1 + 1), empty for an untracked side; the list may be
    empty: none wanted) interpolated with the same weights (each ((n1 - 1) * (n2 - 1),))."""
    uf, vf = np.arange(1, n1) / n1, np.arange(1, n2) / n2
    tracked = [k for k, f in enumerate(cfeet) if f.size]
    values = np.concatenate([cgrid] + [cfeet[k][..., None] for k in tracked], axis=-1)
    out, err = interpolate(values, uf, vf, kinks, cerror, measured=2)
    out = out.reshape(-1, values.shape[-1])
    feet = [np.empty(0)] * len(cfeet)
    for c, k in enumerate(tracked):
        feet[k] = out[:, 2 + c]
    return np.ascontiguousarray(out[:, :2]), err.ravel(), feet


def feet_spread(t: FloatArray) -> FloatArray:
    """Spread (max - min, (c2, c1)) of the feet ``t`` (c2 + 1, c1 + 1) at each cell's
    corners, and their min and max stacked: (3, c2, c1); empty for an untracked side."""
    if t.size == 0:
        return t
    a, b, c, d = t[:-1, :-1], t[:-1, 1:], t[1:, :-1], t[1:, 1:]
    lo = np.minimum(np.minimum(a, b), np.minimum(c, d))
    hi = np.maximum(np.maximum(a, b), np.maximum(c, d))
    return np.stack((hi - lo, lo, hi))


def start_feet(
    coarse: FloatArray,
    cubic: FloatArray | None,
    spread: FloatArray,
    n1: int,
    n2: int,
    rows: np.ndarray | None,
) -> FloatArray:
    """Start feet (2, len(rows)) at the interior nodes ``rows`` (all if None) of an
    ``n1 x n2`` grid: the feet ``cubic`` ((n1 - 1) * (n2 - 1),) interpolated with the
    nodes, or if None the ``coarse`` feet (c2 + 1, c1 + 1) bilinear, and a second start NaN;
    in coarse cells whose corners' feet differ by more than ``FOOT_JUMP`` (``spread``:
    :func:`feet_spread` of the coarse feet; a foot jumps to another part of the side there)
    the lowest and the highest corner foot instead, one on each part: both are tracked and
    the nearer kept (:func:`~medax.mesh.ratio_field._tracked`; the feet are certified
    global at the end)."""
    c2, c1 = spread.shape[1], spread.shape[2]
    ci, cj = _cells(np.arange(1, n1), n1, c1), _cells(np.arange(1, n2), n2, c2)  # per column, row
    if rows is None and cubic is not None:  # every node: no indices needed
        out = np.full((2, cubic.size), np.nan)
        np.clip(cubic, 0.0, 1.0, out=out[0])
        cell = (cj[:, None] * c1 + ci).ravel()
    else:
        rows = np.arange((n1 - 1) * (n2 - 1)) if rows is None else rows
        jj = rows // (n1 - 1)
        ii = rows - jj * (n1 - 1)
        out = np.full((2, rows.size), np.nan)
        if cubic is not None:
            np.clip(cubic[rows], 0.0, 1.0, out=out[0])
        else:
            out[0] = _bilinear(coarse, ii, jj, n1, n2, ci, cj)
        cell = cj[jj] * c1 + ci[ii]
    at = np.flatnonzero(spread[0].ravel()[cell] > FOOT_JUMP)
    out[0, at] = spread[1].ravel()[cell[at]]
    out[1, at] = spread[2].ravel()[cell[at]]
    return out


def _bilinear(
    coarse: FloatArray,
    ii: np.ndarray,
    jj: np.ndarray,
    n1: int,
    n2: int,
    ci: np.ndarray,
    cj: np.ndarray,
) -> FloatArray:
    """The ``coarse`` values (c2 + 1, c1 + 1) bilinear at the interior nodes ``(ii + 1,
    jj + 1)`` (each (p,)) of an ``n1 x n2`` grid, whose interior columns and rows lie in
    the coarse cells ``ci`` (n1 - 1,) and ``cj`` (n2 - 1,): (p,)."""
    c2, c1 = coarse.shape[0] - 1, coarse.shape[1] - 1
    i, j = np.arange(1, n1), np.arange(1, n2)
    fu, fv = (i / n1 * c1 - ci)[ii], (j / n2 * c2 - cj)[jj]  # (p,) the fractions in the cells
    q = cj[jj] * (c1 + 1) + ci[ii]  # (p,) the lower left corners
    flat = coarse.ravel()
    lower = flat[q] * (1.0 - fu) + flat[q + 1] * fu
    upper = flat[q + c1 + 1] * (1.0 - fu) + flat[q + c1 + 2] * fu
    return lower * (1.0 - fv) + upper * fv
