"""Random regions (seeded): convex and non-convex quads with line, arc, B-spline and polyline
sides, sizes 1e-6 to 1e6, offsets up to 1e9. Each is either refused with a typed error, or
gets axes within their tolerance by independent (dense, brute-force) distances and a 16x16
mesh that is written only when no quad is inverted, its boundary nodes on their sides."""

from __future__ import annotations

import json

import numpy as np
import pytest

from medax.axis import trace_axis
from medax.cli.main import main
from medax.errors import InputError, MeshError
from medax.geometry.region_io import region_from_dict
from medax.geometry.resolution import coordinate_resolution
from medax.mesh.mesher import mesh_region
from region_catalogue import random_side

N_REGIONS = 24
KINDS = ("line", "arc", "bspline", "polyline")


def random_region(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0.0, 2.0 * np.pi, 4))
    radii = rng.uniform(0.5, 1.5, 4)  # often non-convex
    corners = np.column_stack((radii * np.cos(angles), radii * np.sin(angles)))
    corners = corners * 10 ** rng.uniform(-6, 6) + rng.uniform(-1, 1, 2) * 10 ** rng.uniform(0, 9)
    if rng.random() < 0.3:
        corners = corners[::-1].copy()  # clockwise input
    kinds = rng.choice(KINDS, 4)
    sides = [
        random_side(rng, corners[k], corners[(k + 1) % 4], kinds[k], 0.25, 6, 0.15)
        for k in range(4)
    ]
    return {"corners": corners.tolist(), "sides": sides}


def dense_distance(points: np.ndarray, curve, n: int = 20_000) -> np.ndarray:
    """Distance from each point to ``curve`` sampled at ``n`` points and its breaks (a
    polyline's vertices), segments between."""
    s = curve.evaluate(np.union1d(np.linspace(0.0, 1.0, n), curve.breaks()))
    a, d = s[:-1], np.diff(s, axis=0)
    dd = np.maximum(np.sum(d * d, axis=1), 1e-300)
    out = np.empty(len(points))
    for i, p in enumerate(points):
        t = np.clip(np.sum((p - a) * d, axis=1) / dd, 0.0, 1.0)
        out[i] = np.sqrt(np.min(np.sum((a + t[:, None] * d - p) ** 2, axis=1)))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(N_REGIONS))
def test_random_region_refused_or_right(seed, tmp_path, capsys):
    spec = random_region(seed)
    try:
        region = region_from_dict(spec, "r")
    except InputError:
        return  # a clear refusal (typed, one line through the CLI)
    res = coordinate_resolution(region.boundary, region.diagonal)
    for pair in ((0, 2), (1, 3)):
        axis = trace_axis(region, pair)
        diag = axis.diagonal
        pts = axis.spline.evaluate(np.linspace(0.0, 1.0, 201))
        d1 = dense_distance(pts, region.sides[axis.roles.a1])
        d2 = dense_distance(pts, region.sides[axis.roles.a2])
        # the spline's tolerance, the sampling's chord error and what doubles resolve there
        assert np.max(np.abs(d1 - d2)) <= (1.2e-6 + 1e-7 + 50 * res) * diag, (seed, pair)
    try:
        mesh = mesh_region(region, divisions=(16, 16))
    except MeshError:
        return  # refused with the reason
    src, out = tmp_path / "r.json", tmp_path / "m.vtu"
    src.write_text(json.dumps({"r": spec}))
    code = main(["mesh", str(src), "--divisions", "16", "-o", str(out)])
    if mesh.quality().summary()["n_inverted"]:
        assert code == 1 and not out.exists(), seed  # never written inverted
        assert "quads are inverted" in capsys.readouterr().err
        return
    assert code == 0 and out.exists()
    grid = mesh.grid()
    rims = (grid[0, :], grid[:, -1], grid[-1, ::-1], grid[::-1, 0])  # S0, S1, S2, S3
    for k, rim in enumerate(rims):
        gap = region.sides[k].closest(rim).distance
        assert np.max(gap) <= 1e-9 * region.diagonal + 50 * res * region.diagonal, (seed, k)
