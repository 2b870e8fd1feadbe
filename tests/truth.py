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


def arc_geometry(spec: dict, p0, p1) -> tuple[np.ndarray, float, float, float]:
    """(centre, radius, start angle, sweep) of a JSON arc side from ``p0`` to ``p1``."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
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
    return centre, float(r), a0, sweep


def side_function(spec: dict, p0, p1):
    """A callable ``f(t) -> (n, 2)`` on [0, 1] for one JSON side between corners p0, p1."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    kind = spec["kind"]
    if kind == "line":
        return lambda t: p0 + np.asarray(t)[:, None] * (p1 - p0)
    if kind == "arc":
        centre, r, a0, sweep = arc_geometry(spec, p0, p1)
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


class SideTruth:
    """Distances from many points to one JSON side at once, independent of medax's curves:
    lines and polylines by exact point-to-segment distances, arcs in closed form (radial
    distance inside the sweep, else the nearer end), B-splines (scipy) by the nearest of
    ``n`` samples' chords and Newton steps on ``(f(t) - x) . f'(t)`` within that chord's
    neighbours. All in coordinates relative to ``origin`` (exact differences of nearby
    doubles), so regions far from the origin keep their relative accuracy. B-spline
    distances are to points on the curve (never a chord's sagitta below it)."""

    def __init__(self, spec: dict, p0, p1, origin, n: int = 20_001, k: int = 4) -> None:
        o = np.asarray(origin, float)
        self.origin = o
        spec = _shifted(spec, o)
        p0, p1 = np.asarray(p0, float) - o, np.asarray(p1, float) - o
        self.kind = spec["kind"]
        self.k = k
        if self.kind == "arc":
            self.arc = arc_geometry(spec, p0, p1)
            self.ends = np.array([p0, p1])
            return
        if self.kind == "line":
            self.s = np.array([p0, p1])
        elif self.kind == "polyline":
            self.s = np.asarray(spec["points"], float)
        else:
            pts = np.asarray(spec["points"], float)
            deg = spec.get("degree", 3)
            n_inner = len(pts) - deg - 1
            knots = np.r_[np.zeros(deg + 1), np.linspace(0, 1, n_inner + 2)[1:-1], np.ones(deg + 1)]
            self.spl = BSpline(knots, pts, deg)
            self.d1 = self.spl.derivative(1)
            self.d2 = self.spl.derivative(2) if deg > 1 else None
            self.t = np.union1d(np.linspace(0.0, 1.0, n), knots)  # no chord across a knot
            self.s = self.spl(self.t)
        self.tree = cKDTree(self.s)

    def __call__(self, x) -> np.ndarray:
        """Distances (m,) from points ``x`` (m, 2) (absolute coordinates) to the side."""
        x = np.atleast_2d(np.asarray(x, float)) - self.origin
        if self.kind == "arc":
            return self._arc(x)
        k = min(self.k, len(self.s))
        _, idx = self.tree.query(x, k=k)
        idx = np.asarray(idx).reshape(len(x), k)
        j = np.clip(np.concatenate((idx, idx - 1), axis=1), 0, len(self.s) - 2)  # chords
        a, ab = self.s[j], self.s[j + 1] - self.s[j]
        w = np.einsum("mkd,mkd->mk", x[:, None] - a, ab) / np.maximum(
            np.einsum("mkd,mkd->mk", ab, ab), 1e-300
        )
        w = np.clip(w, 0.0, 1.0)
        d = np.linalg.norm(a + w[..., None] * ab - x[:, None], axis=2)
        best = np.argmin(d, axis=1)
        rows = np.arange(len(x))
        dist = d[rows, best]
        if self.kind != "bspline":
            return dist
        jb = j[rows, best]
        lo = self.t[np.maximum(jb - 1, 0)]
        hi = self.t[np.minimum(jb + 2, len(self.t) - 1)]
        t = self.t[jb] + w[rows, best] * (self.t[jb + 1] - self.t[jb])
        for _ in range(8):
            r, c1 = self.spl(t) - x, self.d1(t)
            c2 = self.d2(t) if self.d2 is not None else np.zeros_like(c1)
            g = np.einsum("md,md->m", r, c1)
            dg = np.einsum("md,md->m", c1, c1) + np.einsum("md,md->m", r, c2)
            t = np.clip(t - np.where(dg > 0, g / np.where(dg > 0, dg, 1.0), 0.0), lo, hi)
        # points on the curve only (a chord is off it by its sagitta)
        near = np.linalg.norm(self.s[idx] - x[:, None], axis=2).min(axis=1)
        return np.minimum(near, np.linalg.norm(self.spl(t) - x, axis=1))

    def _arc(self, x: np.ndarray) -> np.ndarray:
        centre, r, a0, sweep = self.arc
        v = x - centre
        ang = np.arctan2(v[:, 1], v[:, 0])
        rel = np.mod((ang - a0) * np.sign(sweep), 2 * math.pi)  # angle along the sweep
        inside = rel <= abs(sweep)
        radial = np.abs(np.linalg.norm(v, axis=1) - r)
        ends = np.min(np.linalg.norm(x[:, None] - self.ends[None], axis=2), axis=1)
        return np.where(inside, radial, ends)


def truth_sides(spec: dict) -> list[SideTruth]:
    """The four sides of a JSON region as :class:`SideTruth`, relative to its first corner."""
    c = spec["corners"]
    return [SideTruth(spec["sides"][k], c[k], c[(k + 1) % 4], c[0]) for k in range(4)]


def _shifted(spec: dict, o: np.ndarray) -> dict:
    """A JSON side with its points (and centre) moved by ``-o``."""
    out = dict(spec)
    if "points" in spec:
        out["points"] = (np.asarray(spec["points"], float) - o).tolist()
    if "center" in spec:
        out["center"] = (np.asarray(spec["center"], float) - o).tolist()
    return out
