"""Axes against closed forms: bisectors of lines, middle arcs, parabolas, and bent channels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from medax.axis import trace_axis
from medax.geometry import Arc, Line, Region, read_regions, sample_regions_path
from truth import trapezoid_02_y


@pytest.fixture(scope="module")
def regions() -> dict[str, Region]:
    return read_regions(sample_regions_path())


def _spline_dense(axis, per_interval: int = 10) -> np.ndarray:
    return axis.spline.sample(per_interval * (axis.n_points - 1) + 1)


def test_trapezoid_13_is_the_line_x5(regions):
    a = trace_axis(regions["trapezoid"], (1, 3))
    d = a.diagonal
    assert np.max(np.abs(a.points[:, 0] - 5.0)) <= 1e-10 * d
    assert np.max(np.abs(_spline_dense(a)[:, 0] - 5.0)) <= 1e-6 * d
    assert np.allclose(a.points[[0, -1]], [[5, 0], [5, 6]], atol=1e-12 * d)


def test_trapezoid_02_line_and_parabolic_ends(regions):
    a = trace_axis(regions["trapezoid"], (0, 2))
    d = a.diagonal
    assert np.max(np.abs(a.points[:, 1] - trapezoid_02_y(a.points[:, 0]))) <= 1e-10 * d
    dense = _spline_dense(a)
    assert np.max(np.abs(dense[:, 1] - trapezoid_02_y(dense[:, 0]))) <= 1e-6 * d
    # exact end points on the legs (1.3, 3.12) and (8.7, 3.12)
    assert np.allclose(a.points[0], [1.3, 3.12], atol=1e-12 * d)
    assert np.allclose(a.points[-1], [8.7, 3.12], atol=1e-12 * d)
    # the parabolic pieces really are traced (points exist beyond x = 2.5 and 7.5)
    assert np.sum(a.points[:, 0] < 2.5) >= 3 and np.sum(a.points[:, 0] > 7.5) >= 3


def test_trapezoid_02_transitions_are_exact_points(regions):
    """The line-to-parabola transitions (x = 2.5 and 7.5, y = 3) are axis points exactly,
    and the fit does not pile points up around them."""
    a = trace_axis(regions["trapezoid"], (0, 2))
    d = a.diagonal
    for x in (2.5, 7.5):
        assert np.min(np.linalg.norm(a.points - [x, 3.0], axis=1)) <= 1e-12 * d
    assert a.n_points <= 30


def test_annulus_13_is_the_arc_of_radius_7(regions):
    a = trace_axis(regions["annulus_sector"], (1, 3))
    d = a.diagonal
    assert np.max(np.abs(np.linalg.norm(a.points, axis=1) - 7.0)) <= 1e-10 * d
    assert np.max(np.abs(np.linalg.norm(_spline_dense(a), axis=1) - 7.0)) <= 1e-6 * d
    ang = np.degrees(np.arctan2(a.points[:, 1], a.points[:, 0]))
    assert abs(ang[0]) < 1e-9 and abs(ang[-1] - 120.0) < 1e-9


def test_annulus_02_is_the_ray_at_60_degrees(regions):
    a = trace_axis(regions["annulus_sector"], (0, 2))
    d = a.diagonal
    normal = np.array([math.sin(math.radians(60)), -math.cos(math.radians(60))])
    assert np.max(np.abs(a.points @ normal)) <= 1e-10 * d
    r = np.linalg.norm(a.points[[0, -1]], axis=1)
    assert np.allclose(r, [5.0, 9.0], atol=1e-12 * d)


def channel(r_in: float, r_out: float, sweep_deg: float, centre=(0.0, 0.0)) -> Region:
    """A circular channel bent through ``sweep_deg`` (lines at angle 0 and sweep)."""
    c = np.asarray(centre, float)
    s = math.radians(sweep_deg)
    u0, u1 = np.array([1.0, 0.0]), np.array([math.cos(s), math.sin(s)])
    sides = [
        Line(c + r_in * u0, c + r_out * u0),
        Arc(c, r_out, 0.0, s),
        Line(c + r_out * u1, c + r_in * u1),
        Arc(c, r_in, s, -s),
    ]
    return Region.build(sides, name=f"channel{sweep_deg:g}")


@pytest.mark.parametrize("sweep", [90.0, 180.0, 270.0])
def test_bent_channel_axis_is_the_middle_arc(sweep):
    reg = channel(5.0, 9.0, sweep)
    a = trace_axis(reg, (1, 3))
    d = a.diagonal
    assert np.max(np.abs(np.linalg.norm(a.points, axis=1) - 7.0)) <= 1e-10 * d
    assert np.max(np.abs(np.linalg.norm(_spline_dense(a), axis=1) - 7.0)) <= 1e-6 * d
    end = np.degrees(np.arctan2(a.points[-1, 1], a.points[-1, 0])) % 360.0
    assert abs(end - sweep) < 1e-8


def test_270_channel_02_is_the_bisecting_ray():
    a = trace_axis(channel(5.0, 9.0, 270.0), (0, 2))
    ang = np.degrees(np.arctan2(a.points[:, 1], a.points[:, 0]))
    assert np.max(np.abs(ang - 135.0)) < 1e-9


def test_thin_straight_channel():
    # width / length = 1/100
    c = np.array([[0, 0], [100, 0], [100, 1], [0, 1]], float)
    reg = Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], name="thin")
    a = trace_axis(reg, (0, 2))
    assert np.max(np.abs(a.points[:, 1] - 0.5)) <= 1e-10 * a.diagonal
    assert np.allclose(a.points[[0, -1], 0], [0.0, 100.0], atol=1e-12 * a.diagonal)


def test_thin_curved_channel():
    reg = channel(10.0, 10.1, 200.0)
    a = trace_axis(reg, (1, 3))
    assert np.max(np.abs(np.linalg.norm(_spline_dense(a), axis=1) - 10.05)) <= 1e-6 * a.diagonal


@pytest.mark.parametrize(("shift", "scale"), [(1e6, 1.0), (0.0, 1e-6), (-3e5, 1e3)])
def test_far_from_origin_and_small_units(shift, scale):
    c = (np.array([[0, 0], [10, 0], [7.5, 6], [2.5, 6]], float) * scale) + shift
    reg = Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], name="moved")
    a = trace_axis(reg, (0, 2))
    local = (a.points - shift) / scale
    assert np.max(np.abs(local[:, 1] - trapezoid_02_y(local[:, 0]))) * scale <= 1e-10 * a.diagonal
    dense = (_spline_dense(a) - shift) / scale
    assert np.max(np.abs(dense[:, 1] - trapezoid_02_y(dense[:, 0]))) * scale <= 1e-6 * a.diagonal
