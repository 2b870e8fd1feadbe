"""Axes on curved regions checked with distances recomputed by dense sampling."""

from __future__ import annotations

import numpy as np
import pytest

from medax.axis import trace_axis
from medax.geometry import Line, Region, read_regions, region_from_dict, sample_regions_path
from medax.geometry.embedding import PlaneEmbedding
from truth import Cylinder, dense_sides

REGIONS = ("arcs", "wavy", "trapezoid", "annulus_sector")


@pytest.fixture(scope="module")
def regions() -> dict[str, Region]:
    return read_regions(sample_regions_path())


@pytest.mark.slow
@pytest.mark.parametrize("name", REGIONS)
@pytest.mark.parametrize("pair", [(0, 2), (1, 3)])
def test_points_and_spline_equidistant(regions, regions_spec, name, pair):
    a = trace_axis(regions[name], pair)
    sides = dense_sides(regions_spec[name])
    d = a.diagonal
    da, db = sides[pair[0]], sides[pair[1]]
    pts_err = np.abs(da(a.points) - db(a.points))
    # sampling error of the truth itself is ~1e-11 x diagonal on these curves
    assert pts_err.max() <= 1e-10 * d, pts_err.max() / d
    dense = a.spline.sample(10 * (a.n_points - 1) + 1)
    curve_err = np.abs(da(dense) - db(dense))
    assert curve_err.max() <= 1e-6 * d, curve_err.max() / d
    # ends on B1 and B2 (distance 0 to those sides)
    roles = a.roles
    assert sides[roles.b1](a.points[:1])[0] <= 1e-12 * d + 1e-14
    assert sides[roles.b2](a.points[-1:])[0] <= 1e-12 * d + 1e-14


def test_wavy_has_kinks_located_exactly(regions):
    """The wavy region's axis turns sharply where a foot point jumps; the spline keeps it."""
    a = trace_axis(regions["wavy"], (0, 2))
    seg = np.diff(a.points, axis=0)
    unit = seg / np.linalg.norm(seg, axis=1)[:, None]
    turn = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", unit[:-1], unit[1:]), -1, 1)))
    assert turn.max() > 5.0  # a real corner exists ...
    assert a.max_curve_error <= 1e-6 * a.diagonal  # ... and the fit does not overshoot it


def test_tolerance_is_settable(regions):
    coarse = trace_axis(regions["wavy"], (1, 3), tol=1e-3)
    fine = trace_axis(regions["wavy"], (1, 3), tol=1e-8)
    assert coarse.n_points < fine.n_points
    assert fine.max_curve_error <= 1e-8 * fine.diagonal
    assert coarse.max_curve_error <= 1e-3 * coarse.diagonal


@pytest.mark.parametrize("name", REGIONS)
def test_paper_method_meets_its_one_percent_rule(regions, name):
    for pair in ((0, 2), (1, 3)):
        a = trace_axis(regions[name], pair, method="paper")
        ratio = a.d1 / a.d2
        assert np.all((ratio > 0.99) & (ratio < 1.01))
        assert a.points.shape[0] >= 3


@pytest.mark.parametrize("name", REGIONS)
def test_clockwise_input_gives_the_same_axis(regions_spec, name):
    spec = regions_spec[name]
    ccw = region_from_dict(spec, name)
    # reverse the corner order and each side: 0->3->2->1, side k becomes reversed side
    c = spec["corners"]
    rev_corners = [c[0], c[3], c[2], c[1]]
    rev_sides = []
    for k in (3, 2, 1, 0):
        s = dict(spec["sides"][k])
        if "points" in s:
            s["points"] = s["points"][::-1]
        if "sagitta" in s:
            s["sagitta"] = -s["sagitta"]
        rev_sides.append(s)
    cw = region_from_dict({"corners": rev_corners, "sides": rev_sides}, name)
    assert cw.reoriented and not ccw.reoriented
    for pair in ((0, 2), (1, 3)):
        a = trace_axis(ccw, pair)
        # side k of the clockwise input is side (3 - k) ... of the same physical curve;
        # the pair of physical sides (0,2) there is (3,1) -> pair (1,3) in its numbering
        b = trace_axis(cw, (1, 3) if pair == (0, 2) else (0, 2))
        pa, pb = a.points, b.points
        if np.linalg.norm(pa[0] - pb[0]) > np.linalg.norm(pa[0] - pb[-1]):
            pb = pb[::-1]
        assert np.allclose(pa[[0, -1]], pb[[0, -1]], atol=1e-12 * a.diagonal)
        dense = b.spline.sample(500)
        # every point of one axis lies on the other's spline (within the curve tolerance)
        from scipy.spatial import cKDTree

        gap, _ = cKDTree(a.spline.sample(20000)).query(dense)
        assert gap.max() <= 1e-3 * a.diagonal


def test_axis_on_a_cylinder_patch_measures_in_space():
    """On a cylinder patch u in [0, 2], v in [0, 3]: between the v-edges (circle arcs at
    heights 0 and 3) the axis is v = 1.5; between the u-edges (rulings at angles 0 and 2 rad)
    it is the ruling at u = 1, both measured in space (chord distances)."""
    c = np.array([[0, 0], [2, 0], [2, 3], [0, 3]], float)
    emb = Cylinder(4.0)
    reg = Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], "cyl", embedding=emb)
    a = trace_axis(reg, (0, 2))
    assert np.max(np.abs(a.points[:, 1] - 1.5)) <= 1e-10 * a.diagonal
    b = trace_axis(reg, (1, 3))
    assert np.max(np.abs(b.points[:, 0] - 1.0)) <= 1e-10 * b.diagonal
    assert a.space_points.shape[1] == 3
    # the planar identity embedding gives the planar answer
    assert isinstance(
        Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)]).embedding, PlaneEmbedding
    )


def test_axis_on_a_curved_surface_is_equidistant_in_space():
    """A patch whose u-edges are not symmetric in space: check d1 = d2 by brute force."""
    c = np.array([[0.2, 0], [2.5, 0], [2.0, 3], [0.0, 2.5]], float)
    emb = Cylinder(2.0)
    reg = Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], "cyl2", embedding=emb)
    a = trace_axis(reg, (1, 3))
    s = np.linspace(0, 1, 200001)
    e1 = emb.evaluate(c[1] + s[:, None] * (c[2] - c[1]))
    e3 = emb.evaluate(c[3] + s[:, None] * (c[0] - c[3]))
    from scipy.spatial import cKDTree

    d1, _ = cKDTree(e1).query(a.space_points)
    d3, _ = cKDTree(e3).query(a.space_points)
    assert np.max(np.abs(d1 - d3)) <= 1e-8 * a.diagonal  # sampling error of the truth ~1e-10
