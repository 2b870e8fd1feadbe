"""Structured quad meshes of a 4-sided region from medial axes (paper, section 4).

Two methods build the same kind of grid: ``n1`` strips across the pair ``(S1, S3)`` and
``n2`` across ``(S0, S2)``, node ``(i, j)`` the crossing of curve ``i`` of one family with
curve ``j`` of the other (numbering in [medax.mesh.grid][medax.mesh.grid]).

- ``"ratio"`` (default): the distance ratio ``d_a / (d_a + d_b)`` of each pair (the
  tracer's ``ratio`` curves; ``1/2`` is the medial axis), node ``(i, j)`` solved directly
  where both ratios take the blend of their values at the boundary nodes, which divide the
  sides into equal arc lengths (``medax.mesh.ratio_grid``; ``boundary="ratio"``: the
  boundary nodes at the ends of the curves of constant ratio ``k / n``, the nodes their
  crossings). Any division counts. A pair of lines whose opposite sides
  are arcs centred where the lines meet (an annulus sector) takes rays of equal angle
  instead: the exact polar grid. A planar region bent past 180 degrees around a pair of
  lines (no apex angle to divide) takes the transfinite patch of the same boundary nodes
  where that measures better (``info["interior"] = "transfinite"``).
- ``"angle"``: angle-weighted ratio curves on every pair of lines and arcs (rays of equal
  angle between lines that meet), the distance ratio elsewhere; kept for comparison.
- ``"paper"``: the paper's recursion (``medax.mesh.split``): split along the medial axis,
  recurse on both halves; the families' traced splines are then crossed
  (``medax.mesh.crossings``). Division counts that are not powers of two split unequally
  (curve ``floor(n/2)/n``); with ``size`` the paper's stopping rule applies.

``size`` sets the counts: ``n = ceil(longest of the two sides a family divides / size)``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence

import numpy as np

from medax import tolerances
from medax.errors import InputError, MeshError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve
from medax.geometry.region import Region, normalised_region
from medax.mesh.arclength import arclength_params
from medax.mesh.boundary_nodes import RULES as BOUNDARY_RULES
from medax.mesh.crossings import family_crossings
from medax.mesh.grid import QuadMesh, boundary_indices, structured_quads, transfinite_grid
from medax.mesh.obstacles import corner_angles, corner_quad_angle, obstacle, stuck_corner
from medax.mesh.quality import quad_quality
from medax.mesh.ratio_field import facing
from medax.mesh.ratio_grid import ratio_grid
from medax.mesh.split import FamilyCurve, axis_family
from medax.mesh.untangle import smooth_grid, untangle_grid

log = logging.getLogger(__name__)

METHODS = ("ratio", "angle", "paper")
#: largest division count accepted per direction
MAX_DIVISIONS = 4096


def divisions_for_size(region: Region, size: float) -> tuple[int, int]:
    """Division counts ``(n1, n2)`` so that no edge on the boundary exceeds ``size``."""
    lengths = region.side_lengths()
    if not (math.isfinite(size) and size > 0.0):
        raise InputError(f"size must be positive, got {size}")
    if size > float(lengths.max()):
        raise InputError(
            f"size {size:g} is larger than region '{region.name}' (longest side "
            f"{float(lengths.max()):.4g})"
        )
    n1 = math.ceil(max(lengths[0], lengths[2]) / size * (1.0 - 1e-12))
    n2 = math.ceil(max(lengths[1], lengths[3]) / size * (1.0 - 1e-12))
    return max(n1, 1), max(n2, 1)


#: Default node tolerance (x diagonal) of the ratio and angle methods: that of the tracer's
#: splines (``medax.tolerances.CURVE_TOL``).
NODE_TOL = tolerances.CURVE_TOL
#: Default tolerance (x diagonal) of the paper's traced splines.
PAPER_TOL = 1e-9


def mesh_region(
    region: Region,
    divisions: tuple[int, int] | None = None,
    size: float | None = None,
    method: str = "ratio",
    tol: float | None = None,
    boundary: str = "arclength",
    fractions: Sequence[FloatArray] | None = None,
    allow_inverted: bool = False,
    smooth: bool = True,
) -> QuadMesh:
    """Build a structured quad mesh of a 4-sided region from its medial axes.

    Node ``(i, j)`` is the crossing of curve ``i`` of the family across ``(S1, S3)`` with
    curve ``j`` of the family across ``(S0, S2)`` (numbering in
    [medax.mesh.grid][medax.mesh.grid]). Planar grids with inverted or near-degenerate quads
    then go through the untangling stage (``medax.mesh.untangle``; boundary nodes slide along
    their sides unless ``fractions`` fix them); where the ratio grid cannot be solved, the
    stage starts from the transfinite patch of the boundary nodes
    (``info["interior"] = "untangled"``).

    Parameters
    ----------
    region : Region
        The region ([Region][medax.geometry.region.Region]), planar or on a surface.
    divisions : tuple of int, optional
        ``(n1, n2)``: the divisions along S0 and along S1, each in 1..4096. Give exactly one
        of ``divisions`` and ``size``.
    size : float, optional
        Target edge length (region units):
        ``n = ceil(longest of the two sides a family divides / size)``.
    method : str
        ``"ratio"`` (default): curves of constant distance ratio ``d_a / (d_a + d_b)``, node
        ``(i, j)`` solved directly. ``"angle"``: angle-weighted ratio curves on lines and arcs
        (kept for comparison). ``"paper"``: the paper's recursion along medial axes.
    tol : float, optional
        Node error of the crossings, relative to the diagonal. For ``"ratio"`` and ``"angle"``
        (default [CURVE_TOL][medax.tolerances.CURVE_TOL]) interior nodes of regions with
        free-form sides are interpolated from the coarser level where its error estimate
        allows, and solved elsewhere (``0``: every node solved; boundary nodes, regions of
        lines and arcs and regions on curved faces are always solved). For ``"paper"``
        (default ``PAPER_TOL`` = 1e-9) it is the traced splines' error.
    boundary : str
        ``"ratio"`` and ``"angle"`` methods: boundary nodes at equal arc length
        (``"arclength"``, default) or at the ends of the curves of constant ratio
        (``"ratio"``, see ``medax.mesh.boundary_nodes``).
    fractions : sequence of ndarray, optional
        ``"ratio"`` and ``"angle"``, rule ``"arclength"``, with ``divisions``: per side the
        arc-length fractions (n + 1,) of its boundary nodes, from 0 to 1 in the side's
        direction (default ``k / n``), e.g. to put nodes on the vertices inside a side made
        of several CAD edges.
    allow_inverted : bool
        Return a grid that is still inverted (with a warning) instead of raising.
    smooth : bool
        Planar regions: the quality pass ``medax.mesh.untangle.smooth_grid`` (default;
        Winslow's equations on the interior nodes, kept only where it lowers neither the
        minimum nor the 5th percentile of the scaled Jacobian nor the smallest angle;
        boundary nodes and the exact polar grid stay; ``info["smooth"]``). ``False``: the
        medial grid as solved (and untangled).

    Returns
    -------
    QuadMesh
        The mesh ([QuadMesh][medax.mesh.grid.QuadMesh]); ``info`` holds counts, the
        tolerance and ``time_s``.

    Raises
    ------
    InputError
        Unknown ``method`` or ``boundary``, both or neither of ``divisions`` and ``size``,
        ``fractions`` without divisions or with another rule, divisions out of range, or a
        negative ``tol`` (zero for ``"paper"``).
    MeshError
        The grid is still inverted and not ``allow_inverted``: the message names the
        obstacle (a corner, a side).
    """
    if method not in METHODS:
        raise InputError(f"unknown mesh method '{method}' (known: {', '.join(METHODS)})")
    if boundary not in BOUNDARY_RULES:
        raise InputError(f"unknown boundary rule '{boundary}' (known: {', '.join(BOUNDARY_RULES)})")
    if (divisions is None) == (size is None):
        raise InputError("give exactly one of divisions and size")
    if fractions is not None and (
        method == "paper" or boundary != "arclength" or divisions is None
    ):
        raise InputError("boundary fractions need divisions, the arclength rule and no 'paper'")
    if divisions is not None:
        n1, n2 = (int(d) for d in divisions)
        if n1 < 1 or n2 < 1:
            raise InputError(f"divisions must be at least 1, got {n1},{n2}")
    else:
        assert size is not None
        n1, n2 = divisions_for_size(region, size)
    if max(n1, n2) > MAX_DIVISIONS:
        raise InputError(f"divisions {n1},{n2} exceed the limit {MAX_DIVISIONS} per direction")
    if tol is None:
        tol = PAPER_TOL if method == "paper" else NODE_TOL
    if not (math.isfinite(tol) and tol >= 0.0):
        raise InputError(f"tol must be a non-negative number, got {tol}")
    if method == "paper" and tol == 0.0:
        raise InputError("method 'paper' needs a positive tol (its traced splines' error)")
    t0 = time.perf_counter()
    info: dict = {}
    if method in ("angle", "ratio"):
        weighting = "angle" if method == "angle" else "auto"
        # solved centred and at unit diagonal, so that far from the origin the residual
        # tolerance (down to 1e-13 x diagonal) is still above round-off
        work, offset, scale = normalised_region(region)
        point_tol = min(tol or tolerances.POINT_TOL, tolerances.POINT_TOL)
        planar = work.embedding.is_identity
        try:
            params, info = ratio_grid(
                work, n1, n2, point_tol, weighting, boundary, node_tol=tol, fractions=fractions
            )
        except MeshError as err:
            if not planar:
                raise
            # the ratio curves do not cross everywhere: the boundary nodes at equal arc
            # length and the untangling stage from their transfinite patch
            log.info("region '%s': %s; untangling the transfinite patch", region.name, err)
            params = transfinite_grid(_arclength_rim(work, n1, n2, fractions), n1, n2)
            info = {"interior": "untangled", "ratio_grid": str(err)}
        if planar and any(not facing(work, a, a + 2) for a in (0, 1)):
            params = _not_below_transfinite(params, n1, n2, info)
        if planar:
            slide = None if fractions is not None else work.sides
            if not allow_inverted:
                _refuse_stuck_corner(region, params, n1, n2, work.sides, fractions is None)
            params = untangle_grid(params, n1, n2, slide, info=info)
            if smooth:
                exact = info.get("polar_grid", 0.0) == 1.0 and "untangle" not in info
                params = smooth_grid(params, n1, n2, info, exact=exact)
        params = params * scale + offset
    else:
        params, n1, n2 = _paper_grid(region, n1, n2, size, tol)
        if region.embedding.is_identity:
            work, offset, scale = normalised_region(region)
            local = untangle_grid((params - offset) / scale, n1, n2, work.sides, info=info)
            if smooth:
                local = smooth_grid(local, n1, n2, info)
            params = local * scale + offset
    info["time_s"] = time.perf_counter() - t0
    info["tol"] = tol
    points = region.embedding.evaluate(params)
    mesh = QuadMesh(region, params, points, n1, n2, method, info)
    bad = _inverted_count(mesh)
    if bad:
        if not allow_inverted:
            angles = corner_angles(region) if region.embedding.is_identity else None
            why = obstacle(params, n1, n2, angles) if region.embedding.is_identity else ""
            raise MeshError(
                f"region '{region.name}': no valid structured {n1}x{n2} grid found, "
                f"{bad} quads inverted{': ' + why if why else ''}"
            )
        log.warning("region '%s': %d inverted quads", region.name, bad)
    return mesh


def _refuse_stuck_corner(
    region: Region, params: FloatArray, n1: int, n2: int, sides: Sequence[Curve], slide: bool
) -> None:
    """``MeshError`` before any untangling when a corner's quad cannot be convex (its
    angle 180 degrees or more wherever the first boundary nodes slide; with ``slide``
    False where they are)."""
    if slide:
        hit = stuck_corner(params, n1, n2, sides)
    else:
        quad = [corner_quad_angle(params, n1, n2, k) for k in range(4)]
        k = int(np.argmax(quad))
        hit = (k, quad[k]) if quad[k] >= 180.0 else None
    if hit is None:
        return
    k, ang = hit
    own = corner_angles(region)[k]
    kind = "reflex corner" if own >= 180.0 else "corner"
    raise MeshError(
        f"region '{region.name}': no valid structured {n1}x{n2} grid: {kind} {k} between "
        f"sides {(k - 1) % 4} and {k} ({own:.1f} degrees between the sides' tangents): its "
        f"quad's angle there is at least {ang:.1f} degrees wherever the boundary nodes slide "
        "(a structured grid's corner quad takes the corner's angle)"
    )


def _arclength_rim(
    region: Region, n1: int, n2: int, fractions: Sequence[FloatArray] | None
) -> FloatArray:
    """A grid ((n1 + 1) * (n2 + 1), 2) with its boundary nodes at equal arc length (or at
    ``fractions`` of it) on each side of the planar ``region`` and NaN inside."""
    params = np.full(((n1 + 1) * (n2 + 1), 2), np.nan)
    for k, idx in enumerate(boundary_indices(n1, n2)):
        n = n1 if k % 2 == 0 else n2
        fr = np.arange(n + 1) / n if fractions is None else np.asarray(fractions[k], float)
        params[idx] = region.sides[k].evaluate(arclength_params(region.sides[k], fr))
    return params


def _not_below_transfinite(params: FloatArray, n1: int, n2: int, info: dict) -> FloatArray:
    """``params``, or the transfinite patch of its boundary nodes where that measures better
    (no inverted quad, higher 5th-percentile scaled Jacobian): a region bent past 180
    degrees around a pair of lines has no apex angle for the polar rule, and the distance
    ratio's curves there are not rays (a 270-degree channel: p5 0.965 against 0.989)."""
    quads = structured_quads(n1, n2)
    mine = quad_quality(params, quads).scaled_jacobian
    coons = transfinite_grid(params, n1, n2)
    theirs = quad_quality(coons, quads).scaled_jacobian
    if theirs.min() > 0.0 and np.percentile(theirs, 5) > np.percentile(mine, 5):
        info["interior"] = "transfinite"  # (the ratio grid measured worse)
        return coons
    return params


def _inverted_count(mesh: QuadMesh) -> int:
    """Quads with a corner that is not counter-clockwise (planar: the cross products of the
    grid's edges, in bands of rows; in space: the scaled Jacobian of the quality metrics)."""
    if mesh.points.shape[1] != 2:
        return int(np.count_nonzero(mesh.quality().scaled_jacobian <= 0.0))
    g = mesh.grid()
    bad = 0
    band = max(1, 32768 // g.shape[1])
    for j0 in range(0, g.shape[0] - 1, band):
        b = g[j0 : j0 + band + 1]
        x, y = np.ascontiguousarray(b[..., 0]), np.ascontiguousarray(b[..., 1])
        # edges along i (hx, hy) and along j (vx, vy); the corner of quad (i, j) at row
        # jj in {j, j + 1} and column ii in {i, i + 1} turns counter-clockwise when
        # cross(h[jj, i], v[j, ii]) > 0 (its two edges, both away from it or both towards)
        hx, hy = np.diff(x, axis=1), np.diff(y, axis=1)
        vx, vy = np.diff(x, axis=0), np.diff(y, axis=0)
        flag = np.zeros(vx[:, 1:].shape, dtype=bool)
        for jj in (slice(None, -1), slice(1, None)):
            for ii in (slice(None, -1), slice(1, None)):
                c = hx[jj] * vy[:, ii]
                c -= hy[jj] * vx[:, ii]
                flag |= c <= 0.0
        bad += int(np.count_nonzero(flag))
    return bad


def _paper_grid(
    region: Region, n1: int, n2: int, size: float | None, tol: float
) -> tuple[np.ndarray, int, int]:
    """Nodes of the paper's recursion; with ``size`` the counts come from the recursion."""
    diag = region.diagonal
    if size is not None:
        fam_v = axis_family(region, (1, 3), size=size, tol=tol)  # curves S0 -> S2, S1 -> S3
        fam_u = axis_family(region, (0, 2), size=size, tol=tol)  # curves S3 -> S1, S0 -> S2
    else:
        fam_v = axis_family(region, (1, 3), divisions=n1, tol=tol)
        fam_u = axis_family(region, (0, 2), divisions=n2, tol=tol)
    n1, n2 = len(fam_v) + 1, len(fam_u) + 1
    params = np.full(((n1 + 1) * (n2 + 1), 2), np.nan)
    grid = params.reshape(n2 + 1, n1 + 1, 2)
    s = region.sides
    # pair (1, 3): A1 = S1, B1 = S0, B2 = S2; its curves ordered from S1 to S3 = i from n1 down
    for k, fc in enumerate(fam_v):
        i = n1 - 1 - k
        grid[0, i] = s[0].evaluate(np.array([fc.t_b1]))[0]
        grid[-1, i] = s[2].evaluate(np.array([fc.t_b2]))[0]
    # pair (0, 2): A1 = S0, B1 = S3, B2 = S1; curves ordered from S0 to S2 = j upwards
    for k, fc in enumerate(fam_u):
        j = k + 1
        grid[j, 0] = s[3].evaluate(np.array([fc.t_b1]))[0]
        grid[j, -1] = s[1].evaluate(np.array([fc.t_b2]))[0]
    c = region.corners
    grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0] = c[0], c[1], c[2], c[3]
    if fam_u and fam_v:
        cross = family_crossings(
            [f.curve for f in fam_u], [f.curve for f in fam_v], 1e-2 * tol * diag,
            what=f"region '{region.name}'",
        )  # fmt: skip
        # cross[j-1, k] is curve j of (0, 2) with curve k of (1, 3), i.e. node (n1-1-k, j)
        grid[1:-1, 1:-1] = cross[:, ::-1]
    if not np.all(np.isfinite(params)):
        raise MeshError(f"region '{region.name}': grid has unset nodes")  # pragma: no cover
    _check_boundary(region, params, n1, n2)
    return params, n1, n2


def _check_boundary(region: Region, params: np.ndarray, n1: int, n2: int) -> None:
    """Boundary nodes must be in order along their sides (else the grid folds)."""
    for k, idx in enumerate(boundary_indices(n1, n2)):
        t = region.sides[k].closest(params[idx]).t
        if np.any(np.diff(t) <= 0.0):
            raise MeshError(
                f"region '{region.name}': nodes on side {k} are out of order (curves of the "
                "other family cross before reaching it)"
            )


__all__ = ["METHODS", "FamilyCurve", "divisions_for_size", "mesh_region"]
