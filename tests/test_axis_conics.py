"""The closed-form axis of line and arc constraints (``medax.axis.conics``) against the
closed forms of ``_exact`` and distances recomputed by dense sampling (tests/truth.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import BSpline as ScipyBSpline

from medax.axis import trace_axis
from medax.axis.export import axis_record
from medax.geometry import region_from_dict
from truth import dense_sides

#: regions beyond the shared ones: line/arc pairs with clamped feet (trapezoid-like ends),
#: arcs bulging either way, and a bowl whose bottom foot jumps between its corners (a kink)
SPECS = {
    "arc_trapezoid": {
        "corners": [[0, 0], [10, 0], [7.5, 6], [2.5, 6]],
        "sides": [{"kind": "line"}, {"kind": "line"}, {"kind": "arc", "sagitta": 0.8},
                  {"kind": "line"}],
    },
    "arc_trapezoid_in": {
        "corners": [[0, 0], [10, 0], [7.5, 6], [2.5, 6]],
        "sides": [{"kind": "arc", "sagitta": -0.7}, {"kind": "arc", "sagitta": 0.5},
                  {"kind": "arc", "sagitta": -0.6}, {"kind": "line"}],
    },
    "bowl": {
        "corners": [[0, 0], [10, 0], [10, 10], [0, 10]],
        "sides": [{"kind": "arc", "sagitta": 4.0}, {"kind": "arc", "sagitta": -1.5},
                  {"kind": "arc", "sagitta": 1.0}, {"kind": "arc", "sagitta": -2.5}],
    },
    "lens": {
        "corners": [[0, 0], [10, 1], [9, 7], [1, 6]],
        "sides": [{"kind": "arc", "sagitta": -1.0}, {"kind": "arc", "sagitta": 1.2},
                  {"kind": "line"}, {"kind": "arc", "sagitta": 0.9}],
    },
}  # fmt: skip
CASES = [
    ("arcs", (0, 2)),
    ("arcs", (1, 3)),
    ("annulus_sector", (1, 3)),
    ("arc_trapezoid", (0, 2)),
    ("arc_trapezoid_in", (0, 2)),
    ("arc_trapezoid_in", (1, 3)),
    ("bowl", (0, 2)),
    ("bowl", (1, 3)),
    ("lens", (0, 2)),
]


def _spec(regions_spec, name: str) -> dict:
    return SPECS[name] if name in SPECS else regions_spec[name]


def _dense(axis, per_interval: int = 10) -> np.ndarray:
    """The spline 10x denser than the points (uniform in its parameter)."""
    return axis.spline.sample(per_interval * (axis.n_points - 1) + 1)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "pair"), CASES)
def test_conic_axis_against_dense_sampling(regions_spec, name, pair):
    spec = _spec(regions_spec, name)
    reg = region_from_dict(spec, name)
    a = trace_axis(reg, pair)
    d = a.diagonal
    assert a.counts.closed_form_pieces >= 1 and a.counts.predictor_steps == 0
    assert a.spline.degree == 2 and a.spline.weights is not None
    sides = dense_sides(spec)
    r = a.roles
    dense = _dense(a)
    for x in (a.points, dense):
        assert np.max(np.abs(sides[r.a1](x) - sides[r.a2](x))) <= 1e-13 * d
    assert sides[r.b1](a.points[:1])[0] <= 1e-12 * d
    assert sides[r.b2](a.points[-1:])[0] <= 1e-12 * d
    assert np.all(reg.contains(dense[1:-1]))
    assert a.max_point_error <= 1e-13 * d and a.max_curve_error <= 1e-13 * d
    # ordered from B1 to B2: no step turns back
    steps = np.diff(a.points, axis=0)
    assert np.all(np.einsum("ij,ij->i", steps[:-1], steps[1:]) > 0.0)


def test_annulus_13_is_the_arc_of_radius_7_exactly(regions_spec):
    reg = region_from_dict(regions_spec["annulus_sector"], "annulus_sector")
    a = trace_axis(reg, (1, 3))
    d = a.diagonal
    assert "arc of radius 7" in regions_spec["_exact"]["annulus_sector"]
    assert np.max(np.abs(np.linalg.norm(a.points, axis=1) - 7.0)) <= 1e-13 * d
    assert np.max(np.abs(np.linalg.norm(a.spline.sample(4001), axis=1) - 7.0)) <= 1e-13 * d
    ang = np.degrees(np.arctan2(a.points[[0, -1], 1], a.points[[0, -1], 0]))
    assert abs(ang[0]) <= 1e-12 and abs(ang[1] - 120.0) <= 1e-11


def test_exact_at_any_tolerance(regions_spec):
    reg = region_from_dict(regions_spec["arcs"], "arcs")
    a, b = trace_axis(reg, (0, 2), tol=1e-4), trace_axis(reg, (0, 2), tol=1e-10)
    assert np.array_equal(a.points, b.points)
    assert a.max_curve_error <= 1e-13 * a.diagonal


def test_bowl_kink_where_the_bottom_foot_jumps():
    """Points above the bottom arc's centre are nearest to its corners: the foot jumps from
    one corner to the other at a C0 kink, equidistant from both corners and the top arc."""
    spec = SPECS["bowl"]
    reg = region_from_dict(spec, "bowl")
    a = trace_axis(reg, (0, 2))
    d = a.diagonal
    c0, c1 = np.array(spec["corners"][0], float), np.array(spec["corners"][1], float)
    gap = np.abs(np.linalg.norm(a.points - c0, axis=1) - np.linalg.norm(a.points - c1, axis=1))
    k = int(np.argmin(gap))
    assert gap[k] <= 1e-13 * d and 0 < k < a.n_points - 1
    top = dense_sides(spec)[2]
    assert abs(top(a.points[k : k + 1])[0] - np.linalg.norm(a.points[k] - c0)) <= 1e-13 * d
    t_in, t_out = a.points[k] - a.points[k - 1], a.points[k + 1] - a.points[k]
    turn = math.degrees(math.acos(t_in @ t_out / np.linalg.norm(t_in) / np.linalg.norm(t_out)))
    assert turn > 5.0  # a real corner, not a smooth joint


@pytest.mark.slow
def test_unhandled_case_falls_back_to_the_tracer():
    """``lens (1,3)``: a foot jumps between the ends of its constraint while the other foot
    sits at an end; no hypothesis of the closed form passes its checks, so the numerical
    path runs (the batch start here; within its guarantees)."""
    spec = SPECS["lens"]
    reg = region_from_dict(spec, "lens")
    a = trace_axis(reg, (1, 3))
    d = a.diagonal
    assert a.counts.closed_form_pieces == 0
    sides = dense_sides(spec)
    assert np.max(np.abs(sides[1](a.points) - sides[3](a.points))) <= 1e-10 * d
    dense = a.spline.sample(10 * (a.n_points - 1) + 1)
    assert np.max(np.abs(sides[1](dense) - sides[3](dense))) <= 1e-6 * d


def test_record_writes_the_weights(regions_spec):
    """The JSON record's rational spline, evaluated independently (scipy, homogeneous
    coordinates), is the axis' spline."""
    reg = region_from_dict(regions_spec["arcs"], "arcs")
    a = trace_axis(reg, (0, 2))
    sp = axis_record(a)["spline"]
    kn, w = np.array(sp["knots"]), np.array(sp["weights"])
    ctrl = np.array(sp["control_points"])
    assert len(w) == len(ctrl) and len(kn) == len(ctrl) + sp["degree"] + 1
    hom = ScipyBSpline(kn, np.column_stack((ctrl * w[:, None], w)), sp["degree"])
    t = np.linspace(0.0, 1.0, 501)
    h = hom(t)
    assert np.max(np.abs(h[:, :2] / h[:, 2:] - a.spline.evaluate(t))) <= 1e-13 * a.diagonal
