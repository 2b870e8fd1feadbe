"""The ratio-curve mesher's field, warm-started feet and their global certification."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from medax.geometry import Arc, Line, Region, read_regions, sample_regions_path
from medax.geometry.curve import certify_closest, closest_from, track_closest
from medax.geometry.region_io import region_from_dict
from medax.mesh import ratio_field as rf
from medax.mesh import ratio_grid as rg
from medax.mesh.grid import boundary_indices
from medax.mesh.mesher import mesh_region as _mesh_region
from truth import Cylinder, blended_targets

#: these tests are of the medial grid as solved: without the quality pass
mesh_region = functools.partial(_mesh_region, smooth=False)

REGIONS = read_regions(sample_regions_path())


def sector(r0: float, r1: float, degrees: float) -> Region:
    """Annulus sector: S0 ray at 0, S1 outer arc, S2 ray at ``degrees``, S3 inner arc."""
    a = np.radians(degrees)
    u0, u1 = np.array([1.0, 0.0]), np.array([np.cos(a), np.sin(a)])
    sides = [
        Line(r0 * u0, r1 * u0),
        Arc(np.zeros(2), r1, 0.0, a),
        Line(r1 * u1, r0 * u1),
        Arc(np.zeros(2), r0, a, -a),
    ]
    return Region.build(sides, name=f"sector{degrees:g}")


def polar(r0: float, r1: float, degrees: float, n1: int, n2: int) -> np.ndarray:
    """The exact polar grid (n2 + 1, n1 + 1, 2): radius along S0, angle along S1."""
    rad = r0 + (r1 - r0) * np.arange(n1 + 1) / n1
    ang = np.radians(degrees) * np.arange(n2 + 1) / n2
    return np.stack((rad[None] * np.cos(ang[:, None]), rad[None] * np.sin(ang[:, None])), -1)


@pytest.mark.parametrize("div", [(7, 12), (5, 3), (16, 16)])
def test_shared_annulus_sector_is_exact_polar_grid(div):
    """The default mesher gives concentric arcs and equal-angle rays for any counts."""
    r = REGIONS["annulus_sector"]
    m = mesh_region(r, div)
    assert np.abs(m.grid() - polar(5.0, 9.0, 120.0, *div)).max() <= 1e-9 * r.diagonal


@pytest.mark.parametrize("degrees", [30.0, 150.0])
def test_sector_of_any_angle_is_polar_grid(degrees):
    """Beyond 90 degrees the feet on the segment rays clamp at their ends; the angle field
    measures to the whole lines, so the rays stay exact."""
    r = sector(2.0, 7.0, degrees)
    m = mesh_region(r, (6, 9))
    assert np.abs(m.grid() - polar(2.0, 7.0, degrees, 6, 9)).max() <= 1e-9 * r.diagonal


def test_distance_ratio_is_kept_where_it_measured_better():
    """Only the polar pair of the annulus takes the angle weighting by default."""
    pw = rf.pair_weighting
    assert pw(REGIONS["annulus_sector"], 0, 2, "auto") == "angle"
    assert pw(REGIONS["annulus_sector"], 1, 3, "auto") == "distance"
    for name in ("trapezoid", "arcs", "wavy"):
        assert {pw(REGIONS[name], a, a + 2, "auto") for a in (0, 1)} == {"distance"}
    assert pw(REGIONS["wavy"], 0, 2, "angle") == "distance"  # free-form sides: never
    assert pw(REGIONS["arcs"], 0, 2, "angle") == "angle"


def test_angle_field_gradient_matches_finite_differences():
    r = REGIONS["arcs"]
    sides = rf.SideDistances(r, 0, ("angle", "angle"))
    p = np.random.default_rng(3).uniform(2.0, 8.0, (20, 2))
    ratio = np.linspace(0.1, 0.9, 20)
    h = 1e-6
    for a, b in ((0, 2), (1, 3)):
        _, grad, _ = rf.evaluate_field(sides, a, b, ratio, p, "angle")
        fd = np.column_stack(
            [
                (rf.evaluate_field(sides, a, b, ratio, p + h * e, "angle")[0]
                 - rf.evaluate_field(sides, a, b, ratio, p - h * e, "angle")[0]) / (2 * h)
                for e in np.eye(2)
            ]
        )  # fmt: skip
        np.testing.assert_allclose(grad, fd, atol=1e-7)


@pytest.mark.parametrize("name", sorted(REGIONS))
def test_angle_method_valid_grid(name):
    r = REGIONS[name]
    m = mesh_region(r, (9, 14), method="angle")
    assert np.all(m.quality().scaled_jacobian > 0.0)
    for k, idx in enumerate(boundary_indices(9, 14)):
        assert r.sides[k].closest(m.params[idx]).distance.max() <= 1e-9 * r.diagonal


def test_coarse_start_gives_the_same_nodes(monkeypatch):
    """Large grids start from an interpolated coarse grid with tracked feet; the nodes must
    be those of the direct solve from the transfinite guess with global feet."""
    r = REGIONS["wavy"]
    fast = mesh_region(r, (60, 52), tol=0.0)  # every node solved
    assert fast.info["coarse_newton_iterations"] > 0
    assert fast.info["interpolated"] == fast.info["coarse_interpolated"] == 0
    monkeypatch.setattr(rg, "_COARSE_MIN", 10**6)
    monkeypatch.setattr(rg, "_TRACK_STEP", 0.0)  # every evaluation global
    slow = mesh_region(r, (60, 52))
    assert slow.info["coarse_newton_iterations"] == 0
    assert np.abs(fast.params - slow.params).max() <= 1e-9 * r.diagonal


def _free_form_region(name: str):
    """Free-form regions besides ``wavy`` (10 x 8 box corners): B-splines and a line
    (``bulge``), two zig-zag polylines and lines (``zigzag``), a degree-5 B-spline, arcs and
    a polyline (``mixed``)."""
    c = [[0, 0], [10, 0], [10, 8], [0, 8]]

    def zig(p0, p1, n, amp, seed):
        t = np.linspace(0.0, 1.0, n)[1:-1]
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        d = p1 - p0
        nrm = np.array([-d[1], d[0]]) / np.linalg.norm(d)
        off = amp * np.sin(7 * t) + 0.3 * amp * np.random.default_rng(seed).uniform(-1, 1, t.size)
        return [p0.tolist(), *(p0 + t[:, None] * d + off[:, None] * nrm).tolist(), p1.tolist()]

    sides = {
        "bulge": [
            {"kind": "bspline", "degree": 3, "points": [c[0], [3, -1.5], [7, 1.0], c[1]]},
            {"kind": "bspline", "degree": 3, "points": [c[1], [11.5, 3], [9.2, 5], c[2]]},
            {"kind": "bspline", "degree": 3, "points": [c[2], [6, 9.8], [3, 7.2], c[3]]},
            {"kind": "line"},
        ],
        "zigzag": [
            {"kind": "polyline", "points": zig(c[0], c[1], 9, 0.6, 1)},
            {"kind": "line"},
            {"kind": "polyline", "points": zig(c[2], c[3], 7, 0.5, 2)},
            {"kind": "line"},
        ],
        "mixed": [
            {"kind": "bspline", "degree": 5,
             "points": [c[0], [2, 1.4], [4, -1.2], [6, 1.1], [8, -0.9], c[1]]},
            {"kind": "arc", "sagitta": 0.8},
            {"kind": "polyline", "points": zig(c[2], c[3], 12, 0.3, 3)},
            {"kind": "arc", "sagitta": -0.5},
        ],
    }  # fmt: skip
    return region_from_dict({"corners": c, "sides": sides[name]}, name)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "divisions", "tol", "share"),
    [
        ("wavy", (512, 512), 1e-6, 0.6),
        ("wavy", (400, 150), 1e-6, 0.05),
        ("wavy", (300, 300), 1e-7, 0.02),
        ("bulge", (300, 300), 1e-6, 0.6),
        ("bulge", (512, 200), 1e-6, 0.6),
        ("zigzag", (512, 200), 1e-6, 0.25),
        ("mixed", (300, 300), 1e-6, 0.15),
    ],
)
def test_interpolated_nodes_within_the_tolerance(name, divisions, tol, share):
    """Interior nodes interpolated from the coarser level where the estimate allows (at
    least ``share`` of them; ``wavy``'s four B-spline sides put foot jumps across the grid):
    every node within ``tol`` x diagonal of the grid with every node solved."""
    r = REGIONS[name] if name in REGIONS else _free_form_region(name)
    fast = mesh_region(r, divisions, tol=tol)
    exact = mesh_region(r, divisions, tol=0.0)
    assert exact.info["interpolated"] == 0
    assert fast.info["interpolated"] >= share * (divisions[0] - 1) * (divisions[1] - 1)
    err = np.linalg.norm(fast.params - exact.params, axis=1).max()
    assert err <= tol * r.diagonal
    assert np.all(fast.quality().scaled_jacobian > 0.0)


@pytest.mark.slow
def test_stalled_newton_is_solved_again_from_global_feet(monkeypatch):
    """Quarter-size coarse levels leave one node of the 512x512 ``wavy`` grid whose damped
    Newton stalls with tracked feet (residual 3e-7 x diagonal after 40 iterations); it is
    solved again from global feet, and the grid is that of the half-size levels."""
    r = REGIONS["wavy"]
    halves = mesh_region(r, (512, 512), tol=0.0)

    def quarters(n1, n2):
        out = [(n1, n2)]
        while min(out[-1]) >= 4 * rg._COARSE_MIN:
            out.append(tuple(max(rg._COARSE_MIN, -(-c // 4)) for c in out[-1]))
        return out

    monkeypatch.setattr(rg, "_levels", quarters)
    m = mesh_region(r, (512, 512), tol=0.0)
    assert m.info["global_resolved"] > 0
    assert np.abs(m.params - halves.params).max() <= 1e-9 * r.diagonal


def test_line_and_arc_regions_are_always_solved():
    """Regions of lines and arcs have every foot in closed form: nothing is interpolated,
    whatever the tolerance."""
    r = REGIONS["arcs"]
    m = mesh_region(r, (200, 200), tol=1e-3)
    assert m.info["interpolated"] == m.info["coarse_interpolated"] == 0


def _brute_distance(curve, x: np.ndarray, n: int = 400001) -> np.ndarray:
    """Distances (len(x),) to dense samples: an independent global answer."""
    s = curve.sample(n)
    out = np.empty(len(x))
    for i in range(0, len(x), 50):
        out[i : i + 50] = np.min(np.linalg.norm(x[i : i + 50, None] - s[None], axis=2), axis=1)
    return out


def test_closest_from_converges_to_the_nearby_foot():
    c = REGIONS["wavy"].sides[0]
    rng = np.random.default_rng(5)
    t = rng.uniform(0.05, 0.95, 200)
    normal = c.derivative(t)[:, ::-1] * np.array([1.0, -1.0])
    x = c.evaluate(t) + 0.05 * normal / np.linalg.norm(normal, axis=1)[:, None]
    local = closest_from(c, x, t + rng.uniform(-0.01, 0.01, t.size))
    np.testing.assert_allclose(local.t, t, atol=1e-9)
    np.testing.assert_allclose(local.distance, 0.05, atol=1e-12)


def test_track_closest_gives_exact_feet_from_nearby_starts():
    """Points at a known normal offset of a wavy side: from starts 1e-2 and 1e-7 away the
    tracked feet are the known ones, their points on the curve and the distances exact
    (the Taylor foot of the last step)."""
    c = REGIONS["wavy"].sides[0]
    rng = np.random.default_rng(6)
    t = rng.uniform(0.05, 0.95, 300)
    normal = c.derivative(t)[:, ::-1] * np.array([1.0, -1.0])
    x = c.evaluate(t) + 0.05 * normal / np.linalg.norm(normal, axis=1)[:, None]
    for err in (1e-2, 1e-7):
        got = track_closest(c, x, t + rng.uniform(-err, err, t.size))
        np.testing.assert_allclose(got.t, t, atol=1e-12)
        np.testing.assert_allclose(got.distance, 0.05, atol=1e-14)
        np.testing.assert_allclose(got.foot, c.evaluate(t), atol=1e-14)


@pytest.mark.slow
def test_certify_closest_never_certifies_a_wrong_foot():
    """Feet on the wrong part of a wavy side are never certified; true ones mostly are."""
    r = REGIONS["wavy"]
    c = r.sides[0]
    lo, hi = r.corners.min(axis=0), r.corners.max(axis=0)
    x = np.random.default_rng(7).uniform(lo, hi, (600, 2))
    truth = _brute_distance(c, x)
    g = c.closest(x)
    np.testing.assert_allclose(g.distance, truth, atol=1e-9)
    slack = 1e-12 * r.diagonal
    ok = certify_closest(c, x, g.t, g.distance, slack)
    assert ok.mean() > 0.9
    # local minima started from the far end of the curve: wrong wherever they are farther
    far = closest_from(c, x, np.where(g.t < 0.5, 1.0, 0.0), iters=60)
    wrong = far.distance > truth + 1e-9
    assert wrong.sum() > 50
    assert not np.any(certify_closest(c, x, far.t, far.distance, slack)[wrong])


@pytest.mark.slow
@pytest.mark.parametrize("div", [(5, 4), (50, 48)])
def test_mesh_on_a_cylinder_patch_measures_in_space(div):
    """Nodes of a patch on a cylinder satisfy both ratio equations with distances in space
    measured by brute force (the large grid takes the coarse start and tracked feet)."""
    c = np.array([[0.2, 0], [2.5, 0], [2.0, 3], [0.0, 2.5]], float)
    emb = Cylinder(2.0)
    reg = Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], "cyl", embedding=emb)
    n1, n2 = div
    m = mesh_region(reg, div)
    assert m.points.shape == ((n1 + 1) * (n2 + 1), 3)
    s = np.linspace(0.0, 1.0, 100001)
    from scipy.spatial import cKDTree

    d = [
        cKDTree(emb.evaluate(c[k] + s[:, None] * (c[(k + 1) % 4] - c[k]))).query(m.points)[0]
        for k in range(4)
    ]
    for k, idx in enumerate(boundary_indices(n1, n2)):
        d[k][idx] = 0.0  # (on its own side: the sampled distance is only 1e-5 there)
    j, i = np.divmod(np.arange(m.n_nodes), n1 + 1)
    inner = (i > 0) & (i < n1) & (j > 0) & (j < n2)
    phi_a, phi_b = d[0] / (d[0] + d[2]), d[1] / (d[1] + d[3])
    ra, rb = blended_targets(phi_a, phi_b, n1, n2)
    assert np.abs(phi_a - ra.ravel())[inner].max() < 1e-7
    assert np.abs(phi_b - rb.ravel())[inner].max() < 1e-7
    assert np.all(m.quality().scaled_jacobian > 0.0)


def test_far_from_the_origin_gives_the_same_mesh():
    """The wavy region moved by (1e6, -2e6): the same nodes, moved (tracked feet and their
    certification work in centred coordinates)."""
    r = REGIONS["wavy"]
    shift = np.array([1e6, -2e6])
    moved = Region.build([s.transformed(-shift, 1.0) for s in r.sides], name="far")
    a = mesh_region(r, (50, 48))
    b = mesh_region(moved, (50, 48))
    assert np.abs(b.params - shift - a.params).max() <= 1e-9 * r.diagonal


@pytest.mark.parametrize("degrees", [200.0, 270.0])
def test_channels_bent_past_180_degrees(degrees):
    """Past 180 degrees a sector has no apex angle to divide: the distance ratio is used,
    the arcs stay concentric and no quad inverts (thin channel, 1/50 and 64 x 512)."""
    r = sector(5.0, 5.1, degrees)
    assert rf.pair_weighting(r, 0, 2, "auto") == "distance"
    assert rf.pair_weighting(r, 0, 2, "angle") == "distance"
    for div, method in (((8, 64), "ratio"), ((64, 512), "ratio"), ((8, 64), "angle")):
        m = mesh_region(r, div, method=method)
        rad = np.linalg.norm(m.grid(), axis=-1)
        want = 5.0 + 0.1 * np.arange(div[0] + 1) / div[0]
        assert np.abs(rad - want[None]).max() <= 1e-9 * r.diagonal
        assert m.quality().scaled_jacobian.min() > 0.9


@pytest.mark.parametrize("sweep", [1.0, -2.5, 4.5])
def test_arc_radial_distances_match_closest_points(sweep):
    """The mesher's radial arc distances and directions equal Arc.closest's (points inside
    and outside the circle, inside and outside the arc's angle, sweeps above pi)."""
    arc = Arc(np.array([1.0, -2.0]), 3.0, 0.7, sweep)
    x = np.random.default_rng(2).uniform(-6.0, 8.0, (2000, 2))
    d, u, _ = rf._arc_radial(arc, x)
    c = arc.closest(x)
    np.testing.assert_allclose(d, c.distance, atol=1e-12)
    np.testing.assert_allclose(u, (x - c.foot) / c.distance[:, None], atol=1e-9)


def _planar_cases():
    """(region, weighting) pairs covering every closed-form term: clamped segments, radial
    arcs (sweeps below and above pi), whole lines of an angle pair (meeting and parallel)."""
    return [
        (REGIONS["trapezoid"], "auto"),
        (REGIONS["trapezoid"], "angle"),
        (REGIONS["arcs"], "auto"),
        (REGIONS["annulus_sector"], "auto"),
        (sector(2.0, 7.0, 150.0), "auto"),
        (sector(5.0, 5.1, 270.0), "auto"),
    ]


@pytest.mark.parametrize("case", range(6))
def test_planar_field_equals_the_general_field(case):
    """The closed-form field of line and arc regions gives the values and gradients of
    evaluate_field, at points inside and around the region (feet clamped at segment ends,
    outside an arc's angle, on either side of a whole line)."""
    r, weighting = _planar_cases()[case]
    kinds = (rf.pair_weighting(r, 0, 2, weighting), rf.pair_weighting(r, 1, 3, weighting))
    assert rf.PlanarField.supports(r, kinds)
    field = rf.PlanarField(r, kinds)
    sides = rf.SideDistances(r, 0, kinds)
    lo, hi = r.boundary.min(axis=0), r.boundary.max(axis=0)
    rng = np.random.default_rng(case)
    p = rng.uniform(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo), (3000, 2))
    ratio = rng.uniform(0.0, 1.0, 3000)
    x, y = p[:, 0].copy(), p[:, 1].copy()
    for pair, (a, b) in enumerate(((0, 2), (1, 3))):
        g, grad, _ = rf.evaluate_field(sides, a, b, ratio, p, kinds[pair])
        fg, fx, fy = field.pair(pair, x, y, field.weights(pair, ratio))
        assert np.array_equal(field.value(pair, x, y, field.weights(pair, ratio)), fg)
        np.testing.assert_allclose(fg, g, rtol=0, atol=1e-12 * r.diagonal)
        np.testing.assert_allclose(np.column_stack((fx, fy)), grad, rtol=0, atol=1e-12)


def test_planar_field_only_for_closed_form_sides():
    r = REGIONS["wavy"]
    assert not rf.PlanarField.supports(r, ("distance", "distance"))
    assert not rf.PlanarField.supports(REGIONS["arcs"], ("angle", "angle"))  # foot angle varies
    c = np.array([[0.2, 0], [2.5, 0], [2.0, 3], [0.0, 2.5]], float)
    cyl = Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], "c", embedding=Cylinder(2.0))
    assert not rf.PlanarField.supports(cyl, ("distance", "distance"))


@pytest.mark.slow
@pytest.mark.parametrize(("name", "tol"), [("wavy", 0.0), ("wavy", 1e-6), ("bulge", 0.0)])
def test_free_field_solve_gives_the_general_nodes(name, tol, monkeypatch):
    """The coordinate-row solve of free-form regions (:mod:`medax.mesh.free_field`, several
    blocks) finds the nodes of the general solve, with the same counts of interpolated and
    copied nodes (its feet after long steps are tracked and certified instead of queried,
    so the global re-solves may differ by a few); regions it does not take go the general
    way."""
    import medax.mesh.free_field as ff

    r = REGIONS[name] if name in REGIONS else _free_form_region(name)
    assert ff.FreeField.supports(r, ("distance", "distance"))
    assert not ff.FreeField.supports(r, ("angle", "distance"))
    assert not ff.FreeField.supports(REGIONS["arcs"], ("distance", "distance"))  # (planar)
    assert not ff.FreeField.supports(_free_form_region("mixed"), ("distance", "distance"))
    monkeypatch.setattr(ff, "_BLOCK", 1000)
    fast = mesh_region(r, (120, 97), tol=tol)
    monkeypatch.setattr(ff.FreeField, "supports", staticmethod(lambda region, kinds: False))
    slow = mesh_region(r, (120, 97), tol=tol)
    assert np.abs(fast.params - slow.params).max() <= 1e-11 * r.diagonal
    for key in ("interpolated", "copied", "coarse_interpolated", "coarse_copied"):
        assert fast.info[key] == slow.info[key]
    for key in ("global_resolved", "coarse_global_resolved"):
        assert abs(fast.info[key] - slow.info[key]) <= 3


@pytest.mark.parametrize("name", ["trapezoid", "arcs", "annulus_sector"])
def test_planar_solve_gives_the_general_nodes(name, monkeypatch):
    """The closed-form, blocked solve finds the nodes of the general solve (coarse start,
    several blocks)."""
    r = REGIONS[name]
    monkeypatch.setattr(rg, "_BLOCK", 1000)
    fast = mesh_region(r, (60, 52))
    monkeypatch.setattr(rf.PlanarField, "supports", staticmethod(lambda region, kinds: False))
    slow = mesh_region(r, (60, 52), tol=0.0)  # (the general path solves every node so)
    assert np.abs(fast.params - slow.params).max() <= 1e-12 * r.diagonal


def test_certify_closest_is_the_documented_rule():
    """The compiled certification equals the rule written out on the whole table: no local
    minimum of the sample distances beyond 1.5 spacings of the foot is nearer than the
    foot's distance minus the slack, allowing the larger of 0.55 sample spacings between
    samples and the chord bound ``sqrt(s^2 - l^2 / 4) - e``."""
    r = REGIONS["wavy"]
    lo, hi = r.corners.min(axis=0), r.corners.max(axis=0)
    x = np.random.default_rng(11).uniform(lo, hi, (700, 2))
    for c in r.sides:
        ts, pts = c._search
        t0 = np.random.default_rng(1).uniform(0.0, 1.0, len(x))
        loc = closest_from(c, x, t0, iters=60)
        d = np.linalg.norm(x[:, None] - pts[None], axis=2)
        is_min = np.ones(d.shape, dtype=bool)
        is_min[:, 1:] &= d[:, 1:] <= d[:, :-1]
        is_min[:, :-1] &= d[:, :-1] <= d[:, 1:]
        is_min &= np.abs(ts[None] - loc.t[:, None]) > 1.5 * (ts[1] - ts[0])
        other = np.where(is_min, d, np.inf).min(axis=1)
        chord = np.linalg.norm(np.diff(pts, axis=0), axis=1).max()
        dt = ts[1] - ts[0]
        mid = np.concatenate((ts, 0.5 * (ts[1:] + ts[:-1])))
        sag = 1.5 * np.linalg.norm(c.derivative(mid, 2), axis=1).max() * dt * dt / 8
        bound = np.maximum(
            other - 0.55 * chord, np.sqrt(np.maximum(other**2 - chord**2 / 4, 0)) - sag
        )
        assert np.all(bound[np.isfinite(other)] >= other[np.isfinite(other)] - 0.55 * chord)
        want = bound >= loc.distance - 1e-12
        got = certify_closest(c, x, loc.t, loc.distance, 1e-12)
        assert 0 < want.sum() < len(x)
        assert np.count_nonzero(got != want) <= 2  # (round-off at the margin only)
        assert not np.any(got & ~want & (bound < loc.distance - 1e-9))


@pytest.mark.slow
def test_certify_closest_near_equidistant_parts():
    """Points near where the nearest point of a wavy side jumps (two local feet at nearly
    the same distance): the farther foot is never certified, even when it is farther by
    less than a sample spacing (the chord bound's regime), and the nearer one mostly is."""
    r = REGIONS["wavy"]
    c = r.sides[0]
    lo, hi = r.corners.min(axis=0), r.corners.max(axis=0)
    x = np.random.default_rng(12).uniform(lo, hi, (20000, 2))
    dense = np.linspace(0.0, 1.0, 4001)
    d = np.linalg.norm(x[:, None] - c.evaluate(dense)[None], axis=2)
    is_min = np.ones(d.shape, dtype=bool)
    is_min[:, 1:] &= d[:, 1:] < d[:, :-1]
    is_min[:, :-1] &= d[:, :-1] < d[:, 1:]
    two = np.flatnonzero(is_min.sum(axis=1) >= 2)
    score = np.where(is_min[two], d[two], np.inf)
    order = np.argsort(score, axis=1)[:, :2]
    first = closest_from(c, x[two], dense[order[:, 0]], iters=60)
    second = closest_from(c, x[two], dense[order[:, 1]], iters=60)
    gap = second.distance - first.distance
    sep = np.abs(second.t - first.t) > 0.01
    near = (
        sep
        & (gap > 1e-9)
        & (gap < 0.55 * np.linalg.norm(np.diff(c._search[1], axis=0), axis=1).max())
    )
    assert near.sum() > 20
    slack = 1e-12 * r.diagonal
    wrong = sep & (gap > 1e-9)
    assert not np.any(certify_closest(c, x[two], second.t, second.distance, slack)[wrong])
    assert certify_closest(c, x[two], first.t, first.distance, slack)[near].mean() > 0.5


def test_targets_blend_and_separable_rows():
    """Interior targets are the linear blends of the boundary ratios; rows (columns) whose
    two end values agree to round-off come back as one value each, equal to the blend."""
    n1, n2 = 5, 4
    rng = np.random.default_rng(9)
    rows, cols = np.sort(rng.uniform(0, 1, n2 + 1)), np.sort(rng.uniform(0, 1, n1 + 1))[::-1]
    t1, t2 = np.zeros(n1 + 1), np.zeros(n2 + 1)
    sides = [(t1, cols), (t2, rows), (t1, cols[::-1] + 1e-17), (t2, rows[::-1])]
    ra, rb, (ur, vc) = rg._targets(sides, n1, n2)
    np.testing.assert_allclose(ur, rows[1:-1], atol=1e-15)
    np.testing.assert_allclose(vc, cols[1:-1], atol=1e-15)
    np.testing.assert_allclose(ra.reshape(n2 - 1, n1 - 1), rows[1:-1, None] + 0 * cols[None, 1:-1])
    bent = [(t1, cols), (t2, rows), (t1, cols[::-1] + 0.01), (t2, rows[::-1])]
    _, rb2, (ur2, vc2) = rg._targets(bent, n1, n2)
    assert ur2 is not None and vc2 is None
    v = (np.arange(1, n2) / n2)[:, None]
    np.testing.assert_allclose(rb2.reshape(n2 - 1, n1 - 1), cols[None, 1:-1] + 0.01 * v)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "divisions", "tol"), [("wavy", (512, 512), 1e-6), ("wavy", (300, 200), 0.0),
                                   ("bulge", (256, 256), 1e-6)],
)  # fmt: skip
def test_solved_nodes_meet_the_residual_with_global_distances(name, divisions, tol, monkeypatch):
    """Every node the solve returns (at every level), including those whose last Newton step
    was taken on its Taylor bound without an evaluation at its end
    (:func:`medax.mesh.free_field._newton_block`), meets both equations to the residual
    tolerance with distances to the sides measured by global queries."""
    r = REGIONS[name] if name in REGIONS else _free_form_region(name)
    seen = []
    solve = rg._solve

    def spy(region, p, ra, rb, ntol, kinds, *a, **k):
        out = solve(region, p, ra, rb, ntol, kinds, *a, **k)
        seen.append((region, out[0], ra, rb, ntol))
        return out

    monkeypatch.setattr(rg, "_solve", spy)
    mesh_region(r, divisions, tol=tol)
    assert len(seen) >= 3
    for region, p, ra, rb, ntol in seen:
        if p.shape[0] == 0:
            continue
        d = [region.sides[k].closest(p).distance for k in range(4)]
        res = np.hypot((1 - ra) * d[0] - ra * d[2], (1 - rb) * d[1] - rb * d[3])
        assert res.max() <= ntol * (1 + 1e-6)


def test_chord_bound_only_on_smooth_curves():
    """The chord bound of the per-point certification needs a C1 curve: a B-spline with a
    kink (a knot of full multiplicity) and curves that do not say keep ``s - h / 2`` alone;
    a sub-curve of a smooth B-spline keeps it."""
    from medax.geometry.bspline import BSpline
    from medax.geometry.curve import SubCurve

    ctrl = np.array([[0, 0], [1, 1.5], [2, -1], [3, 0.5], [4, 2], [5, -0.5], [6, 0.0]], float)
    kink = BSpline(ctrl, 3, np.array([0, 0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1, 1.0]))
    smooth = REGIONS["wavy"].sides[0]
    assert not kink.chord_smooth() and np.isinf(kink._gaps[2])
    assert smooth.chord_smooth() and np.isfinite(smooth._gaps[2])
    assert SubCurve(smooth, 0.2, 0.7).chord_smooth()
    assert not SubCurve(kink, 0.2, 0.7).chord_smooth()
