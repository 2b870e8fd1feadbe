"""Random 4-sided regions (seeded), shared by the random-region mesh test and
``benchmarks/bench_regions.py``: convex and non-convex quads with line, arc, B-spline and
polyline sides, scales 1e-3 to 1e3, offsets up to 10 x the scale, a third clockwise."""

from __future__ import annotations

from typing import Any

import numpy as np

from medax.errors import InputError
from medax.geometry.region import Region
from medax.geometry.region_io import region_from_dict

KINDS = ("line", "arc", "bspline", "polyline")
#: the seed of the first region; region ``k`` of the catalogue is the k-th valid one from it
FIRST_SEED = 24_000


def random_side(
    rng: np.random.Generator,
    p0: np.ndarray,
    p1: np.ndarray,
    kind: str,
    sagitta: float = 0.3,
    points: int = 7,
    bump_share: float = 0.2,
) -> dict:
    """One side from ``p0`` to ``p1`` (2,): a line, an arc of sagitta 3 % - ``sagitta`` of
    the chord (either way), or a B-spline / polyline through 3 - ``points`` points bumped off
    the chord by up to ``bump_share`` of its length."""
    chord = p1 - p0
    length = float(np.linalg.norm(chord))
    if kind == "line":
        return {"kind": "line"}
    if kind == "arc":
        h = float(rng.uniform(0.03, sagitta)) * float(rng.choice([-1.0, 1.0]))
        return {"kind": "arc", "sagitta": h * length}
    m = int(rng.integers(3, points + 1))
    normal = np.array([-chord[1], chord[0]]) / length
    bump = rng.uniform(-bump_share, bump_share, m) * length
    bump[[0, -1]] = 0.0
    pts = p0 + np.linspace(0.0, 1.0, m)[:, None] * chord + bump[:, None] * normal
    pts[0], pts[-1] = p0, p1
    if kind == "polyline":
        return {"kind": "polyline", "points": pts.tolist()}
    return {"kind": "bspline", "degree": min(3, m - 1), "points": pts.tolist()}


def random_spec(seed: int) -> dict[str, Any]:
    """The JSON spec of random region ``seed`` (valid or not)."""
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0.0, 2.0 * np.pi, 4))
    radii = rng.uniform(0.4, 1.6, 4)  # often non-convex
    corners = np.column_stack((radii * np.cos(angles), radii * np.sin(angles)))
    scale = 10 ** rng.uniform(-3.0, 3.0)
    corners = (corners + rng.uniform(-10.0, 10.0, 2)) * scale
    if rng.random() < 0.3:
        corners = corners[::-1].copy()  # clockwise input
    kinds = rng.choice(KINDS, 4)
    sides = [random_side(rng, corners[k], corners[(k + 1) % 4], str(kinds[k])) for k in range(4)]
    return {"corners": corners.tolist(), "sides": sides}


def corner_angles(region: Region) -> np.ndarray:
    """Interior angles (4,) in degrees at corners 0..3, between chords to points of the two
    sides 1e-6 of their parameter from the corner (not the sides' derivatives the mesher's
    obstacle check uses); above 180 a corner is reflex."""
    out = np.empty(4)
    h = np.array([1e-6])
    for k in range(4):
        prev, side = region.sides[k - 1], region.sides[k]
        back = prev.evaluate(1.0 - h)[0] - prev.evaluate(np.array([1.0]))[0]
        ahead = side.evaluate(h)[0] - side.evaluate(np.array([0.0]))[0]
        cross = ahead[0] * back[1] - ahead[1] * back[0]
        out[k] = np.degrees(np.arctan2(cross, float(ahead @ back))) % 360.0
    return out


def valid_regions(
    count: int, first_seed: int = FIRST_SEED, reflex: bool = False
) -> list[tuple[int, dict, Region]]:
    """The first ``count`` valid random regions from ``first_seed`` on: (seed, spec, region);
    valid = ``region_from_dict`` accepts it (the sides form one simple closed curve). With
    ``reflex=False`` only regions whose four corners are below 180 degrees (a reflex corner
    admits no structured quad mesh: its one quad has the corner's angle), with ``True`` only
    regions with a reflex corner."""
    out: list[tuple[int, dict, Region]] = []
    seed = first_seed
    while len(out) < count:
        spec = random_spec(seed)
        seed += 1
        try:
            region = region_from_dict(spec, f"r{seed - 1}")
        except InputError:
            continue
        if bool(np.any(corner_angles(region) >= 180.0)) == reflex:
            out.append((seed - 1, spec, region))
    return out
