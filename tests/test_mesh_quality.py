"""Verdict quad metrics against values computed by hand on single quads."""

from __future__ import annotations

import math

import numpy as np
import pytest

from medax.errors import MeshError
from medax.mesh.quality import quad_quality, summarize

Q = np.array([[0, 1, 2, 3]])
S3 = math.sqrt(3.0)


def one(points):
    return quad_quality(np.asarray(points, dtype=float), Q)


def test_unit_square():
    q = one([[0, 0], [1, 0], [1, 1], [0, 1]])
    assert q.scaled_jacobian[0] == pytest.approx(1.0)
    assert q.aspect_ratio[0] == pytest.approx(1.0)
    assert q.skew[0] == pytest.approx(0.0, abs=1e-15)
    assert q.min_angle[0] == pytest.approx(90.0)
    assert q.max_angle[0] == pytest.approx(90.0)


def test_rhombus_60_degrees():
    # side 1, angles 60/120: SJ = sin 60; AR = 0.5*1*4/(2 sin 60) = 2/sqrt3; skew = cos 60
    q = one([[0, 0], [1, 0], [1.5, S3 / 2], [0.5, S3 / 2]])
    assert q.scaled_jacobian[0] == pytest.approx(S3 / 2)
    assert q.aspect_ratio[0] == pytest.approx(2 / S3)
    assert q.skew[0] == pytest.approx(0.5)
    assert q.min_angle[0] == pytest.approx(60.0)
    assert q.max_angle[0] == pytest.approx(120.0)


def test_isosceles_trapezoid():
    # base 4, top 2, height 1: base angles 45, top 135; |L0 x L1| = 4, |L2 x L3| = 2,
    # AR = 0.5 * 4 * (6 + 2 sqrt2) / 6; principal axes (6, 0), (0, 2): skew 0
    q = one([[0, 0], [4, 0], [3, 1], [1, 1]])
    assert q.scaled_jacobian[0] == pytest.approx(math.sqrt(0.5))
    assert q.aspect_ratio[0] == pytest.approx(0.5 * 4 * (6 + 2 * math.sqrt(2)) / 6)
    assert q.skew[0] == pytest.approx(0.0, abs=1e-15)
    assert q.min_angle[0] == pytest.approx(45.0)
    assert q.max_angle[0] == pytest.approx(135.0)


def test_clockwise_square_is_inverted():
    q = one([[0, 0], [0, 1], [1, 1], [1, 0]])
    assert q.scaled_jacobian[0] == pytest.approx(-1.0)
    assert q.max_angle[0] == pytest.approx(270.0)  # Verdict: 360 - max when a corner is < 0


def test_dart_with_reflex_corner():
    # corner 3 is reflex: (P0-P3) x (P2-P3) = -2 over |.||.| = 2.5 -> -0.8; angle 360-126.87
    q = one([[0, 0], [2, 0], [2, 2], [1.5, 0.5]])
    assert q.scaled_jacobian[0] == pytest.approx(-0.8)
    assert q.min_angle[0] == pytest.approx(math.degrees(math.atan2(1, 3)))
    assert q.max_angle[0] == pytest.approx(360.0 - math.degrees(math.acos(-0.6)))


def test_square_in_space_matches_planar():
    # a unit square tilted 30 degrees about x: same metrics as in the plane
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, c, s], [0, c, s]])
    q = one(pts)
    assert q.scaled_jacobian[0] == pytest.approx(1.0)
    assert q.aspect_ratio[0] == pytest.approx(1.0)
    assert q.max_angle[0] == pytest.approx(90.0)


def test_degenerate_edge():
    q = one([[0, 0], [0, 0], [1, 1], [0, 1]])
    assert q.scaled_jacobian[0] == 0.0
    assert math.isinf(q.aspect_ratio[0])


def test_vectorised_and_summary():
    # 3 x 1 strip of unit squares plus one inverted copy
    pts = np.array([[x, y] for y in (0, 1) for x in range(4)], dtype=float)
    quads = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [0, 4, 5, 1]])
    q = quad_quality(pts, quads)
    np.testing.assert_allclose(q.scaled_jacobian, [1, 1, 1, -1])
    s = summarize(q)
    assert s["n_quads"] == 4
    assert s["n_inverted"] == 1
    assert s["n_sj_below_0_5"] == 1
    assert s["scaled_jacobian"]["min"] == -1.0
    assert s["scaled_jacobian"]["mean"] == pytest.approx(0.5)


def test_bad_shapes():
    with pytest.raises(MeshError, match="quads must be"):
        quad_quality(np.zeros((4, 2)), np.zeros((2, 3), dtype=int))
    with pytest.raises(MeshError, match="out of range"):
        quad_quality(np.zeros((4, 2)), np.array([[0, 1, 2, 4]]))


def test_quality_histograms_count_known_quads():
    """Squares (scaled Jacobian 1, angles 90) and rhombi of 62 / 118 degrees (scaled
    Jacobian sin 62, inside its bin) land in the bins their exact values fall in."""
    from medax.cad.part_report import HISTOGRAM_BINS, histograms

    c, s = np.cos(np.radians(62.0)), np.sin(np.radians(62.0))
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    rhombus = [[0, 0, 0], [1, 0, 0], [1 + c, s, 0], [c, s, 0]]
    pts = np.array([*[np.add(p, [3 * k, 0, 0]) for k in range(5) for p in square],
                    *[np.add(p, [3 * k, 5, 0]) for k in range(3) for p in rhombus]])  # fmt: skip
    quads = np.arange(len(pts)).reshape(-1, 4)
    h = histograms(quad_quality(pts, quads))
    assert set(h) == set(HISTOGRAM_BINS)
    for name, (lo, hi, n) in HISTOGRAM_BINS.items():
        assert len(h[name]["counts"]) == n and sum(h[name]["counts"]) == 8
        assert h[name]["edges"][0] == lo and h[name]["edges"][-1] == hi

    def bin_of(name, value):
        lo, hi, n = HISTOGRAM_BINS[name]
        return min(int((value - lo) / (hi - lo) * n), n - 1)

    sj = h["scaled_jacobian"]["counts"]
    assert sj[bin_of("scaled_jacobian", 1.0)] == 5 and sj[bin_of("scaled_jacobian", s)] == 3
    assert h["min_angle"]["counts"][bin_of("min_angle", 62.0)] == 3
    assert h["min_angle"]["counts"][-1] == 5  # 90 degrees: the last bin holds its top edge
    assert h["max_angle"]["counts"][bin_of("max_angle", 118.0)] == 3
    assert h["max_angle"]["counts"][0] == 5
