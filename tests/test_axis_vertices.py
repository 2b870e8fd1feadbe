"""Constraints with corners: the foot sits on a corner over a wedge, the axis is a parabola
there, and the transitions onto and off the corner are exact fit breaks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from medax.axis import trace_axis
from medax.geometry import Line, Polyline, Region, read_regions, sample_regions_path
from medax.mesh.mesher import mesh_region


def roof_region() -> Region:
    """S0: roof (0,0) -> (5,1) -> (10,0); S1, S3 vertical lines; S2 the line y = 6."""
    sides = [
        Polyline(np.array([[0.0, 0.0], [5.0, 1.0], [10.0, 0.0]])),
        Line(np.array([10.0, 0.0]), np.array([10.0, 6.0])),
        Line(np.array([10.0, 6.0]), np.array([0.0, 6.0])),
        Line(np.array([0.0, 6.0]), np.array([0.0, 0.0])),
    ]
    return Region.build(sides, name="roof")


@pytest.mark.slow
def test_axis_over_a_roof_corner_is_exact():
    reg = roof_region()
    a = trace_axis(reg, (0, 2), tol=1e-8)
    d = a.diagonal
    # transitions: where the axis crosses the normals of the roof's segments at the corner
    v = np.array([5.0, 1.0])
    s = 5.0 / (1.0 + 5.0 / math.sqrt(26.0))
    for n in (np.array([-1.0, 5.0]), np.array([1.0, 5.0])):
        q = v + s * n / math.sqrt(26.0)
        assert np.min(np.linalg.norm(a.points - q, axis=1)) <= 1e-10 * d
    # independent truth: distances to the roof and to y = 6 by dense sampling of the spline
    u = np.linspace(0.0, 1.0, 20001)
    x = a.spline.evaluate(u)
    roof = reg.sides[0].sample(400001)
    from scipy.spatial import cKDTree

    d_roof, _ = cKDTree(roof).query(x)
    err = np.abs(d_roof - (6.0 - x[:, 1]))
    assert err.max() <= 1e-8 * d + 1e-9  # + sampling error of the truth
    assert a.max_curve_error <= 1e-8 * d
    assert a.n_points < 80


def test_paper_mesh_of_annulus_sector_16_is_polar():
    """The recursion's sub-regions have traced axes as sides; their feet reach the corners
    where the sides were cut (regression: a transition found on an existing point)."""
    r = read_regions(sample_regions_path())["annulus_sector"]
    m = mesh_region(r, (16, 16), method="paper")
    rad = 5.0 + 4.0 * np.arange(17) / 16
    ang = np.radians(120.0) * np.arange(17) / 16
    exact = np.stack((rad[None] * np.cos(ang[:, None]), rad[None] * np.sin(ang[:, None])), -1)
    assert np.abs(m.grid() - exact).max() <= 1e-8 * r.diagonal
