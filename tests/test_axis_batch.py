"""The batch start (B1, B2 and chord roots in one Newton batch) against independent truth:
distances recomputed by dense sampling, the trapezoid's closed form, and the trace."""

from __future__ import annotations

import numpy as np
import pytest

from medax.axis import trace_axis
from medax.geometry import Region, read_regions, sample_regions_path
from truth import dense_sides, trapezoid_02_y


@pytest.fixture(scope="module")
def regions() -> dict[str, Region]:
    return read_regions(sample_regions_path())


def _batched(axis) -> bool:
    """The batch start was used: no predictor steps of the trace."""
    return axis.counts.predictor_steps == 0 and axis.counts.closed_form_pieces == 0


@pytest.mark.slow
@pytest.mark.parametrize("pair", [(0, 2), (1, 3)])
@pytest.mark.parametrize("tol", [1e-6, 1e-8])
def test_wavy_batch_against_dense_distances(regions, regions_spec, pair, tol):
    a = trace_axis(regions["wavy"], pair, tol=tol)
    assert _batched(a)
    sides = dense_sides(regions_spec["wavy"])
    d = a.diagonal
    da, db = sides[pair[0]], sides[pair[1]]
    assert np.abs(da(a.points) - db(a.points)).max() <= 1e-10 * d
    dense = a.spline.sample(10 * (a.n_points - 1) + 1)
    assert np.abs(da(dense) - db(dense)).max() <= tol * d
    assert sides[a.roles.b1](a.points[:1])[0] <= 1e-12 * d + 1e-14
    assert sides[a.roles.b2](a.points[-1:])[0] <= 1e-12 * d + 1e-14


@pytest.mark.parametrize("pair", [(0, 2), (1, 3)])
def test_wavy_batch_keeps_the_kinks_of_the_trace(regions, pair):
    """The C0 corners of the batch spline (kinks where a foot jumps, located by Newton) are
    corners of the trace's too, with the same ends and no more points. (The trace on
    ``(0, 2)`` also keeps a break at (1.851, 5.102) where neither foot jumps.)"""
    a = trace_axis(regions["wavy"], pair)
    b = trace_axis(regions["wavy"], pair, batch=False)
    assert _batched(a) and not _batched(b)
    ka = a.spline.evaluate(a.spline.breaks())
    kb = b.spline.evaluate(b.spline.breaks())
    assert len(ka) >= 4
    gap = np.linalg.norm(ka[:, None, :] - kb[None, :, :], axis=2).min(axis=1)
    assert gap.max() <= 1e-9 * a.diagonal
    assert np.linalg.norm(a.points[[0, -1]] - b.points[[0, -1]], axis=1).max() <= 1e-12 * a.diagonal
    assert abs(a.t_start - b.t_start) <= 1e-12 and abs(a.t_end - b.t_end) <= 1e-12
    assert a.n_points <= b.n_points


def test_trapezoid_batch_against_the_closed_form(regions):
    """Forced off the closed form, the batch start's axis is the parabola - line - parabola
    of the trapezoid (``_exact``) with exact end points."""
    a = trace_axis(regions["trapezoid"], (0, 2), closed_form=False)
    assert _batched(a)
    d = a.diagonal
    assert np.max(np.abs(a.points[:, 1] - trapezoid_02_y(a.points[:, 0]))) <= 1e-10 * d
    dense = a.spline.sample(10 * (a.n_points - 1) + 1)
    assert np.max(np.abs(dense[:, 1] - trapezoid_02_y(dense[:, 0]))) <= 1e-6 * d
    assert np.allclose(a.points[0], [1.3, 3.12], atol=1e-12 * d)
    assert np.allclose(a.points[-1], [8.7, 3.12], atol=1e-12 * d)


def test_batch_falls_back_to_the_trace(regions, monkeypatch):
    """Where the batch start does not apply (here: no chord roots), the trace runs."""
    import medax.axis.medial as medial

    monkeypatch.setattr(medial, "chord_points", lambda *a, **k: None)
    a = trace_axis(regions["wavy"], (0, 2))
    assert not _batched(a)
    assert a.max_curve_error <= 1e-6 * a.diagonal


def test_chords_out_of_order_are_refused(regions):
    """A chord whose root lies behind its neighbour's (the axis folds back across the
    chords) makes the batch start refuse: ``None``, not a zigzag."""
    from medax.axis.chords import chord_points
    from medax.axis.field import DistanceField
    from medax.geometry.region import normalised_region, pair_roles

    work, _, _ = normalised_region(regions["wavy"])
    roles = pair_roles((0, 2))
    field = DistanceField(work, roles)
    b1, b2 = work.sides[roles.b1], work.sides[roles.b2]
    assert chord_points(field, b1, b2, 8, 1e-10) is not None
    # B1 and B2 swapped: the start is on B2, so every step goes backwards
    assert chord_points(field, b2, b1, 8, 1e-10) is None


def test_a_stalled_refinement_falls_back_to_the_trace(regions, monkeypatch):
    """Uniform chords on the 120-degree channel: the refinement from them stalled at
    1.7e-6 x diagonal (splitting one interval made its neighbour stray); that result is not
    returned, the trace runs and the axis is the circle r = 7 within the tolerance."""
    import medax.axis.chords as chords

    monkeypatch.setattr(chords, "GRADING", 0.0)
    a = trace_axis(regions["annulus_sector"], (1, 3), closed_form=False)
    assert not _batched(a)
    d = a.diagonal
    assert a.max_curve_error <= 1e-6 * d
    assert np.max(np.abs(np.linalg.norm(a.points, axis=1) - 7.0)) <= 1e-10 * d
    dense = a.spline.sample(10 * (a.n_points - 1) + 1)
    assert np.max(np.abs(np.linalg.norm(dense, axis=1) - 7.0)) <= 1e-6 * d


def test_graded_chords_on_the_channel_are_the_circle(regions):
    """With the graded chords the batch start reaches the tolerance there itself."""
    a = trace_axis(regions["annulus_sector"], (1, 3), closed_form=False)
    assert _batched(a)
    d = a.diagonal
    assert np.max(np.abs(np.linalg.norm(a.points, axis=1) - 7.0)) <= 1e-10 * d
    dense = a.spline.sample(10 * (a.n_points - 1) + 1)
    assert np.max(np.abs(np.linalg.norm(dense, axis=1) - 7.0)) <= 1e-6 * d
    ang = np.degrees(np.arctan2(a.points[[0, -1], 1], a.points[[0, -1], 0]))
    assert abs(ang[0]) < 1e-9 and abs(ang[1] - 120.0) < 1e-9
