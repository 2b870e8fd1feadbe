"""Nodes where the two ratios of :mod:`medax.mesh.ratio_field` take given values, solved
directly.

Boundary nodes divide each side into equal arc lengths in space (as gmsh's transfinite
curves do; they are the side's curve evaluated, so they lie on it exactly). The ratio of the
crossing pair is measured at each of them, and interior node ``(i, j)`` is the root of both
equations with the transfinite blend of those boundary values: the ratio of ``(S0, S2)``
linear in ``i / n1`` between its values at node ``j`` of S3 and of S1, that of ``(S1, S3)``
linear in ``j / n2`` between node ``i`` of S0 and of S2. Where the boundary nodes are the
ends of the curves of constant ratio ``k / n`` (a rectangle, an annulus sector: equal
spacing is then the same thing), the targets are those constants and the nodes the
crossings of those curves: the uniform and the polar grid (the other rule,
``boundary="ratio"``, always places them so: :mod:`medax.mesh.boundary_nodes`).

Interior nodes are solved all at once by a damped 2-D Newton iteration, started from the
transfinite interpolation of the boundary nodes or, for large grids, from a coarser grid
interpolated. Feet on sides without a closed-form closest point (B-splines, curves on
surfaces) are tracked locally from one iteration to the next
(:func:`~medax.geometry.curve.track_closest`) once steps are small, and certified global at
the end (:func:`~medax.geometry.certify.certify_many`, a full query where that is not
conclusive); nodes whose foot was on the wrong part of a side are solved again from the
global feet.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from medax import tolerances
from medax.errors import MeshError
from medax.geometry._types import FloatArray
from medax.geometry.certify import PointGroups, certify_many, group_cells
from medax.geometry.curve import Curve, certify_closest, track_closest
from medax.geometry.region import Region
from medax.mesh.boundary_nodes import RULES, side_params
from medax.mesh.coarse_start import (
    INTERP_MIN,
    feet_spread,
    hard_nodes,
    kink_cells,
    refine_guess,
    start_feet,
)
from medax.mesh.free_field import FreeField, newton_free
from medax.mesh.grid import boundary_indices
from medax.mesh.ratio_field import (
    WEIGHTINGS,
    PlanarField,
    SideDistances,
    evaluate_field,
    pair_weighting,
)

log = logging.getLogger(__name__)
_NEWTON_ITERS = 40
_GLOBAL_ROUNDS = 3  # re-solves after the global foot check
_COARSE_MIN = 12  # grids with both counts >= 2x this start from a coarser grid
_NEWTON_SHARE = 1e-4  # residual share of the node tolerance to which free-form grids are solved
_TRACK_STEP = 1e-3  # Newton moves (x diagonal) below which feet are tracked, not searched
_SAME = 1e-15  # boundary ratios at both ends of a node row or column taken as one value
_BLOCK = 32768  # nodes solved together on the closed-form path (temporaries stay in cache)


def ratio_grid(
    region: Region,
    n1: int,
    n2: int,
    point_tol: float = tolerances.POINT_TOL,
    weighting: str = "auto",
    boundary: str = "arclength",
    node_tol: float = 0.0,
    fractions: Sequence[FloatArray] | None = None,
) -> tuple[FloatArray, dict[str, float]]:
    """Parameter-plane nodes (``(n1 + 1) * (n2 + 1)``, 2) of the ratio grid; and counts.
    ``boundary`` places the boundary nodes (:data:`~medax.mesh.boundary_nodes.RULES`).
    Solved nodes meet both equations to ``1e-3 * point_tol`` (x diagonal; on free-form
    sides to ``_NEWTON_SHARE * node_tol`` if that is larger); with ``node_tol > 0``
    (x diagonal) interior nodes on free-form sides whose interpolation from the coarser
    level is estimated within it keep the interpolated position
    (:func:`~medax.mesh.coarse_start.hard_nodes` picks the others). ``fractions``: per side
    the arc-length fractions (n + 1,) of the boundary nodes (default ``k / n``); the grid is
    then solved without a coarse start."""
    if weighting not in WEIGHTINGS:
        raise ValueError(f"unknown weighting '{weighting}'")
    if boundary not in RULES:
        raise ValueError(f"unknown boundary rule '{boundary}'")
    kinds = (pair_weighting(region, 0, 2, weighting), pair_weighting(region, 1, 3, weighting))
    tol = point_tol * region.diagonal
    levels = _levels(n1, n2) if fractions is None else [(n1, n2)]
    sides = side_params(region, levels, tol, kinds, boundary, fractions)
    level = _grid(region, levels, sides, tol, kinds, node_tol * region.diagonal, False)
    counts = level.counts
    counts["max_residual"] /= region.diagonal
    return level.grid.reshape(-1, 2), counts


def _levels(n1: int, n2: int) -> list[tuple[int, int]]:
    """Division counts of the grid and of its coarse starts, finest first: grids with both
    counts at least ``2 * _COARSE_MIN`` start from one of about half the counts."""
    out = [(n1, n2)]
    while min(out[-1]) >= 2 * _COARSE_MIN:
        c1, c2 = out[-1]
        out.append((max(_COARSE_MIN, -(-c1 // 2)), max(_COARSE_MIN, -(-c2 // 2))))
    return out


@dataclass
class _Level:
    """A solved level: nodes ``grid`` (n2 + 1, n1 + 1, 2), feet on the tracked sides (each
    (n2 + 1, n1 + 1), empty arrays for the others), the estimated error of each node
    ((n2 + 1, n1 + 1): 0 where solved), how far the solve moved each node from its
    interpolated start ((n2 + 1, n1 + 1): the measured interpolation error; 0 where not
    solved, inf where solved from no interpolation) and counts; feet, errors and moves only
    where asked for (a coarse start), else empty arrays."""

    grid: FloatArray
    feet: list[FloatArray]
    error: FloatArray
    moved: FloatArray
    counts: dict[str, float]


def _grid(
    region: Region,
    levels: list[tuple[int, int]],
    side_t: list[list[tuple[FloatArray, FloatArray]]],
    tol: float,
    kinds: tuple[str, str],
    node_tol: float,
    with_feet: bool = True,
) -> _Level:
    """The grid of ``levels[0]`` (boundary nodes and their ratios: ``side_t[0]``, see
    :func:`~medax.mesh.boundary_nodes.side_params`), feet only ``with_feet`` (a coarse
    start needs them).

    Large grids start from the coarser ``levels[1]`` (solved the same way) interpolated
    (:mod:`medax.mesh.coarse_start`), with feet interpolated too: Newton then takes small
    steps with tracked feet, and one global query per side checks them. Nodes that
    :func:`~medax.mesh.coarse_start.hard_nodes` does not pick keep the interpolated
    position.
    """
    n1, n2 = levels[0]
    idx = boundary_indices(n1, n2)
    params = np.full(((n1 + 1) * (n2 + 1), 2), np.nan)
    for side in range(4):
        params[idx[side]] = region.sides[side].evaluate(side_t[0][side][0])
    params[idx[0][[0, -1]]] = region.corners[[0, 1]]
    params[idx[2][[0, -1]]] = region.corners[[2, 3]]
    grid = params.reshape(n2 + 1, n1 + 1, 2)
    ra, rb, axes = _targets(side_t[0], n1, n2)
    m = (n1 - 1) * (n2 - 1)
    feet0: list[FloatArray] | None = None
    coarse_counts: dict[str, float] = {}
    hard = np.ones(m, dtype=bool)
    spread: list[FloatArray] = []
    fine = src = np.empty(0, dtype=np.int64)  # interior nodes copied from coarse nodes
    planar = PlanarField.supports(region, kinds)  # every foot in closed form
    if len(levels) > 1:
        coarse = _grid(region, levels[1:], side_t[1:], tol, kinds, node_tol)
        coarse_counts = coarse.counts
        spread = [feet_spread(f) for f in coarse.feet]
        kinks = kink_cells(spread, coarse.feet, coarse.grid.shape[:2])
        # feet interpolated with the nodes where this level starts a finer one (all needed)
        inner, err, cubic_feet = refine_guess(
            coarse.grid, coarse.feet if with_feet else [], coarse.error, kinks, n1, n2
        )
        if (
            node_tol > 0.0
            and min(levels[1]) >= INTERP_MIN
            and region.embedding.is_identity  # (the estimate is in parameter units)
            and not planar
        ):
            hard = hard_nodes(err, kinks, coarse.moved, n1, n2, node_tol)
        if not planar:
            # nodes on a coarse node solve the same equations: copied, with its feet (free-
            # form sides only: the closed-form path is cheaper whole, with its row weights)
            fine, src = _coincident(n1, n2, levels[1])
            copy = coarse.error.ravel()[src] == 0.0  # solved (or copied) there
            fine, src = fine[copy], src[copy]
            inner[fine] = coarse.grid.reshape(-1, 2)[src]
            err[fine], hard[fine] = 0.0, False
    else:
        inner = _coons(grid, n1, n2)[1:-1, 1:-1].reshape(-1, 2)
    rows = np.flatnonzero(hard)
    start: list[FloatArray] | None = None
    if len(levels) > 1:
        # the feet: at every node if this level starts a finer one, else at the solved ones
        at = None if with_feet else rows
        feet0 = [
            f
            if f.size == 0
            else start_feet(f, cubic_feet[k] if with_feet else None, sp, n1, n2, at)
            for k, (f, sp) in enumerate(zip(coarse.feet, spread, strict=True))
        ]
        if with_feet and fine.size:  # the copied nodes' feet are the coarse nodes' own
            for f, cf in zip(feet0, coarse.feet, strict=True):
                if f.size:
                    f[0, fine], f[1, fine] = cf.ravel()[src], np.nan
        start = [f[:, rows] if f.size and with_feet else f for f in feet0]
    solved, feet, counts = _solve(
        region, inner[rows], ra[rows], rb[rows], _newton_tol(planar, tol, node_tol),
        kinds, start,
        axes if rows.size == m else (None, None),
    )  # fmt: skip
    moved = error = np.empty((0, 0))  # (only a coarse start's are used)
    if with_feet:
        moved = np.zeros((n2 + 1, n1 + 1))  # how far the solve moved each node from its start
        if rows.size:
            step = np.zeros(m)
            if len(levels) > 1:
                d = solved - inner[rows]
                step[rows] = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
            else:
                step[rows] = np.inf
            moved[1:-1, 1:-1] = step.reshape(n2 - 1, n1 - 1)
    inner[rows] = solved
    grid[1:-1, 1:-1] = inner.reshape(n2 - 1, n1 - 1, 2)
    if with_feet:
        error = np.zeros((n2 + 1, n1 + 1))  # solved and boundary nodes: exact
        if rows.size < m:
            err[rows] = 0.0
            error[1:-1, 1:-1] = err.reshape(n2 - 1, n1 - 1)
    counts["copied"] = float(fine.size)  # on a solved coarse node: solved there
    counts["interpolated"] = float(m - rows.size - fine.size)
    # 1: the exact polar grid (the crossings of curves of constant ratio, one family rays of
    # equal angle), which the quality pass keeps as it is
    constant = axes[0] is not None and axes[1] is not None
    counts["polar_grid"] = float(constant and "angle" in kinds)
    for key in ("newton_iterations", "global_resolved", "interpolated", "copied"):
        counts[f"coarse_{key}"] = coarse_counts.get(key, 0) + coarse_counts.get(f"coarse_{key}", 0)
    own = [(idx[k], side_t[0][k][0]) for k in range(4)]
    out_feet = _level_feet(region, grid, feet0, feet, rows, kinds, own, tol) if with_feet else []
    return _Level(grid, out_feet, error, moved, counts)


def _level_feet(
    region: Region,
    grid: FloatArray,
    start: list[FloatArray] | None,
    solved: list[FloatArray],
    rows: np.ndarray,
    kinds: tuple[str, str],
    own: list[tuple[np.ndarray, FloatArray]],
    tol: float,
) -> list[FloatArray]:
    """Feet (n2 + 1, n1 + 1) of every node of ``grid`` on each tracked side: those the
    solve found at the interior nodes ``rows``, the interpolated ``start`` (2, m) at the
    others (all interior nodes solved if None), on the boundary a global query, or the
    node's own parameter on its own side (``own``: per side, node indices and
    parameters)."""
    if start is None:
        return _full_feet(region, grid, solved, kinds, own, tol)
    inner = []
    for k in range(4):
        f = start[k][0].copy() if start[k].size else start[k]
        if f.size:
            f[rows] = solved[k]
        inner.append(f)
    return _full_feet(region, grid, inner, kinds, own, tol)


def _coincident(n1: int, n2: int, coarse: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    c1, c2 = coarse
    i, j = np.arange(1, n1), np.arange(1, n2)
    i, j = i[(i * c1) % n1 == 0], j[(j * c2) % n2 == 0]
    jj, ii = np.meshgrid(j, i, indexing="ij")
    fine = ((jj - 1) * (n1 - 1) + (ii - 1)).ravel()
    src = ((jj * c2 // n2) * (c1 + 1) + ii * c1 // n1).ravel()
    return fine, src


def _newton_tol(planar: bool, tol: float, node_tol: float) -> float:
    """Residual (region units) to which nodes are solved: ``1e-3 * tol``, or on regions
    with free-form sides (not ``planar``: not every foot in closed form) ``_NEWTON_SHARE``
    of the node tolerance if that is larger (a node then sits within about that of its
    root, far inside the tolerance, and one Newton evaluation fewer is needed from an
    interpolated start)."""
    if planar:
        return 1e-3 * tol
    return max(1e-3 * tol, _NEWTON_SHARE * node_tol)


def _targets(
    sides: list[tuple[FloatArray, FloatArray]], n1: int, n2: int
) -> tuple[FloatArray, FloatArray, tuple[FloatArray | None, FloatArray | None]]:
    """The ratios ``(ra, rb)`` (each ((n1 - 1) * (n2 - 1),)) of the pairs (S0, S2) and
    (S1, S3) at the interior nodes: the transfinite blend of their values at the boundary
    nodes (``sides``: per side, parameters and the crossing pair's ratio), linear in
    ``i / n1`` between S3 and S1 and in ``j / n2`` between S0 and S2. Where both ends agree
    to round-off (``_SAME``) the blend is their mean, one value per node row of ``ra`` or per
    column of ``rb``: those values are returned too (else None), so that the weights can be
    computed once per row or column."""
    s0, s1, s2, s3 = (r for _, r in sides)
    u = (np.arange(1, n1) / n1)[None, :]
    v = (np.arange(1, n2) / n2)[:, None]
    a0, a1 = s3[::-1][1:-1], s1[1:-1]  # ratio of (S0, S2) on S3 and on S1, per row
    b0, b1 = s0[1:-1], s2[::-1][1:-1]  # ratio of (S1, S3) on S0 and on S2, per column
    rows = 0.5 * (a0 + a1) if np.abs(a0 - a1).max(initial=0.0) <= _SAME else None
    cols = 0.5 * (b0 + b1) if np.abs(b0 - b1).max(initial=0.0) <= _SAME else None
    ra = (1.0 - u) * a0[:, None] + u * a1[:, None] if rows is None else rows[:, None] + 0.0 * u
    rb = (1.0 - v) * b0[None] + v * b1[None] if cols is None else cols[None] + 0.0 * v
    return ra.ravel(), rb.ravel(), (rows, cols)


def _ring_feet(
    curve: Curve, x: FloatArray, t: FloatArray, at: np.ndarray, tol: float
) -> FloatArray:
    """Global feet (len(at),) on ``curve`` of the boundary nodes ``at`` (flat indices into
    the grid's feet ``t`` (n2 + 1, n1 + 1), interior ones known) at points ``x``: tracked
    from the nearest interior node's foot, certified global
    (:func:`~medax.geometry.curve.certify_closest`, slack ``tol``), a global query where
    that is not shown."""
    n2, n1 = t.shape[0] - 1, t.shape[1] - 1
    j, i = np.divmod(at, n1 + 1)
    start = t[np.clip(j, 1, n2 - 1), np.clip(i, 1, n1 - 1)]
    c = track_closest(curve, x, start)
    ok = certify_closest(curve, x, c.t, c.distance, tol)
    if not ok.all():
        c.t[~ok] = curve.closest(x[~ok]).t
    return c.t


def _full_feet(
    region: Region,
    grid: FloatArray,
    inner: list[FloatArray],
    kinds: tuple[str, str],
    own: list[tuple[np.ndarray, FloatArray]],
    tol: float = 0.0,
) -> list[FloatArray]:
    """Feet (n2 + 1, n1 + 1) on each tracked side: interior ones from the solve, boundary
    ones by a global query (few points), except on the side's own boundary nodes (``own``:
    per side, node indices and parameters), which lie on it; empty arrays for untracked
    sides."""
    n2, n1 = grid.shape[0] - 1, grid.shape[1] - 1
    sides = SideDistances(region, 0, kinds)
    out: list[FloatArray] = []
    ring = np.ones((n2 + 1, n1 + 1), dtype=bool)
    ring[1:-1, 1:-1] = False
    flat = grid.reshape(-1, 2)
    for k in range(4):
        if not sides.tracked[k]:
            out.append(np.empty(0))
            continue
        t = np.empty((n2 + 1, n1 + 1))
        t[1:-1, 1:-1] = inner[k].reshape(n2 - 1, n1 - 1)
        tf = t.reshape(-1)
        others = ring.copy().reshape(-1)
        others[own[k][0]] = False
        at = np.flatnonzero(others)
        tf[at] = _ring_feet(sides.curves[k], region.embedding.evaluate(flat[at]), t, at, tol)
        tf[own[k][0]] = own[k][1]
        out.append(t)
    return out


def _coons(grid: FloatArray, n1: int, n2: int) -> FloatArray:
    """Transfinite (Coons) interpolation (n2 + 1, n1 + 1, 2) of the boundary of ``grid``."""
    u = (np.arange(n1 + 1) / n1)[None, :, None]
    v = (np.arange(n2 + 1) / n2)[:, None, None]
    bottom, top = grid[0][None], grid[-1][None]
    left, right = grid[:, 0][:, None], grid[:, -1][:, None]
    c00, c10, c11, c01 = grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]
    return (
        (1 - v) * bottom + v * top + (1 - u) * left + u * right
        - ((1 - u) * (1 - v) * c00 + u * (1 - v) * c10 + u * v * c11 + (1 - u) * v * c01)
    )  # fmt: skip


def _solve(
    region: Region,
    p: FloatArray,
    ra: FloatArray,
    rb: FloatArray,
    tol: float,
    kinds: tuple[str, str],
    feet0: list[FloatArray] | None = None,
    axes: tuple[FloatArray | None, FloatArray | None] = (None, None),
) -> tuple[FloatArray, list[FloatArray], dict[str, float]]:
    """Solve ``g_a = g_b = 0`` for all rows of ``p`` (n, 2): Newton with tracked feet
    (starting from ``feet0`` if given, else from global ones), then a global check of the
    feet and a re-solve of the rows whose feet were wrong. Returns nodes, feet, counts.
    ``axes`` ``(u, v)`` say the rows are a grid whose ratios are constant along its rows
    (``ra`` is ``u`` with each value repeated) or columns (``rb`` is ``v`` tiled); None
    where they are not."""
    n = p.shape[0]
    counts = {"newton_iterations": 0, "global_resolved": 0, "max_residual": 0.0}
    if n > 0 and PlanarField.supports(region, kinds):
        # every foot in closed form: nothing to track or certify
        p, counts["newton_iterations"], res = _solve_planar(
            PlanarField(region, kinds), p, ra, rb, tol, region.diagonal, axes
        )
        _check_residual(region, res, ra, rb, tol, counts)
        return p, [np.empty(0)] * 4, counts
    sides = SideDistances(region, n, kinds)
    sides.set_tolerance(tol)
    if n == 0:
        return p, sides.t, counts
    if feet0 is not None:
        for k in range(4):
            if sides.tracked[k]:
                # NaN stays NaN: no start (a global query), or no second one
                sides.t[k] = np.clip(feet0[k][0], 0.0, 1.0)
                sides.t_alt[k] = np.clip(feet0[k][1], 0.0, 1.0)
    p = p.copy()
    res = np.zeros(n)
    rows = np.arange(n)
    unsettled = rows[:0]  # rows still off (or with wrong feet) after the global rounds
    free = FreeField.supports(region, kinds)
    for round_ in range(_GLOBAL_ROUNDS + 1):
        if free:
            p[rows], it, res[rows] = newton_free(
                sides, p[rows], ra, rb, rows, tol, _NEWTON_ITERS, _TRACK_STEP
            )
        else:
            p[rows], it, res[rows] = _newton(sides, p[rows], ra, rb, rows, tol, kinds)
        counts["newton_iterations"] += it
        # not converged: the tracked feet may have stalled it (a foot passing to another
        # part of its side between trial points): solved again from global feet
        wrong = _wrong_feet(sides, p, tol, rows)
        stuck = rows[res[rows] > tol]
        for k in range(4):
            if sides.tracked[k]:
                sides.t[k][stuck] = np.nan
        rows = np.union1d(wrong, stuck)
        if rows.size == 0:
            break
        if round_ == _GLOBAL_ROUNDS:
            unsettled = rows
            break
        counts["global_resolved"] += int(rows.size)
        log.debug("region '%s': %d nodes re-solved from global feet", region.name, rows.size)
    # the feet of every row are now the global ones (to tol): res is the true residual
    _check_residual(region, res, ra, rb, tol, counts, unsettled)
    return p, sides.t, counts


def _check_residual(
    region: Region,
    res: FloatArray,
    ra: FloatArray,
    rb: FloatArray,
    tol: float,
    counts: dict[str, float],
    unsettled: np.ndarray | None = None,
) -> None:
    """Store the worst residual in ``counts``; raise if a node did not converge (also the
    ``unsettled`` rows: still off, or their feet not the global ones, after the re-solves
    from global feet)."""
    worst = float(res.max())
    counts["max_residual"] = worst if unsettled is None or not unsettled.size else np.inf
    diag = region.diagonal
    if unsettled is not None and unsettled.size:
        bad = int(unsettled[np.argmax(res[unsettled])])
        raise MeshError(
            f"region '{region.name}': ratio curves {ra[bad]:.4g} of (S0, S2) and "
            f"{rb[bad]:.4g} of (S1, S3) do not cross: Newton did not settle on {unsettled.size} "
            f"nodes from global feet either (residual {res[bad] / diag:.2e} x diagonal); the "
            "region is too distorted for a structured grid"
        )
    if worst > 1e3 * tol or not np.isfinite(worst):
        bad = int(np.argmax(res))
        raise MeshError(
            f"region '{region.name}': ratio curves {ra[bad]:.4g} of (S0, S2) and "
            f"{rb[bad]:.4g} of (S1, S3) do not cross (Newton residual {worst / diag:.2e} x "
            "diagonal); the region is too distorted for a structured grid"
        )


def _solve_planar(
    field: PlanarField,
    p: FloatArray,
    ra: FloatArray,
    rb: FloatArray,
    tol: float,
    diag: float,
    axes: tuple[FloatArray | None, FloatArray | None] = (None, None),
) -> tuple[FloatArray, int, FloatArray]:
    """:func:`_newton` on the closed-form field, blocks of ``_BLOCK`` nodes at a time (each
    node's iteration is its own: blocking changes no result, only keeps the temporaries
    small). With the grid's ``axes`` (see :func:`_solve`) the weights are computed once per
    row or column, not per node. Returns nodes, iterations (the most of any block) and residuals."""
    n = p.shape[0]
    px, py = p[:, 0].copy(), p[:, 1].copy()
    res = np.empty(n)
    u, v = axes
    if u is None:
        wa = field.weights(0, ra)
    else:
        wa = tuple(np.repeat(w, n // max(u.size, 1)) for w in field.weights(0, u))
    if v is None:
        wb = field.weights(1, rb)
    else:
        wb = tuple(np.tile(w, n // max(v.size, 1)) for w in field.weights(1, v))
    iters = 0
    for s in range(0, n, _BLOCK):
        e = min(n, s + _BLOCK)
        it, res[s:e] = _newton_planar(
            field, px[s:e], py[s:e], tuple(w[s:e] for w in wa), tuple(w[s:e] for w in wb),
            tol, diag,
        )  # fmt: skip
        iters = max(iters, it)
    return np.column_stack((px, py)), iters, res


def _newton_planar(
    field: PlanarField,
    px: FloatArray,
    py: FloatArray,
    wa: tuple[FloatArray, ...],
    wb: tuple[FloatArray, ...],
    tol: float,
    diag: float,
) -> tuple[int, FloatArray]:
    """The damped Newton of :func:`_newton` (same steps, same backtracking on the residual
    ``hypot(g_a, g_b)``, converged rows left where they are) on coordinates ``px``, ``py``
    (updated in place) with the rows' weights ``wa``, ``wb`` (:meth:`PlanarField.weights`).
    Trial points are evaluated without gradients (most rows converge at their first trial
    point and never need one); gradients are computed for the rows still unconverged at
    the start of an iteration. While most rows are unconverged all rows are evaluated
    (converged ones with a zero step, which they accept unchanged), else the unconverged
    ones are compacted: no scatter and gather of the whole block. Returns iterations and
    residuals."""
    n = px.size
    res_out = np.empty(n)
    rows = np.arange(n)  # block rows held in the working arrays below
    x, y = px, py
    ga, gax, gay = field.pair(0, x, y, wa)
    gb, gbx, gby = field.pair(1, x, y, wb)
    res = np.sqrt(ga * ga + gb * gb)
    fresh = True  # gradients known at the working points
    max_step = 0.1 * diag
    it = 0
    while True:
        hot = res > tol
        count = int(np.count_nonzero(hot))
        if count == 0 or it == _NEWTON_ITERS:
            break
        if 2 * count <= rows.size:  # compact: keep the unconverged rows only
            done = ~hot
            px[rows[done]], py[rows[done]], res_out[rows[done]] = x[done], y[done], res[done]
            keep = np.flatnonzero(hot)
            rows = rows[keep]
            x, y, res, ga, gb = x[keep], y[keep], res[keep], ga[keep], gb[keep]
            if fresh:
                gax, gay, gbx, gby = gax[keep], gay[keep], gbx[keep], gby[keep]
            wa, wb = tuple(v[keep] for v in wa), tuple(v[keep] for v in wb)
            hot = np.ones(rows.size, dtype=bool)
            count = rows.size
        if not fresh:  # (the values come out the same as the stored ones)
            ga, gax, gay = field.pair(0, x, y, wa)
            gb, gbx, gby = field.pair(1, x, y, wb)
            fresh = True
        it += 1
        det = gax * gby - gay * gbx
        safe = np.where(np.abs(det) > 1e-300, det, 1e-300)
        sx = (gay * gb - gby * ga) / safe
        sy = (gbx * ga - gax * gb) / safe
        n2 = sx * sx + sy * sy
        if np.any(n2 > max_step * max_step):  # (else the cap is 1 for every row)
            cap = np.minimum(1.0, max_step / np.maximum(np.sqrt(n2), 1e-300))
            sx *= cap
            sy *= cap
        if count < rows.size:  # converged rows: a zero step
            sx *= hot
            sy *= hot
        # the full step for every row, then backtracking (halved steps) where it fails
        qx, qy = x + sx, y + sy
        na, nb = field.value(0, qx, qy, wa), field.value(1, qx, qy, wb)
        nres = np.sqrt(na * na + nb * nb)
        ok = nres < res * (1.0 - 1e-4) + tol
        fresh = False
        if ok.all():
            x, y, res, ga, gb = qx, qy, nres, na, nb
            continue
        for old, new in zip((x, y, res, ga, gb), (qx, qy, nres, na, nb), strict=True):
            np.copyto(old, new, where=ok)
        todo = np.flatnonzero(~ok)
        lam = 1.0
        for _ in range(11):
            lam *= 0.5
            tx, ty = x[todo] + lam * sx[todo], y[todo] + lam * sy[todo]
            ta = field.value(0, tx, ty, tuple(v[todo] for v in wa))
            tb = field.value(1, tx, ty, tuple(v[todo] for v in wb))
            tres = np.sqrt(ta * ta + tb * tb)
            good = tres < res[todo] * (1.0 - 1e-4 * lam) + tol
            acc = todo[good]
            x[acc], y[acc], res[acc], ga[acc], gb[acc] = (
                tx[good],
                ty[good],
                tres[good],
                ta[good],
                tb[good],
            )
            todo = todo[~good]
            if todo.size == 0:
                break
    px[rows], py[rows], res_out[rows] = x, y, res
    return it, res_out


def _wrong_feet(sides: SideDistances, p: FloatArray, tol: float, rows: np.ndarray) -> np.ndarray:
    """Those of ``rows`` whose tracked foot is not the global one; their feet are reset to
    the global ones."""
    x = sides.region.embedding.evaluate(p[rows])
    wrong = np.zeros(rows.size, dtype=bool)
    groups: PointGroups | None = None
    for k in range(4):
        if not sides.tracked[k]:
            continue
        curve, tk, dk = sides.curves[k], sides.t[k][rows], sides.d[k][rows]
        if groups is None and rows.size >= 2048:
            groups = PointGroups.build(x, group_cells(rows.size))
        doubt = np.flatnonzero(~certify_many(curve, x, tk, dk, tol, groups))
        if doubt.size == 0:
            continue
        c = curve.closest(x[doubt])
        bad = c.distance < dk[doubt] - tol
        sides.t[k][rows[doubt[bad]]] = c.t[bad]
        wrong[doubt[bad]] = True
    return rows[wrong]


@dataclass
class _Values:
    """Both equations at some rows: values ``ga``, ``gb`` (n,), gradients ``Ga``, ``Gb``
    (n, 2) and the feet ``(t, t, d, d)`` on sides (0, 2) and (1, 3)."""

    ga: FloatArray
    Ga: FloatArray
    gb: FloatArray
    Gb: FloatArray
    feet_a: tuple[FloatArray, ...]
    feet_b: tuple[FloatArray, ...]

    def take(self, ok: np.ndarray) -> _Values:
        return _Values(
            self.ga[ok], self.Ga[ok], self.gb[ok], self.Gb[ok],
            tuple(f[ok] for f in self.feet_a), tuple(f[ok] for f in self.feet_b),
        )  # fmt: skip

    @staticmethod
    def merge(hot: _Values, cold: _Values, warm: np.ndarray) -> _Values:
        """Rows ``warm`` from ``hot``, the others from ``cold``, in order."""

        def mix(h: FloatArray, c: FloatArray) -> FloatArray:
            out = np.empty((warm.size, *h.shape[1:]))
            out[warm], out[~warm] = h, c
            return out

        return _Values(
            mix(hot.ga, cold.ga), mix(hot.Ga, cold.Ga), mix(hot.gb, cold.gb),
            mix(hot.Gb, cold.Gb),
            tuple(mix(h, c) for h, c in zip(hot.feet_a, cold.feet_a, strict=True)),
            tuple(mix(h, c) for h, c in zip(hot.feet_b, cold.feet_b, strict=True)),
        )  # fmt: skip


@dataclass
class _System:
    """The two equations of the node ``rows`` (indices into the feet arrays of ``sides``)."""

    sides: SideDistances
    ra: FloatArray
    rb: FloatArray
    rows: np.ndarray
    kinds: tuple[str, str]

    def _part(self, q: FloatArray, sel: np.ndarray, warm: bool) -> _Values:
        gr = self.rows[sel] if warm else None
        ga, Ga, fa = evaluate_field(self.sides, 0, 2, self.ra[sel], q, self.kinds[0], gr)
        gb, Gb, fb = evaluate_field(self.sides, 1, 3, self.rb[sel], q, self.kinds[1], gr)
        return _Values(ga, Ga, gb, Gb, fa, fb)

    def evaluate(self, q: FloatArray, sel: np.ndarray, warm: np.ndarray) -> _Values:
        """Values at ``q`` (len(sel), 2) for rows ``sel``: feet tracked where ``warm``,
        found by a global query elsewhere."""
        if warm.all() or not warm.any() or not any(self.sides.tracked):
            return self._part(q, sel, bool(warm.all()))
        hot = self._part(q[warm], sel[warm], True)
        cold = self._part(q[~warm], sel[~warm], False)
        return _Values.merge(hot, cold, warm)

    def accept(self, sel: np.ndarray, v: _Values) -> None:
        """Store the feet of rows ``sel`` as the accepted ones (the next warm start)."""
        g, s = self.rows[sel], self.sides
        s.t[0][g], s.t[2][g], s.d[0][g], s.d[2][g] = v.feet_a
        s.t[1][g], s.t[3][g], s.d[1][g], s.d[3][g] = v.feet_b
        for alt in s.t_alt:  # the accepted foot is the one to follow
            alt[g] = np.nan


def _newton_step(ga: FloatArray, Ga: FloatArray, gb: FloatArray, Gb: FloatArray) -> FloatArray:
    """The Newton step (n, 2) of the 2 x 2 systems ``[Ga; Gb] step = -[ga; gb]``."""
    det = Ga[:, 0] * Gb[:, 1] - Ga[:, 1] * Gb[:, 0]
    safe = np.where(np.abs(det) > 1e-300, det, 1e-300)
    return (
        -np.column_stack((Gb[:, 1] * ga - Ga[:, 1] * gb, -Gb[:, 0] * ga + Ga[:, 0] * gb))
        / safe[:, None]
    )


def _newton(
    sides: SideDistances,
    p: FloatArray,
    ra_all: FloatArray,
    rb_all: FloatArray,
    rows: np.ndarray,
    tol: float,
    kinds: tuple[str, str],
) -> tuple[FloatArray, int, FloatArray]:
    """Damped Newton on ``g_a = g_b = 0`` for the node ``rows`` (p: (len(rows), 2)), with
    backtracking on the residual ``hypot(g_a, g_b)``. Returns nodes, iterations, residuals."""
    p = p.copy()
    system = _System(sides, ra_all[rows], rb_all[rows], rows, kinds)
    # every row starts tracked (a side without a foot yet, NaN, is queried globally)
    all_rows = np.arange(rows.size)
    v = system.evaluate(p, all_rows, np.ones(rows.size, dtype=bool))
    system.accept(all_rows, v)
    res = np.hypot(v.ga, v.gb)
    diag = sides.region.diagonal
    max_step = 0.1 * diag
    active = all_rows
    it = 0
    while it < _NEWTON_ITERS:
        active = active[res[active] > tol]
        if active.size == 0:
            break
        it += 1
        step = _newton_step(v.ga[active], v.Ga[active], v.gb[active], v.Gb[active])
        norm = np.linalg.norm(step, axis=1)
        step *= np.minimum(1.0, max_step / np.maximum(norm, 1e-300))[:, None]
        lam = np.ones(active.size)
        todo = np.arange(active.size)
        for _ in range(12):  # backtracking on the residual
            sel = active[todo]
            q = p[sel] + lam[todo, None] * step[todo]
            # feet are tracked for small moves only: a long step may cross the place where a
            # foot jumps to another part of its side, which only a global query sees
            warm = lam[todo] * norm[todo] <= _TRACK_STEP * diag
            nv = system.evaluate(q, sel, warm)
            nres = np.hypot(nv.ga, nv.gb)
            ok = nres < res[sel] * (1.0 - 1e-4 * lam[todo]) + tol
            acc, good = sel[ok], nv.take(ok)
            p[acc], res[acc] = q[ok], nres[ok]
            v.ga[acc], v.Ga[acc], v.gb[acc], v.Gb[acc] = good.ga, good.Ga, good.gb, good.Gb
            system.accept(acc, good)
            todo = todo[~ok]
            if todo.size == 0:
                break
            lam[todo] *= 0.5
        # a row with no acceptable step left its state unchanged: the next iteration would
        # repeat the same step and fail again (it stays unconverged, for the global rounds)
        active = np.setdiff1d(active, active[todo], assume_unique=True)
    return p, it, res
