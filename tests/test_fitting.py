"""Interpolating B-splines with C0 breaks: short pieces between close breaks."""

from __future__ import annotations

import numpy as np
import pytest

from medax.errors import CurveError
from medax.geometry.fitting import interpolate


@pytest.mark.parametrize("degree", [2, 3, 5])
def test_short_pieces_are_their_lower_degree_polynomials(degree):
    """Breaks 2 and 3 leave pieces of 3 and 2 points: the spline passes through every point,
    the 2-point piece is the straight segment and the 3-point piece the parabola through
    its points (in the chord-length parameter)."""
    t = np.linspace(0.0, 1.0, 12) ** 1.3
    pts = np.column_stack((np.cos(3 * t), np.sin(2 * t) + t))
    spline, u = interpolate(pts, [2, 3, 6], degree)
    assert np.abs(spline.evaluate(u) - pts).max() <= 1e-13
    s = np.linspace(u[2], u[3], 9)  # the 2-point piece
    line = pts[2] + ((s - u[2]) / (u[3] - u[2]))[:, None] * (pts[3] - pts[2])
    assert np.abs(spline.evaluate(s) - line).max() <= 1e-13
    s = np.linspace(u[0], u[2], 9)  # the 3-point piece: Lagrange through its points
    want = sum(
        pts[k] * np.prod([(s - u[m]) / (u[k] - u[m]) for m in range(3) if m != k], axis=0)[:, None]
        for k in range(3)
    )
    assert np.abs(spline.evaluate(s) - want).max() <= 1e-12


def test_empty_piece_refused():
    pts = np.column_stack((np.arange(6.0), np.arange(6.0) ** 2))
    with pytest.raises(CurveError, match="breaks"):
        interpolate(pts, [2, 2], 3)
