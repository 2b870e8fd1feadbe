"""Pcurve sides of a loose input close at their corners within the face's vertex tolerance
(truth: the corner gaps measured in space on a known surface, and the sides' other points
unmoved)."""

from __future__ import annotations

import numpy as np

from medax.cad.face_region import closed_corners
from medax.geometry.bspline import BSpline


class _Scaled:
    """A plane u, v -> (2u, 3v, 0): lengths in space differ from those in (u, v)."""

    def evaluate(self, p: np.ndarray) -> np.ndarray:
        p = np.atleast_2d(p)
        return np.column_stack([2.0 * p[:, 0], 3.0 * p[:, 1], np.zeros(len(p))])


def _square(gap: np.ndarray) -> list[BSpline]:
    """A unit square's four sides as cubics; side 0 ends ``gap`` away from side 1's start."""
    c = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    sides = []
    for k in range(4):
        a, b = c[k], c[(k + 1) % 4]
        pts = a + np.linspace(0, 1, 4)[:, None] * (b - a)
        if k == 0:
            pts[-1] += gap
        sides.append(BSpline(pts, 3))
    return sides


def test_loose_corner_closes_within_the_vertex_tolerance():
    gap = np.array([1e-6, -2e-6])  # 6.3e-6 in space on the scaled plane
    sides = closed_corners(_square(gap), _Scaled(), 1e-5)
    for k in range(4):
        assert np.array_equal(sides[k].control_points[-1], sides[(k + 1) % 4].control_points[0])
    assert np.allclose(sides[0].control_points[-1], [1, 0] + gap / 2, rtol=0, atol=1e-15)
    # nothing else moved: the inner control points and the other corners are as built
    ref = _square(gap)
    assert np.array_equal(sides[0].control_points[:-1], ref[0].control_points[:-1])
    assert np.array_equal(sides[2].control_points, ref[2].control_points)


def test_gap_above_the_tolerance_or_a_period_stays_open():
    gap = np.array([1e-6, -2e-6])
    sides = closed_corners(_square(gap), _Scaled(), 5e-6)  # 6.3e-6 in space: too far
    assert not np.array_equal(sides[0].control_points[-1], sides[1].control_points[0])
    period = np.array([0.0, 2 * np.pi])  # a seam's period apart in v: no gap to close

    class _Periodic(_Scaled):
        def evaluate(self, p: np.ndarray) -> np.ndarray:
            p = np.atleast_2d(p)
            return super().evaluate(np.column_stack([p[:, 0], np.mod(p[:, 1], 2 * np.pi)]))

    sides = closed_corners(_square(period), _Periodic(), 1e-5)
    assert np.array_equal(sides[0].control_points[-1], [1.0, 2 * np.pi])
