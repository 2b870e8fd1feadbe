"""Independent truth for axis tests: distances to side curves by dense sampling.

Deliberately does not use medax's curve or closest-point code: sides are rebuilt from the
JSON definition with scipy / numpy, sampled densely, and the nearest sample is refined by a
bounded scalar minimisation.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import BSpline
from scipy.optimize import minimize_scalar
from scipy.spatial import cKDTree


def side_function(spec: dict, p0, p1):
    """A callable ``f(t) -> (n, 2)`` on [0, 1] for one JSON side between corners p0, p1."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    kind = spec["kind"]
    if kind == "line":
        return lambda t: p0 + np.asarray(t)[:, None] * (p1 - p0)
    if kind == "arc":
        if "sagitta" in spec:
            h = spec["sagitta"]
            c = np.linalg.norm(p1 - p0)
            right = np.array([(p1 - p0)[1], -(p1 - p0)[0]]) / c
            r = (c * c / 4 + h * h) / (2 * abs(h))
            apex = (p0 + p1) / 2 + h * right
            centre = apex - math.copysign(r, h) * right
        else:
            centre, r = np.asarray(spec["center"], float), spec["radius"]
        a0 = math.atan2(*(p0 - centre)[::-1])
        a1 = math.atan2(*(p1 - centre)[::-1])
        sweep = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
        if "sagitta" in spec:
            am = math.atan2(*(apex - centre)[::-1])
            sweep = 2 * ((am - a0 + math.pi) % (2 * math.pi) - math.pi)
        return lambda t: (
            centre
            + r
            * np.column_stack(
                (np.cos(a0 + sweep * np.asarray(t)), np.sin(a0 + sweep * np.asarray(t)))
            )
        )
    if kind == "bspline":
        pts = np.asarray(spec["points"], float)
        k = spec.get("degree", 3)
        n_inner = len(pts) - k - 1
        knots = np.r_[np.zeros(k + 1), np.linspace(0, 1, n_inner + 2)[1:-1], np.ones(k + 1)]
        spl = BSpline(knots, pts, k)
        return lambda t: spl(np.asarray(t))
    if kind == "polyline":
        pts = np.asarray(spec["points"], float)
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        cum = np.r_[0, np.cumsum(seg)] / seg.sum()
        return lambda t: np.column_stack(
            (np.interp(np.asarray(t), cum, pts[:, 0]), np.interp(np.asarray(t), cum, pts[:, 1]))
        )
    raise ValueError(kind)


class DenseDistance:
    """Distance from points to one side: nearest of 200k samples, refined by Brent."""

    def __init__(self, f, n: int = 200_001) -> None:
        self.f = f
        self.t = np.linspace(0.0, 1.0, n)
        self.tree = cKDTree(f(self.t))
        self.dt = self.t[1] - self.t[0]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        _, idx = self.tree.query(x, k=3)
        out = np.empty(len(x))
        for i, (xi, cand) in enumerate(zip(x, idx, strict=True)):
            best = np.inf
            for j in cand:
                lo = max(self.t[j] - self.dt, 0.0)
                hi = min(self.t[j] + self.dt, 1.0)
                res = minimize_scalar(
                    lambda s, xi=xi: float(np.sum((self.f(np.array([s]))[0] - xi) ** 2)),
                    bounds=(lo, hi),
                    method="bounded",
                    options={"xatol": 1e-14},
                )
                best = min(
                    best,
                    math.sqrt(res.fun),
                    float(np.linalg.norm(self.f(np.array([lo]))[0] - xi)),
                    float(np.linalg.norm(self.f(np.array([hi]))[0] - xi)),
                )
            out[i] = best
        return out


def dense_sides(spec: dict) -> list[DenseDistance]:
    """The four sides of a JSON region as independent distance functions."""
    corners = spec["corners"]
    return [
        DenseDistance(side_function(spec["sides"][k], corners[k], corners[(k + 1) % 4]))
        for k in range(4)
    ]


class Cylinder:
    """``E(u, v) = (R cos u, R sin u, v)``: a test embedding written independently of medax's
    surfaces."""

    dim = 3
    is_identity = False

    def __init__(self, radius: float) -> None:
        self.r = radius

    def evaluate(self, p):
        return np.column_stack((self.r * np.cos(p[:, 0]), self.r * np.sin(p[:, 0]), p[:, 1]))

    def jacobian(self, p):
        j = np.zeros((len(p), 3, 2))
        j[:, 0, 0] = -self.r * np.sin(p[:, 0])
        j[:, 1, 0] = self.r * np.cos(p[:, 0])
        j[:, 2, 1] = 1.0
        return j


def trapezoid_02_y(x: np.ndarray) -> np.ndarray:
    """Exact axis of the trapezoid between y=0 and the top side (2.5..7.5, 6)."""
    y = np.full_like(x, 3.0)
    left, right = x < 2.5, x > 7.5
    y[left] = ((x[left] - 2.5) ** 2 + 36.0) / 12.0
    y[right] = ((x[right] - 7.5) ** 2 + 36.0) / 12.0
    return y


def boundary_distances(old: object, new: object, n_old: int, n_new: int) -> tuple[float, float]:
    """(old -> new, new -> old) largest distances between two solids' boundaries, from
    ``n x n`` samples per face measured against all faces of the other solid (BRepExtrema
    where a foot falls outside), not the simplifier's per-group check. Imports OCP lazily:
    the axis tests that share this module run without it."""
    from medax.cad.simplify.occ import faces_of
    from medax.cad.simplify.validate import face_samples, max_distance

    old_faces, new_faces = list(faces_of(old)), list(faces_of(new))
    old_pts = np.vstack([face_samples(f, n_old) for f in old_faces])
    new_pts = np.vstack([face_samples(f, n_new) for f in new_faces])
    return max_distance(old_pts, new_faces), max_distance(new_pts, old_faces)


def blended_targets(phi_a: np.ndarray, phi_b: np.ndarray, n1: int, n2: int):
    """The ratios node ``(i, j)`` of an ``n1 x n2`` ratio grid must have, from the ratios
    ``phi_a`` (pair (S0, S2)) and ``phi_b`` (pair (S1, S3)) measured at all its nodes (each
    ((n1 + 1) * (n2 + 1),), row ``j`` after row): the boundary values blended linearly, in
    ``i / n1`` from column 0 to column n1 for ``phi_a`` and in ``j / n2`` from row 0 to row
    n2 for ``phi_b``. Returns two (n2 + 1, n1 + 1) arrays."""
    a, b = phi_a.reshape(n2 + 1, n1 + 1), phi_b.reshape(n2 + 1, n1 + 1)
    u = (np.arange(n1 + 1) / n1)[None, :]
    v = (np.arange(n2 + 1) / n2)[:, None]
    ra = (1 - u) * a[:, :1] + u * a[:, -1:]
    rb = (1 - v) * b[:1, :] + v * b[-1:, :]
    return ra, rb


def polyline_arc_lengths(f, t: np.ndarray, n: int = 400001) -> np.ndarray:
    """Arc lengths (len(t),) from ``f(0)`` to ``f(t)`` along the dense polyline of ``n``
    samples of ``f`` (a callable on [0, 1]), interpolated linearly between samples."""
    s = np.linspace(0.0, 1.0, n)
    cum = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(f(s), axis=0), axis=1))))
    return np.interp(t, s, cum)


def classified_and_simplified(shape: object) -> tuple[object, object]:
    """(classification, simplification) of a part built with OCCT: healed, classified by
    medax, simplified with the default tolerance."""
    from medax.cad.classify import classify_solid
    from medax.cad.reader import heal
    from medax.cad.simplify import simplify, specs_from_classification

    cls = classify_solid(heal(shape))
    return cls, simplify(cls.shape, specs_from_classification(cls))


def assert_same_solid(
    before: object,
    r: object,
    n_old: int = 9,
    n_new: int = 16,
    volume_tol: float = 1e-6,
    deviation_tol: float = 1e-5,
) -> None:
    """The simplified solid is one valid closed shell, its volume within ``volume_tol``
    (relative) of the input's, and its boundary within ``deviation_tol`` x diagonal of the
    input's both ways (whole solids; the defaults are the issue's, exact surfaces are held
    to tighter ones)."""
    from medax.cad.simplify.validate import check

    c = check(r.shape)  # type: ignore[attr-defined]
    assert c.valid and c.shells == 1 and c.closed
    assert abs(r.volume_rel_change) <= volume_tol  # type: ignore[attr-defined]
    old_to_new, new_to_old = boundary_distances(before, r.shape, n_old, n_new)  # type: ignore[attr-defined]
    assert max(old_to_new, new_to_old) <= deviation_tol * r.diagonal  # type: ignore[attr-defined]


def face_neighbours(shape: object) -> list[set[int]]:
    """For each face of ``shape`` (0-based, indexed-map order), the faces it shares an
    edge with."""
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE

    from medax.cad.simplify.occ import shape_map
    from medax.cad.simplify.specs import edge_face_map

    fmap, emap, e2f = (
        shape_map(shape, TopAbs_FACE),
        shape_map(shape, TopAbs_EDGE),
        edge_face_map(shape),
    )
    out: list[set[int]] = [set() for _ in range(fmap.Size())]
    for i in range(1, emap.Size() + 1):
        owners = {fmap.FindIndex(f) - 1 for f in e2f.FindFromKey(emap.FindKey(i))}
        for f in owners:
            out[f] |= owners - {f}
    return out


def default_volume(shape: object) -> float:
    """Volume by OCCT's default mass properties (``BRepGProp.VolumeProperties_s`` without
    a tolerance: fixed-order Gauss), what FreeCAD and CadQuery report."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    return float(props.Mass())
