"""The closed-form axis of two line-segment constraints (``medax.axis.segments``) against
closed forms, distances recomputed by dense sampling, and the general tracer."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import BSpline as ScipyBSpline

from medax.axis import trace_axis
from medax.errors import CurveError
from medax.geometry import Arc, BSpline, Line, Region, read_region, region_from_dict
from medax.geometry import sample_regions_path as samples
from truth import DenseDistance, dense_sides, side_function, trapezoid_02_y


def _dense(axis, per_interval: int = 10) -> np.ndarray:
    """The spline 10x denser than the points."""
    return axis.spline.sample(per_interval * (axis.n_points - 1) + 1)


def _segment_distance(p: np.ndarray, a, b) -> np.ndarray:
    """Distance of points (n, 2) to the segment a-b by 20001 samples + the exact
    projection onto the nearest sample's neighbouring chords (independent of medax)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    s = np.linspace(0.0, 1.0, 20001)
    q = a + s[:, None] * (b - a)
    i = np.argmin(np.linalg.norm(p[:, None, :] - q[None], axis=2), axis=1)
    best = np.full(len(p), np.inf)
    for j in (i - 1, i):
        j = np.clip(j, 0, len(s) - 2)
        q0, q1 = q[j], q[j + 1]
        t = np.clip(np.sum((p - q0) * (q1 - q0), axis=1) / np.sum((q1 - q0) ** 2, axis=1), 0, 1)
        best = np.minimum(best, np.linalg.norm(q0 + t[:, None] * (q1 - q0) - p, axis=1))
    return best


def _equidistance(axis, pts: np.ndarray) -> float:
    """max |d1 - d2| at pts by dense sampling of the two constraint segments."""
    a1 = axis.region.sides[axis.roles.a1]
    a2 = axis.region.sides[axis.roles.a2]
    d1 = _segment_distance(pts, a1.start, a1.end)
    d2 = _segment_distance(pts, a2.start, a2.end)
    return float(np.max(np.abs(d1 - d2)))


def _quad(corners, name: str = "quad") -> Region:
    c = np.asarray(corners, float)
    return Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], name=name)


def _line_distance(p: np.ndarray, a, b) -> np.ndarray:
    """Distance of points to the segment a-b (closed form, for the end point checks)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * (b - a) - p, axis=1)


@pytest.fixture(scope="module")
def trapezoid() -> Region:
    return read_region(samples(), "trapezoid")


def test_trapezoid_13_is_x5_exactly(trapezoid, regions_spec):
    a = trace_axis(trapezoid, (1, 3))
    d = a.diagonal
    # the interior and the both-clamped pieces lie on one line: one Bezier piece
    assert a.counts.closed_form_pieces == 1 and a.counts.predictor_steps == 0
    assert a.spline.degree == 2
    # _exact: the line x = 5 from y = 0 to y = 6
    assert "x=5 from y=0 to y=6" in regions_spec["_exact"]["trapezoid"]
    assert np.max(np.abs(a.points[:, 0] - 5.0)) <= 1e-12 * d
    assert np.max(np.abs(_dense(a)[:, 0] - 5.0)) <= 1e-12 * d
    assert np.allclose(a.points[[0, -1]], [[5.0, 0.0], [5.0, 6.0]], rtol=0, atol=1e-12 * d)
    assert np.all(np.diff(a.points[:, 1]) > 0)  # ordered B1 -> B2
    sides = dense_sides(regions_spec["trapezoid"])
    assert np.max(np.abs(sides[1](a.points) - sides[3](a.points))) <= 1e-10 * d
    assert a.max_point_error <= 1e-12 * d and a.max_curve_error <= 1e-12 * d


def test_trapezoid_02_line_and_parabolas_exactly(trapezoid, regions_spec):
    a = trace_axis(trapezoid, (0, 2))
    d = a.diagonal
    assert a.counts.closed_form_pieces == 3  # parabola, line, parabola
    assert np.max(np.abs(a.points[:, 1] - trapezoid_02_y(a.points[:, 0]))) <= 1e-12 * d
    dense = _dense(a)
    assert np.max(np.abs(dense[:, 1] - trapezoid_02_y(dense[:, 0]))) <= 1e-10 * d
    # ends on the legs at (1.3, 3.12) and (8.7, 3.12); the transitions are points
    assert np.allclose(a.points[0], [1.3, 3.12], rtol=0, atol=1e-12 * d)
    assert np.allclose(a.points[-1], [8.7, 3.12], rtol=0, atol=1e-12 * d)
    for x in (2.5, 7.5):
        assert np.min(np.linalg.norm(a.points - [x, 3.0], axis=1)) <= 1e-12 * d
    assert np.sum(a.points[:, 0] < 2.5) >= 3 and np.sum(a.points[:, 0] > 7.5) >= 3
    sides = dense_sides(regions_spec["trapezoid"])
    assert np.max(np.abs(sides[0](a.points) - sides[2](a.points))) <= 1e-10 * d
    assert _equidistance(a, dense) <= 1e-10 * d


def test_annulus_02_is_the_ray_at_60_degrees(regions_spec):
    reg = region_from_dict(regions_spec["annulus_sector"], "annulus_sector")
    a = trace_axis(reg, (0, 2))
    d = a.diagonal
    assert a.counts.closed_form_pieces == 1  # both feet at the inner corners throughout
    normal = np.array([math.sin(math.radians(60)), -math.cos(math.radians(60))])
    assert np.max(np.abs(a.points @ normal)) <= 1e-12 * d
    assert np.max(np.abs(_dense(a) @ normal)) <= 1e-12 * d
    # ends on the arcs B1 (r = 5) and B2 (r = 9), exactly
    r = np.linalg.norm(a.points[[0, -1]], axis=1)
    assert np.allclose(r, [5.0, 9.0], rtol=0, atol=1e-12 * d)
    sides = dense_sides(regions_spec["annulus_sector"])
    assert np.max(np.abs(sides[0](a.points) - sides[2](a.points))) <= 1e-10 * d
    assert _equidistance(a, _dense(a)) <= 1e-10 * d


#: an asymmetric quad whose axis (pair 0, 2) has a parabolic piece about the corner (3, 7)
SKEW = [[0.0, 0.0], [10.0, 0.0], [9.0, 5.0], [3.0, 7.0]]


def test_parabolic_pieces_point_by_point():
    """Beyond the normal lines at A2's ends its foot is clamped at the corner: there the
    axis is the parabola with that corner as focus and A1's line y = 0 as directrix."""
    reg = _quad(SKEW, "skew")
    a = trace_axis(reg, (0, 2))
    d = a.diagonal
    start, end = np.array([9.0, 5.0]), np.array([3.0, 7.0])  # A2 runs from (9, 5) to (3, 7)
    length = np.linalg.norm(end - start)
    u = (end - start) / length
    n2 = np.array([-u[1], u[0]])
    assert a.counts.closed_form_pieces == 3
    for pts, tol in ((a.points, 1e-12), (_dense(a), 1e-10)):
        s = (pts - start) @ u / length  # foot parameter on A2's line
        assert np.all((pts[:, 0] > 0) & (pts[:, 0] < 10))  # A1's foot stays interior
        for focus, clamped in ((end, s > 1.0), (start, s < 0.0)):
            assert np.sum(clamped) >= 3
            p = pts[clamped]
            assert np.max(np.abs(np.linalg.norm(p - focus, axis=1) - p[:, 1])) <= tol * d
        q = pts[(s >= 0.0) & (s <= 1.0)]  # between: the angle bisector of the two lines
        assert len(q) >= 2
        assert np.max(np.abs(q[:, 1] - np.abs((q - start) @ n2))) <= tol * d
    assert _equidistance(a, a.points) <= 1e-10 * d
    assert _equidistance(a, _dense(a)) <= 1e-10 * d


def test_end_points_on_b1_b2():
    for corners in (
        SKEW,
        [[0, 0], [10, 0], [7.5, 6], [2.5, 6]],
        [[1, -2], [8, 1], [6, 9], [-3, 4]],
    ):
        reg = _quad(corners)
        c = np.asarray(corners, float)
        for pair in ((0, 2), (1, 3)):
            a = trace_axis(reg, pair)
            d = a.diagonal
            assert a.counts.closed_form_pieces >= 1
            b1, b2 = a.roles.b1, a.roles.b2
            assert _line_distance(a.points[:1], c[b1], c[(b1 + 1) % 4])[0] <= 1e-12 * d
            assert _line_distance(a.points[-1:], c[b2], c[(b2 + 1) % 4])[0] <= 1e-12 * d
            # t_start / t_end are the parameters of the end points on B1 / B2
            assert np.allclose(reg.sides[b1].evaluate(np.array([a.t_start]))[0], a.points[0],
                               rtol=0, atol=1e-12 * d)  # fmt: skip
            assert np.allclose(reg.sides[b2].evaluate(np.array([a.t_end]))[0], a.points[-1],
                               rtol=0, atol=1e-12 * d)  # fmt: skip


def test_arc_start_and_end_sides_and_a_parabola_on_them():
    """Line constraints, arc B sides (one bulging out, one in): the ends solve the quartic
    of a parabola against a circle."""
    p = np.array([[0.0, 0.0], [10.0, 0.0], [8.0, 6.0], [3.0, 6.0]])
    sides = [
        Line(p[0], p[1]),
        Arc.from_sagitta(p[1], p[2], 1.5),
        Line(p[2], p[3]),
        Arc.from_sagitta(p[3], p[0], -1.0),
    ]
    reg = Region.build(sides, name="arcs-b")
    a = trace_axis(reg, (0, 2))
    d = a.diagonal
    assert a.counts.closed_form_pieces >= 2
    for k, x in ((3, a.points[0]), (1, a.points[-1])):
        arc = reg.sides[k]
        assert abs(np.linalg.norm(x - arc.center) - arc.radius) <= 1e-12 * d
    assert _equidistance(a, a.points) <= 1e-10 * d
    assert _equidistance(a, _dense(a)) <= 1e-10 * d
    b = trace_axis(reg, (0, 2), closed_form=False, tol=1e-9, point_tol=1e-13)
    assert np.max(np.linalg.norm(a.points[[0, -1]] - b.points[[0, -1]], axis=1)) <= 1e-12 * d


def _random_convex_quad(rng: np.random.Generator) -> Region:
    while True:
        ang = np.sort(rng.uniform(0.0, 2.0 * np.pi, 4))
        if np.min(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) > 0.5:
            break
    r = rng.uniform(0.6, 1.4, 4) * rng.uniform(0.5, 20.0)
    c = np.column_stack((r * np.cos(ang), r * np.sin(ang))) + rng.uniform(-50, 50, 2)
    return _quad(c, "random")


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_same_axis_as_the_tracer_on_random_convex_quads(seed):
    reg = _random_convex_quad(np.random.default_rng(seed))
    for pair in ((0, 2), (1, 3)):
        a = trace_axis(reg, pair)
        b = trace_axis(reg, pair, tol=1e-9, point_tol=1e-13, closed_form=False)
        d = a.diagonal
        assert a.counts.closed_form_pieces >= 1 and b.counts.closed_form_pieces == 0
        assert np.max(np.linalg.norm(a.points[[0, -1]] - b.points[[0, -1]], axis=1)) <= 1e-12 * d
        assert abs(a.t_start - b.t_start) <= 1e-12 and abs(a.t_end - b.t_end) <= 1e-12
        # every traced point on the exact spline; the exact spline within the trace's tol
        assert np.max(a.spline.closest(b.points).distance) <= 1e-12 * d
        assert np.max(b.spline.closest(_dense(a)).distance) <= 2e-9 * d
        assert _equidistance(a, _dense(a)) <= 1e-10 * d


def test_clockwise_input_gives_the_same_axis():
    ccw = _quad(SKEW)
    cw = _quad([SKEW[0], SKEW[3], SKEW[2], SKEW[1]])
    assert cw.reoriented and not ccw.reoriented
    for pair, other in (((0, 2), (1, 3)), ((1, 3), (0, 2))):
        a, b = trace_axis(ccw, pair), trace_axis(cw, other)
        d = a.diagonal
        assert b.counts.closed_form_pieces >= 1
        ends_a, ends_b = a.points[[0, -1]], b.points[[0, -1]]
        if np.linalg.norm(ends_a[0] - ends_b[0]) > np.linalg.norm(ends_a[0] - ends_b[1]):
            ends_b = ends_b[::-1]
        assert np.max(np.linalg.norm(ends_a - ends_b, axis=1)) <= 1e-12 * d
        assert np.max(a.spline.closest(_dense(b)).distance) <= 1e-12 * d
        assert np.max(b.spline.closest(_dense(a)).distance) <= 1e-12 * d


def test_far_from_the_origin():
    """Coordinates near 1e6 (the double grid there is 1.2e-10, 1e-11 of this diagonal)."""
    base = np.array(SKEW)
    shift = np.array([1e6, -2e6 / 3.0])
    a, b = trace_axis(_quad(base), (0, 2)), trace_axis(_quad(base + shift), (0, 2))
    d = b.diagonal
    assert b.counts.closed_form_pieces == a.counts.closed_form_pieces >= 2
    assert a.n_points == b.n_points
    assert np.max(np.abs(b.points - shift - a.points)) <= 1e-10 * d
    assert np.max(np.abs(_dense(b) - shift - _dense(a))) <= 1e-10 * d
    assert b.max_point_error <= 1e-10 * d and b.max_curve_error <= 1e-10 * d
    assert _equidistance(b, b.points) <= 1e-10 * d


def test_spline_is_c1_at_the_transitions(trapezoid):
    a = trace_axis(trapezoid, (0, 2))
    joints = a.spline.breaks()  # multiplicity-2 knots: the Bezier joints
    assert len(joints) == 2
    eps = 1e-9
    left = a.spline.derivative(joints - eps)
    right = a.spline.derivative(joints + eps)
    assert np.max(np.linalg.norm(left - right, axis=1) / np.linalg.norm(left, axis=1)) <= 1e-7


def test_paper_method_and_other_ratios_still_trace(trapezoid):
    p = trace_axis(trapezoid, (0, 2), method="paper")
    assert p.counts.closed_form_pieces == 0 and p.counts.predictor_steps > 0
    q = trace_axis(trapezoid, (0, 2), method="paper", closed_form=False)
    assert np.array_equal(p.points, q.points)
    r = trace_axis(trapezoid, (0, 2), ratio=0.25)
    assert r.counts.closed_form_pieces == 0


def test_curved_constraints_are_traced(regions_spec):
    """B-spline constraints are traced; arcs too when the closed forms are turned off."""
    wavy = region_from_dict(regions_spec["wavy"], "wavy")
    assert trace_axis(wavy, (0, 2)).counts.closed_form_pieces == 0
    reg = region_from_dict(regions_spec["annulus_sector"], "annulus_sector")
    assert trace_axis(reg, (1, 3), closed_form=False).counts.closed_form_pieces == 0


def test_from_bezier_matches_scipy_and_checks_its_input():
    rng = np.random.default_rng(7)
    for k in (1, 2, 3):
        m = 3
        ctrl = rng.normal(size=(m * k + 1, 2))
        breaks = np.array([0.0, 0.2, 0.7, 1.0])
        s = BSpline.from_bezier(ctrl, breaks, k)
        knots = np.r_[np.zeros(k + 1), np.repeat(breaks[1:-1], k), np.ones(k + 1)]
        ref = ScipyBSpline(knots, ctrl, k)
        t = np.linspace(0.0, 1.0, 101)
        assert np.allclose(s.knots, knots, rtol=0, atol=0)
        assert np.max(np.abs(s.evaluate(t) - ref(t))) <= 1e-14
        assert np.max(np.abs(s.derivative(t) - ref(t, 1))) <= 1e-12
    with pytest.raises(CurveError, match=r"need \(m \* degree"):
        BSpline.from_bezier(np.zeros((6, 2)), np.array([0.0, 0.5, 1.0]), 2)
    with pytest.raises(CurveError, match="increasing"):
        BSpline.from_bezier(np.zeros((5, 2)), np.array([0.0, 1.0, 1.0]), 2)


def test_independent_side_functions_agree_with_the_truth_helpers(regions_spec):
    """The dense-sampling helper of this file against the shared one (both independent)."""
    spec = regions_spec["trapezoid"]
    f = side_function(spec["sides"][0], spec["corners"][0], spec["corners"][1])
    x = np.array([[3.0, 2.0], [-1.0, 1.0], [12.0, -3.0]])
    ref = DenseDistance(f)(x)
    assert np.allclose(_segment_distance(x, [0, 0], [10, 0]), ref, rtol=0, atol=1e-12)


def test_polyline_start_and_end_sides_use_the_side_solver():
    """B sides of another kind (polylines): the end points come from the Newton solver on
    the side, then the exact pieces between them."""
    from medax.geometry import Polyline

    c = np.array([[0.0, 0.0], [10.0, 0.0], [8.0, 6.0], [2.0, 6.0]])
    sides = [
        Line(c[0], c[1]),
        Polyline(np.array([c[1], [10.5, 3.0], c[2]])),
        Line(c[2], c[3]),
        Polyline(np.array([c[3], [0.5, 3.5], c[0]])),
    ]
    reg = Region.build(sides, name="polyline-b")
    a = trace_axis(reg, (0, 2))
    b = trace_axis(reg, (0, 2), closed_form=False, tol=1e-9, point_tol=1e-13)
    d = a.diagonal
    assert a.counts.closed_form_pieces >= 2
    assert np.max(np.linalg.norm(a.points[[0, -1]] - b.points[[0, -1]], axis=1)) <= 1e-12 * d
    assert np.max(a.spline.closest(b.points).distance) <= 1e-12 * d
    assert _equidistance(a, _dense(a)) <= 1e-10 * d


def test_thin_sliver_where_the_tracer_strays():
    """A thin non-convex random quad (found by fuzzing against the tracer): the closed form
    is equidistant to rounding (dense sampling), ends on B1/B2 exactly, and stays inside.
    (The tracer's fit stalls here at ~1e-2 x diagonal, with a warning.)"""
    c = np.array(
        [
            [8.671642599902032, 2.8352653624098103],
            [7.765497554966579, -2.6081880705309324],
            [9.936783118873667, 6.711959983781561],
            [4.498415819085341, -8.632097048033913],
        ]
    )
    reg = _quad(c, "sliver")
    a = trace_axis(reg, (0, 2))
    d = a.diagonal
    assert a.counts.closed_form_pieces >= 1
    assert _equidistance(a, a.points) <= 1e-10 * d
    assert _equidistance(a, _dense(a)) <= 1e-10 * d
    assert _line_distance(a.points[:1], c[3], c[0])[0] <= 1e-12 * d
    assert _line_distance(a.points[-1:], c[1], c[2])[0] <= 1e-12 * d
    assert np.all(reg.contains(_dense(a)[1:-1]))


SLIVER = np.array(
    [
        [8.671642599902032, 2.8352653624098103],
        [7.765497554966579, -2.6081880705309324],
        [9.936783118873667, 6.711959983781561],
        [4.498415819085341, -8.632097048033913],
    ]
)


@pytest.mark.slow
def test_tracer_follows_the_sliver():
    """The tracer (forced) on the sliver: its first step was the shortest side / 5, longer
    than the whole axis (0.9 of a 17-long region), and it lost the axis (6e-3 x diagonal);
    with the first step at most half the chord it matches the closed form."""
    reg = _quad(SLIVER, "sliver")
    a = trace_axis(reg, (0, 2), closed_form=False, batch=False)
    b = trace_axis(reg, (0, 2))
    d = a.diagonal
    assert a.counts.closed_form_pieces == 0
    assert _equidistance(a, a.points) <= 1e-10 * d
    assert _equidistance(a, _dense(a)) <= 1e-6 * d
    assert np.linalg.norm(a.points[0] - b.points[0]) <= 1e-12 * d
    assert np.linalg.norm(a.points[-1] - b.points[-1]) <= 1e-12 * d


@pytest.mark.slow
def test_tracer_refuses_a_lost_trace(monkeypatch):
    """With the old first step (past the end of the axis) the trace is lost; it says so
    with a typed error instead of returning points 6e-3 x diagonal off the axis."""
    import medax.axis.medial as medial
    from medax.errors import TraceError

    real = medial.trace_frame

    def past_the_end(field, p0, p1, h0, **kw):
        return real(field, p0, p1, h0=1.25 * float(np.linalg.norm(p1 - p0)), **kw)

    monkeypatch.setattr(medial, "trace_frame", past_the_end)
    with pytest.raises(TraceError, match="lost the axis"):
        trace_axis(_quad(SLIVER, "sliver"), (0, 2), closed_form=False, batch=False)
