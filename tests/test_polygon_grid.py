"""The scanline grid test against matplotlib's point-in-polygon, point by point."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.path import Path

from medax.geometry.polygon_grid import inside_grid


def _star(n: int, rng: np.random.Generator) -> np.ndarray:
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    rad = rng.uniform(0.3, 1.0, n)
    return np.column_stack([rad * np.cos(ang), rad * np.sin(ang)])


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_matches_contains_points_on_random_polygons(scale):
    """At any scale: the columns' searches are one search over shifted values."""
    rng = np.random.default_rng(3)
    xs, ys = np.linspace(-1.1, 1.1, 157) * scale, np.linspace(-1.05, 1.05, 143) * scale
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    pts = np.column_stack([gx.ravel(), gy.ravel()])
    for n in (3, 7, 40, 300):
        poly = _star(n, rng) * scale
        ref = Path(poly).contains_points(pts).reshape(gx.shape)
        got = inside_grid(xs, ys, poly)
        assert np.count_nonzero(got != ref) == 0


def test_square_with_vertices_on_grid_columns():
    """Columns through vertices and along vertical edges: each crossing counted once."""
    xs = ys = np.linspace(-0.5, 1.5, 9)  # contains 0, 1 (the vertical edges)
    sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    got = inside_grid(xs, ys + 0.01, sq)  # rows off the horizontal edges
    want = (xs[:, None] >= 0.0) & (xs[:, None] < 1.0) & (ys[None, :] + 0.01 > 0.0)
    want &= ys[None, :] + 0.01 < 1.0
    assert np.array_equal(got, want)
