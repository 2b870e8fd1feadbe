"""The mesher against exact grids and invariants; the crossing finder on synthetic families."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from scipy.spatial import cKDTree

from medax.errors import InputError, MeshError
from medax.geometry import Arc, Line, Region, read_regions, sample_regions_path
from medax.mesh.crossings import family_crossings
from medax.mesh.grid import boundary_indices, structured_quads
from medax.mesh.mesher import divisions_for_size
from medax.mesh.mesher import mesh_region as _mesh_region
from medax.mesh.split import split_region
from truth import blended_targets, polyline_arc_lengths, side_function

#: these tests are of the medial grid as solved: without the quality pass
mesh_region = functools.partial(_mesh_region, smooth=False)

REGIONS = read_regions(sample_regions_path())


def rectangle(w: float = 6.0, h: float = 2.0) -> Region:
    c = np.array([[1.0, -1.0], [1.0 + w, -1.0], [1.0 + w, h - 1.0], [1.0, h - 1.0]])
    return Region.build([Line(c[k], c[(k + 1) % 4]) for k in range(4)], name="rect")


def test_structured_quads_ccw_unit_grid():
    q = structured_quads(3, 2)
    assert q.shape == (6, 4)
    pts = np.array([[i, j] for j in range(3) for i in range(4)], dtype=float)
    p = pts[q]
    area = 0.5 * np.sum(
        p[:, :, 0] * np.roll(p[:, :, 1], -1, 1) - np.roll(p[:, :, 0], -1, 1) * p[:, :, 1], axis=1
    )
    np.testing.assert_allclose(area, 1.0)
    s0, s1, s2, s3 = boundary_indices(3, 2)
    assert s0.tolist() == [0, 1, 2, 3] and s1.tolist() == [3, 7, 11]
    assert s2.tolist() == [11, 10, 9, 8] and s3.tolist() == [8, 4, 0]


@pytest.mark.parametrize("method", ["ratio", "paper"])
def test_rectangle_is_uniform_grid(method):
    r = rectangle()
    m = mesh_region(r, (6, 4), method=method)
    x = 1.0 + 6.0 * np.arange(7) / 6
    y = -1.0 + 2.0 * np.arange(5) / 4
    exact = np.stack(np.meshgrid(x, y), axis=-1)
    assert np.abs(m.grid() - exact).max() <= 1e-9 * r.diagonal


def polar(n1: int, n2: int) -> np.ndarray:
    rad = 5.0 + 4.0 * np.arange(n1 + 1) / n1
    ang = np.radians(120.0) * np.arange(n2 + 1) / n2
    return np.stack((rad[None] * np.cos(ang[:, None]), rad[None] * np.sin(ang[:, None])), -1)


def test_annulus_sector_paper_is_polar_grid():
    r = REGIONS["annulus_sector"]
    m = mesh_region(r, (4, 4), method="paper")
    assert np.abs(m.grid() - polar(4, 4)).max() <= 1e-9 * r.diagonal


def test_annulus_sector_ratio_arcs_are_concentric():
    """The (S1, S3) ratio curves of two concentric arcs are the equally spaced arcs."""
    r = REGIONS["annulus_sector"]
    m = mesh_region(r, (5, 3))
    g = m.grid()
    radius = np.linalg.norm(g, axis=-1)
    want = 5.0 + 4.0 * np.arange(6) / 5
    assert np.abs(radius - want[None]).max() <= 1e-9 * r.diagonal
    # the middle (S0, S2) curve of a symmetric sector is the 60 degree ray... only for even n2
    m2 = mesh_region(r, (3, 2))
    ang = np.degrees(np.arctan2(m2.grid()[1, :, 1], m2.grid()[1, :, 0]))
    np.testing.assert_allclose(ang, 60.0, atol=1e-9)


@pytest.mark.parametrize("name", sorted(REGIONS))
@pytest.mark.parametrize("div", [(7, 12), (16, 16)])
def test_invariants_ratio(name, div):
    r = REGIONS[name]
    n1, n2 = div
    m = mesh_region(r, div)
    assert m.n_nodes == (n1 + 1) * (n2 + 1) and m.quads.shape == (n1 * n2, 4)
    q = m.quality()
    assert np.all(q.scaled_jacobian > 0.0)  # every quad counter-clockwise
    diag = r.diagonal
    for k, idx in enumerate(boundary_indices(n1, n2)):
        side = r.sides[k]
        d = side.closest(m.params[idx]).distance
        assert d.max() <= 1e-9 * diag, (name, k, d.max())
        np.testing.assert_allclose(
            m.params[idx[[0, -1]]], [side.start, side.end], atol=1e-12 * diag
        )


@pytest.mark.parametrize("boundary", ["arclength", "ratio"])
def test_ratio_nodes_are_on_their_curves(boundary):
    """Independent check: node (i, j) has the ratios d0/(d0+d2) and d1/(d1+d3) blended
    linearly from their values at the boundary nodes (in i/n1 between S3 and S1, in j/n2
    between S0 and S2), distances by dense sampling of the sides (not the closest-point
    solver). With boundary nodes at the ends of the constant-ratio curves those values are
    the constants j/n2 and 1 - i/n1."""
    r = REGIONS["wavy"]
    n1, n2 = 5, 4
    m = mesh_region(r, (n1, n2), boundary=boundary)
    dense = [s.sample(200001) for s in r.sides]
    p = m.params
    d = np.array(
        [np.min(np.linalg.norm(p[:, None] - s[None, ::10], axis=2), axis=1) for s in dense]
    )
    # refine the coarse minimum locally with the full sampling around it
    for k, s in enumerate(dense):
        i0 = np.argmin(np.linalg.norm(p[:, None] - s[None, ::10], axis=2), axis=1) * 10
        for n in range(len(p)):
            lo, hi = max(i0[n] - 20, 0), min(i0[n] + 21, len(s))
            d[k, n] = np.min(np.linalg.norm(s[lo:hi] - p[n], axis=1))
    for k, idx in enumerate(boundary_indices(n1, n2)):
        d[k, idx] = 0.0  # on its own side (checked by the invariants test)
    j, i = np.divmod(np.arange(len(p)), n1 + 1)
    inner = (i > 0) & (i < n1) & (j > 0) & (j < n2)
    ra, rb = blended_targets(d[0] / (d[0] + d[2]), d[1] / (d[1] + d[3]), n1, n2)
    assert np.abs(d[0] / (d[0] + d[2]) - ra.ravel())[inner].max() < 1e-7
    assert np.abs(d[1] / (d[1] + d[3]) - rb.ravel())[inner].max() < 1e-7
    if boundary == "ratio":
        assert np.abs(ra.ravel() - j / n2).max() < 1e-7
        assert np.abs(rb.ravel() - (1 - i / n1)).max() < 1e-7
    else:  # the blend is not the constant ratio of a row: the test can tell them apart
        assert np.abs(ra.ravel() - j / n2)[inner].max() > 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("name", ["wavy", "arcs", "trapezoid"])
def test_boundary_nodes_at_equal_arc_length(name):
    """Boundary nodes divide each side into equal arc lengths (as gmsh's transfinite
    curves do), measured on an independent dense polyline of the side."""
    spec = json.loads(sample_regions_path().read_text())[name]
    n1, n2 = 9, 7
    m = mesh_region(REGIONS[name], (n1, n2))
    for k, idx in enumerate(boundary_indices(n1, n2)):
        f = side_function(spec["sides"][k], spec["corners"][k], spec["corners"][(k + 1) % 4])
        s = np.linspace(0.0, 1.0, 400001)
        _, near = cKDTree(f(s)).query(m.params[idx])
        lengths = polyline_arc_lengths(f, s[near])
        edges = np.diff(lengths)
        assert np.abs(edges / edges.mean() - 1.0).max() < 1e-4, (name, k)


def test_paper_invariants_and_size_rule():
    r = REGIONS["arcs"]
    m = mesh_region(r, size=3.0, method="paper", tol=1e-7)
    assert m.n1 >= 4 and m.n2 >= 4
    assert np.all(m.quality().scaled_jacobian > 0.0)
    for k, idx in enumerate(boundary_indices(m.n1, m.n2)):
        assert r.sides[k].closest(m.params[idx]).distance.max() <= 1e-9 * r.diagonal
    # every boundary edge at most the size (the paper's stopping rule on B1/B2 pieces)
    for idx in boundary_indices(m.n1, m.n2):
        assert np.linalg.norm(np.diff(m.points[idx], axis=0), axis=1).max() <= 3.0


def test_split_region_gives_two_valid_regions():
    from medax.axis import trace_axis

    r = REGIONS["wavy"]
    ax = trace_axis(r, (1, 3))
    r1, r2 = split_region(r, (1, 3), ax.spline, ax.t_start, ax.t_end)
    for half in (r1, r2):
        Region.build(half.sides, name="half").check()
        assert half.signed_area() > 0
    assert r1.signed_area() + r2.signed_area() == pytest.approx(r.signed_area(), rel=1e-4)


def test_family_crossings_lines_and_arcs():
    # rays at 0..90 degrees and arcs of radius 1..3 cross at known polar points
    dirs = [np.array([np.cos(a), np.sin(a)]) for a in np.radians([10.0, 40.0, 80.0])]
    rays = [Line(0.5 * d, 4.0 * d) for d in dirs]
    arcs = [Arc(np.zeros(2), rad, 0.0, np.pi / 2) for rad in (1.0, 2.0, 3.0, 3.5)]
    x = family_crossings(rays, arcs, 1e-12)
    ang = np.radians([10.0, 40.0, 80.0])[:, None]
    rad = np.array([1.0, 2.0, 3.0, 3.5])[None]
    np.testing.assert_allclose(x[..., 0], rad * np.cos(ang), atol=1e-12)
    np.testing.assert_allclose(x[..., 1], rad * np.sin(ang), atol=1e-12)


def test_family_crossings_errors():
    a = [Line(np.array([0.0, 0.0]), np.array([1.0, 0.0]))]
    b = [Line(np.array([2.0, -1.0]), np.array([2.0, 1.0]))]
    with pytest.raises(MeshError, match="does not cross"):
        family_crossings(a, b, 1e-12)
    wave = [Arc(np.array([0.5, 0.0]), 0.3, np.pi, -np.pi)]  # upper half circle: crosses y=0.1 twice
    flat = [Line(np.array([0.0, 0.1]), np.array([1.0, 0.1]))]
    with pytest.raises(MeshError, match="more than once"):
        family_crossings(flat, wave, 1e-12)


def test_bad_input():
    r = REGIONS["trapezoid"]
    with pytest.raises(InputError, match="at least 1"):
        mesh_region(r, (0, 3))
    with pytest.raises(InputError, match="positive"):
        mesh_region(r, size=-1.0)
    with pytest.raises(InputError, match="larger than region"):
        mesh_region(r, size=100.0)
    with pytest.raises(InputError, match="unknown mesh method"):
        mesh_region(r, (2, 2), method="voodoo")
    with pytest.raises(InputError, match="unknown boundary rule"):
        mesh_region(r, (2, 2), boundary="even")
    assert divisions_for_size(r, 1.0) == (10, 7)


@pytest.mark.slow
def test_axis_side_closest_points_are_global():
    """A traced axis used as a side (hundreds of spans) answers the nearest point, checked
    against dense sampling of the spline; with the total sampling capped (12 pieces, as
    before) the search returned local feet up to 5e-5 of the diagonal too far."""
    from medax.axis import trace_axis
    from medax.mesh.split import AxisSide

    r = REGIONS["wavy"]
    axis = trace_axis(r, (0, 2), tol=1e-9)
    side = AxisSide(axis.spline)
    rng = np.random.default_rng(4)
    # points at 0.2 - 1.0 from the axis, on both sides: where the sub-regions' axes run
    u = rng.uniform(0.0, 1.0, 3000)
    tan = axis.spline.derivative(u)
    nrm = np.column_stack((-tan[:, 1], tan[:, 0])) / np.linalg.norm(tan, axis=1)[:, None]
    x = (
        axis.spline.evaluate(u)
        + rng.choice([-1.0, 1.0], u.size)[:, None] * rng.uniform(0.2, 1.0, u.size)[:, None] * nrm
    )
    dense = axis.spline.sample(400001)
    from scipy.spatial import cKDTree

    truth, _ = cKDTree(dense).query(x)
    got = side.closest(x).distance
    assert np.all(got <= truth + 1e-9 * r.diagonal)  # never farther than the true nearest


@pytest.mark.parametrize("div", [(3, 2), (120, 300)])
def test_inverted_count_is_the_non_positive_scaled_jacobians(div):
    """The mesher's banded count of inverted quads (edge cross products) agrees with the
    Verdict scaled Jacobian of every quad, on grids perturbed until many quads fold."""
    from medax.mesh.grid import QuadMesh
    from medax.mesh.mesher import _inverted_count

    m = mesh_region(REGIONS["arcs"], div)
    rng = np.random.default_rng(div[0])
    h = 10.0 / max(div)
    for amp in (0.0, 0.3 * h, 0.8 * h):
        pts = m.points + rng.normal(0.0, amp, m.points.shape)
        q = QuadMesh(m.region, pts, pts, *div, "ratio", {})
        want = int(np.count_nonzero(q.quality().scaled_jacobian <= 0.0))
        assert _inverted_count(q) == want
        assert (want == 0) == (amp == 0.0)
