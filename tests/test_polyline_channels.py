"""Channels bounded by many-vertex polylines (issue 19): every vertex of a polyline is a
transition (a convex vertex: the foot rests on it) or a kink (a reflex one: the foot jumps
across it) of the axis, hundreds of breaks close together. The axis must still meet its
tolerances (measured by independent distances) and the mesh must not lose to a plain
transfinite (Coons) patch of the same boundary nodes."""

from __future__ import annotations

import numpy as np
import pytest

from medax import tolerances
from medax.axis import trace_axis
from medax.geometry.region_io import region_from_dict
from medax.mesh.mesher import mesh_region
from truth import truth_sides


def bent_channel(r0: float, r1: float, degrees: float, n: int) -> dict:
    """A channel bent through ``degrees`` around the origin: S0 the radial line at 0, S1
    the outer arc and S3 the inner arc as polylines of ``n`` vertices, S2 the radial line at
    ``degrees``."""
    a = np.linspace(0.0, np.radians(degrees), n)
    outer = np.column_stack((r1 * np.cos(a), r1 * np.sin(a)))
    inner = np.column_stack((r0 * np.cos(a), r0 * np.sin(a)))[::-1]
    corners = [[r0, 0.0], [r1, 0.0], outer[-1].tolist(), inner[0].tolist()]
    return {
        "corners": corners,
        "sides": [
            {"kind": "line"},
            {"kind": "polyline", "points": outer.tolist()},
            {"kind": "line"},
            {"kind": "polyline", "points": inner.tolist()},
        ],
    }


def check_axis(spec: dict, pair: tuple[int, int]) -> None:
    """Points, end points and spline (10 samples per point interval) within the stated
    tolerances by independent distances."""
    region = region_from_dict(spec, "c")
    axis = trace_axis(region, pair)
    side = truth_sides(spec)  # (counter-clockwise input: the file's numbering is the region's)
    ro, diag, p = axis.roles, axis.diagonal, axis.points
    gap = np.abs(side[ro.a1](p) - side[ro.a2](p)).max()
    assert gap <= tolerances.POINT_TOL * diag, gap / diag
    assert side[ro.b1](p[:1])[0] <= tolerances.ENDPOINT_TOL * diag
    assert side[ro.b2](p[-1:])[0] <= tolerances.ENDPOINT_TOL * diag
    x = axis.spline.evaluate(np.linspace(0.0, 1.0, 10 * (len(p) - 1) + 1))
    err = np.abs(side[ro.a1](x) - side[ro.a2](x)).max()
    assert err <= 1.05 * tolerances.CURVE_TOL * diag, err / diag
    assert axis.max_curve_error <= tolerances.CURVE_TOL * diag


@pytest.mark.parametrize("n", [91, 271])
def test_270_degree_polyline_channel_axis(n):
    """Pair (1, 3) of the 270-degree channel: at 271 vertices the breaks lay so close that a
    piece between two of them had 3 points ('piece N has 3 points; degree 3 needs more')."""
    check_axis(bent_channel(5.0, 9.0, 270.0, n), (1, 3))


def scaled_jacobians(grid: np.ndarray) -> np.ndarray:
    """Verdict's scaled Jacobian (min over the corners of the sine of the corner angle) of
    every quad of a structured grid (n2 + 1, n1 + 1, 2), written independently of medax."""
    p = [grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]]  # counter-clockwise
    out = np.full(p[0].shape[:2], np.inf)
    for k in range(4):
        e1, e2 = p[(k + 1) % 4] - p[k], p[k - 1] - p[k]
        cross = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
        out = np.minimum(out, cross / (np.linalg.norm(e1, axis=-1) * np.linalg.norm(e2, axis=-1)))
    return out.ravel()


def coons(grid: np.ndarray) -> np.ndarray:
    """The bilinearly blended Coons patch of a grid's boundary nodes."""
    n2, n1 = grid.shape[0] - 1, grid.shape[1] - 1
    u = (np.arange(n1 + 1) / n1)[None, :, None]
    v = (np.arange(n2 + 1) / n2)[:, None, None]
    b, t, left, right = grid[0][None], grid[-1][None], grid[:, :1], grid[:, -1:]
    c00, c10, c01, c11 = grid[0, 0], grid[0, -1], grid[-1, 0], grid[-1, -1]
    bilinear = (1 - u) * (1 - v) * c00 + u * (1 - v) * c10 + (1 - u) * v * c01 + u * v * c11
    return (1 - v) * b + v * t + (1 - u) * left + u * right - bilinear


@pytest.mark.parametrize(("r0", "r1"), [(5.0, 9.0), (5.0, 5.5)])
def test_270_degree_polyline_channel_mesh_not_below_coons(r0, r1):
    """16x16: the 5th-percentile scaled Jacobian is at least the Coons patch's of the same
    boundary nodes (it was 0.965 against 0.989), nodes on their sides, none inverted."""
    spec = bent_channel(r0, r1, 270.0, 271)
    mesh = mesh_region(region_from_dict(spec, "c"), (16, 16))
    grid = mesh.grid()
    mine, theirs = scaled_jacobians(grid), scaled_jacobians(coons(grid))
    assert np.percentile(mine, 5) >= np.percentile(theirs, 5) - 1e-12
    assert mine.min() > 0.9
    side = truth_sides(spec)
    rims = (grid[0, :], grid[:, -1], grid[-1, ::-1], grid[::-1, 0])
    for k, rim in enumerate(rims):
        assert side[k](rim).max() <= 1e-9 * mesh.region.diagonal


def thin_channel(kind: str, n: int = 300) -> dict:
    """A 1:20 channel between two ``n``-vertex polylines (S0 and S2; S1, S3 lines across):
    ``"arc"`` bent through 90 degrees (radii 12.7 and 13.7: vertices of both sides on the
    same rays, a kink and two transitions close together at each), ``"wave"`` a sine."""
    if kind == "arc":
        a = np.linspace(0.0, np.pi / 2, n)
        outer = np.column_stack((13.7 * np.cos(a), 13.7 * np.sin(a)))
        inner = np.column_stack((12.7 * np.cos(a), 12.7 * np.sin(a)))[::-1]
        lo, hi = outer, inner
    else:
        x = np.linspace(0.0, 20.0, n)
        lo = np.column_stack((x, 0.5 * np.sin(x / 3)))
        hi = np.column_stack((x, 1.0 + 0.5 * np.sin(x / 3)))[::-1]
    return {
        "corners": [lo[0].tolist(), lo[-1].tolist(), hi[0].tolist(), hi[-1].tolist()],
        "sides": [
            {"kind": "polyline", "points": lo.tolist()},
            {"kind": "line"},
            {"kind": "polyline", "points": hi.tolist()},
            {"kind": "line"},
        ],
    }


@pytest.mark.parametrize("kind", ["arc", "wave"])
def test_thin_channel_of_300_vertex_polylines(kind):
    """The axis spline along a 1:20 channel meets 1e-6 x diagonal (it ended at 2.7e-6 - 4.8e-6:
    vertices crossed between two points were never made breaks)."""
    check_axis(thin_channel(kind), (0, 2))
