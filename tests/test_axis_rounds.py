"""The refinement's batched rounds against independent truth: kinks of the wavy region are
triple points (two branches of one constraint and the other constraint at one distance,
recomputed by dense sampling of the sides rebuilt from the JSON), whichever way the kink
Newton gets there, and the stacked local closest-point query agrees with dense sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import medax.axis.kinks as kinks
from medax.axis import trace_axis
from medax.axis.field import DistanceField
from medax.geometry import Region, read_regions, sample_regions_path
from medax.geometry.region import normalised_region, pair_roles
from truth import dense_sides, side_function

N_DENSE = 200_001


@pytest.fixture(scope="module")
def regions() -> dict[str, Region]:
    return read_regions(sample_regions_path())


def _side(spec: dict, k: int):
    c = spec["corners"]
    return side_function(spec["sides"][k], c[k], c[(k + 1) % 4])


def _basins(f, x: np.ndarray) -> list[tuple[float, float]]:
    """``(t, distance)`` of every local minimum of ``|f(t) - x|`` on [0, 1] (dense samples,
    each refined by a bounded scalar minimisation), nearest first."""
    t = np.linspace(0.0, 1.0, N_DENSE)
    d = np.linalg.norm(f(t) - x, axis=1)
    inner = np.flatnonzero((d[1:-1] <= d[:-2]) & (d[1:-1] <= d[2:])) + 1
    ends = ([0] if d[0] <= d[1] else []) + ([len(t) - 1] if d[-1] <= d[-2] else [])
    idx = np.concatenate((inner, ends))
    out = []
    dt = t[1] - t[0]
    for j in idx.astype(int).tolist():
        lo, hi = max(t[j] - dt, 0.0), min(t[j] + dt, 1.0)
        res = minimize_scalar(
            lambda s: float(np.sum((f(np.array([s]))[0] - x) ** 2)),
            bounds=(lo, hi), method="bounded", options={"xatol": 1e-14},
        )  # fmt: skip
        out.append((float(res.x), min(math.sqrt(res.fun), float(d[j]))))
    return sorted(out, key=lambda b: b[1])


def _assert_triple_points(axis, spec: dict, pair: tuple[int, int]) -> None:
    """Every C0 corner of ``axis.spline`` is on the axis and one constraint has two distinct
    nearest points there (its foot jumps), all three distances equal (dense truth)."""
    d = axis.diagonal
    corners = axis.spline.evaluate(axis.spline.breaks())
    assert len(corners) >= 4
    fa, fb = _side(spec, pair[0]), _side(spec, pair[1])
    for q in corners:
        ba, bb = _basins(fa, q), _basins(fb, q)
        da, db = ba[0][1], bb[0][1]
        assert abs(da - db) <= 1e-10 * d, (q, abs(da - db) / d)
        # the jumping constraint: a second basin, far along the curve, at the same distance
        jumps = [
            b
            for b in (ba, bb)
            if len(b) > 1 and abs(b[1][1] - b[0][1]) <= 1e-9 * d and abs(b[1][0] - b[0][0]) > 1e-3
        ]
        assert jumps, (q, ba[:2], bb[:2])


@pytest.mark.slow
@pytest.mark.parametrize("pair", [(0, 2), (1, 3)])
@pytest.mark.parametrize("tol", [1e-6, 1e-8])
def test_wavy_kinks_are_triple_points(regions, regions_spec, pair, tol):
    a = trace_axis(regions["wavy"], pair, tol=tol)
    assert a.counts.predictor_steps == 0  # the batch start
    _assert_triple_points(a, regions_spec["wavy"], pair)
    sides = dense_sides(regions_spec["wavy"])
    err = np.abs(sides[pair[0]](a.points) - sides[pair[1]](a.points))
    assert err.max() <= 1e-10 * a.diagonal


@pytest.mark.parametrize("pair", [(0, 2), (1, 3)])
def test_kinks_by_global_queries_are_the_same(regions, regions_spec, monkeypatch, pair):
    """With every local row refused, the kinks come from the global queries of the other
    constraint (the fallback) and are the same triple points."""
    ref = trace_axis(regions["wavy"], pair)
    solve = kinks._solve
    used = []

    def refuse_local(*args, **kw):
        ok, q, fs = solve(*args, **kw)
        glob = kw.get("global_other", args[-1] if len(args) > 8 else False)
        used.append(glob)
        return (ok if glob else np.zeros_like(ok)), q, fs

    monkeypatch.setattr(kinks, "_solve", refuse_local)
    a = trace_axis(regions["wavy"], pair)
    assert True in used
    _assert_triple_points(a, regions_spec["wavy"], pair)
    ka = a.spline.evaluate(a.spline.breaks())
    kr = ref.spline.evaluate(ref.spline.breaks())
    assert len(ka) == len(kr)
    assert np.linalg.norm(ka[:, None] - kr[None], axis=2).min(axis=1).max() <= 1e-9 * a.diagonal


@pytest.mark.parametrize("pair", [(0, 2), (1, 3)])
def test_stacked_local_closest_against_dense_sampling(regions, regions_spec, pair):
    """``DistanceField.closest_near`` (both constraints in one bracketed Newton) gives the
    nearest point within each row's bracket, as dense samples of the rebuilt sides do."""
    work, offset, scale = normalised_region(regions["wavy"])
    field = DistanceField(work, pair_roles(pair))
    rng = np.random.default_rng(7)
    n = 40
    x = rng.uniform(-0.3, 0.3, (n, 2))
    on2 = rng.random(n) < 0.5
    t0 = rng.uniform(0.0, 1.0, n)
    width = 0.05
    got = field.closest_near(on2, x, t0, width)
    spec = regions_spec["wavy"]
    fa, fb = _side(spec, pair[0]), _side(spec, pair[1])
    for i in range(n):
        f = fb if on2[i] else fa
        lo, hi = max(t0[i] - width, 0.0), min(t0[i] + width, 1.0)
        t = np.linspace(lo, hi, 20_001)
        d = np.linalg.norm((f(t) - offset) / scale - x[i], axis=1)
        j = int(np.argmin(d))
        a, b = t[max(j - 1, 0)], t[min(j + 1, len(t) - 1)]
        res = minimize_scalar(
            lambda s, i=i, f=f: float(np.sum(((f(np.array([s]))[0] - offset) / scale - x[i]) ** 2)),
            bounds=(a, b), method="bounded", options={"xatol": 1e-14},
        )  # fmt: skip
        best = min(math.sqrt(res.fun), float(d[j]))
        assert abs(got.distance[i] - best) <= 1e-12, (i, got.distance[i], best)
        assert lo - 1e-15 <= got.t[i] <= hi + 1e-15
