"""A fitted surface for a planar supporting face merged with blend pieces (a height field).

Where the exact routes do not apply (fillet halves along non-parallel edges of one plane,
pieces of corner blends), the merged face is the graph of a height ``h(x, y)`` along the
plane's normal over the plane: the plane piece at ``h = 0``, each fillet half or corner piece
rising or falling to its medial curve (a half turns the normal by less than 90 degrees, so the
graph is single-valued). The height is known exactly: at every grid point the line along the
normal is intersected in closed form with the surface of the member face above it (plane,
cylinder, sphere; a torus by a batched quartic), the member found by point-in-polygon on the
members' projected boundaries; outside the face there is no data (a tiny penalty continues
the fit there: the pieces' own continuations disagree beyond their edges). The fit
(:func:`medax.geometry.tensor_fit.fit_height`) puts C1 knots on the projected straight edges
parallel to the frame's axes (where the curvature jumps) and measures its own error on a
grid 7 points per knot span; the result is one cubic ``Geom_BSplineSurface`` whose control
points sit at the Greville abscissae (so ``x`` and ``y`` are reproduced exactly).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from matplotlib.path import Path
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.GeomAbs import (
    GeomAbs_BSplineSurface,
    GeomAbs_Cylinder,
    GeomAbs_Line,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_Torus,
)
from OCP.TopAbs import TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from scipy.spatial import cKDTree

from medax.cad.face_region import bspline_embedding, surface_embedding
from medax.cad.simplify.occ import (
    Array,
    bspline_surface,
    edge_points,
    edges_of,
    face_inside_point,
    face_normal_at,
    uv_bounds,
    xyz,
)
from medax.geometry.polygon_grid import inside_grid
from medax.geometry.surface_heights import graph_heights
from medax.geometry.surfaces import NurbsSurface
from medax.geometry.tensor_fit import (
    MAX_COEFFICIENTS,
    HeightFitter,
    TensorFit,
    greville,
)

#: Samples per edge for the projected member boundaries.
EDGE_SAMPLES = 48
#: A misfit point counts as stalled when the next finer fit left more than this share of
#: its error (a cubic fit divides it by 4 - 16 per halving where the data are smooth).
STALLED = 0.5
#: Most misfit points (the worst first) located on the members by :func:`_culprits`.
CULPRIT_POINTS = 20_000
#: Heights are taken where the member surface's normal is within this angle of the plane's
#: (steeper points are dropped: the penalty continues the fit there).
MAX_SLOPE_ANGLE = np.radians(70.0)


@dataclass(frozen=True)
class _Member:
    kind: str  # "plane" | "cylinder" | "sphere" | "torus" | "nurbs"
    centre: Array  # a point of the plane / the axis / the centre
    axis: Array  # the plane's normal / the cylinder's or torus' axis (unused for spheres)
    radius: float  # cylinder, sphere: radius; torus: minor radius
    outer: Path
    inner: tuple[Path, ...]
    edges: tuple[Array, ...]  # projected samples (EDGE_SAMPLES, 2) of each boundary edge
    major: float = 0.0  # torus: major radius
    nurbs: NurbsSurface | None = None  # freeform pieces: the surface
    uv_box: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)  # and the face's UV box
    plane_axes: tuple[Array, Array] = (np.zeros(3), np.zeros(3))  # the frame's ex, ey

    @property
    def boundary(self) -> Array:
        """All projected boundary samples, (k, 2)."""
        return np.vstack(self.edges)


@dataclass(frozen=True)
class FittedSurface:
    """The fitted ``surface`` (``Geom_BSplineSurface``), its measured ``error`` (largest
    height error on the face, length unit), the knot ``spacing`` that reached it and
    ``volume_change``: the signed volume between the fitted and the original surface over
    the face, positive where the solid grows (length unit cubed; a second measure of the
    volume change, independent of OCCT's integrators)."""

    surface: Any
    error: float
    spacing: float
    volume_change: float = 0.0


def _wire_edges(wire: Any, frame: tuple[Array, Array, Array]) -> list[Array]:
    """Projected samples (EDGE_SAMPLES, 2) of each edge of ``wire``, in order and following
    the wire (degenerated pole edges left out)."""
    o, ex, ey = frame
    out = []
    exp = BRepTools_WireExplorer(TopoDS.Wire(wire))
    while exp.More():
        e = exp.Current()
        if not BRep_Tool.Degenerated_s(e):
            p = edge_points(e, EDGE_SAMPLES)
            if e.Orientation() == TopAbs_REVERSED:
                p = p[::-1]
            q = p - o
            out.append(np.column_stack([q @ ex, q @ ey]))
        exp.Next()
    return out


def _polygon(edges: list[Array]) -> Path:
    """The closed polygon of a wire's consecutive edge samples."""
    return Path(np.vstack([e[:-1] for e in edges]))


def face_loops(
    face: Any, project: Callable[[Any], list[Array]]
) -> tuple[list[Array], Path, tuple[Path, ...], tuple[Array, ...]]:
    """The outer wire's projected edge samples (``project(wire)``: one (k, 2) array per edge,
    in order), its polygon, the holes' polygons and every edge's samples, of ``face``."""
    outer_wire = BRepTools.OuterWire_s(face)
    outer = project(outer_wire)
    edges, inner = list(outer), []
    exp = TopExp_Explorer(face, TopAbs_WIRE)
    while exp.More():
        w = exp.Current()
        if not w.IsSame(outer_wire):
            hole = project(w)
            inner.append(_polygon(hole))
            edges += hole
        exp.Next()
    return outer, _polygon(outer) if outer else Path(np.zeros((1, 2))), tuple(inner), tuple(edges)


@dataclass(frozen=True)
class Piece:
    """The surface of a member face: ``kind`` ("plane" | "cylinder" | "sphere" | "torus" |
    "nurbs"), a point ``centre`` (3,) and ``axis`` (3,) (the plane's normal, the cylinder's
    or torus' axis; zeros for spheres and NURBS), ``radius`` (cylinder, sphere; the torus'
    minor; a NURBS piece's smallest curvature radius), the torus' ``major`` radius, and for
    NURBS pieces the numpy copy (continued past its domain) and its ``uv_box``."""

    kind: str
    centre: Array
    axis: Array
    radius: float
    major: float = 0.0
    nurbs: NurbsSurface | None = None
    uv_box: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)


def piece_surface(
    face: Any, analytic_torus: Callable[[Any], bool] = lambda ad: True
) -> Piece | str:
    """The :class:`Piece` of ``face``: planes, cylinders, spheres and the tori for which
    ``analytic_torus(adaptor)`` holds in closed form, every other kind as a NURBS copy (its
    B-spline, or OCCT's B-spline of the face's piece: cones, revolutions, extrusions,
    Bezier); the reason (str) when there is none."""
    ad = BRepAdaptor_Surface(face)
    kind = ad.GetType()
    zero = np.zeros(3)
    if kind == GeomAbs_Plane:
        ax = ad.Plane().Axis()
        return Piece("plane", xyz(ax.Location()), xyz(ax.Direction()), 0.0)
    if kind == GeomAbs_Cylinder:
        cyl = ad.Cylinder()
        ax = cyl.Axis()
        return Piece("cylinder", xyz(ax.Location()), xyz(ax.Direction()), float(cyl.Radius()))
    if kind == GeomAbs_Sphere:
        sph = ad.Sphere()
        return Piece("sphere", xyz(sph.Location()), zero, float(sph.Radius()))
    if kind == GeomAbs_Torus and analytic_torus(ad):
        tor = ad.Torus()
        ax = tor.Axis()
        return Piece(
            "torus",
            xyz(ax.Location()),
            xyz(ax.Direction()),
            float(tor.MinorRadius()),
            float(tor.MajorRadius()),
        )
    if kind == GeomAbs_BSplineSurface:
        emb = surface_embedding(face)
        if not isinstance(emb, NurbsSurface):
            return "a B-spline piece without a NURBS embedding"
        nurbs, box = emb, uv_bounds(face)
    else:
        conv = trimmed_bspline(face)
        if conv is None:
            return f"a {kind.name[7:].lower()} piece that does not convert to a B-spline"
        nurbs = bspline_embedding(conv)
        u0, u1, v0, v1 = conv.Bounds()
        box = (u0, u1, v0, v1)
    # continued like the analytic pieces
    return Piece("nurbs", zero, zero, min_radius(ad), 0.0, replace(nurbs, extrapolate=True), box)


def _member(face: Any, frame: tuple[Array, Array, Array]) -> _Member | str:
    pc = piece_surface(face)
    if isinstance(pc, str):
        return pc
    _, outer, inner, edges = face_loops(face, lambda w: _wire_edges(w, frame))
    return _Member(
        pc.kind,
        pc.centre,
        pc.axis,
        pc.radius,
        outer,
        inner,
        edges,
        pc.major,
        pc.nurbs,
        pc.uv_box,
        (frame[1], frame[2]),
    )


def trimmed_bspline(face: Any) -> Any | None:
    """The B-spline of ``face``'s surface over the face's UV box (exact for the elementary
    and swept kinds; its own parameters), or None when OCCT's conversion fails."""
    from OCP.Geom import Geom_RectangularTrimmedSurface
    from OCP.GeomConvert import GeomConvert

    u0, u1, v0, v1 = uv_bounds(face)
    try:
        trimmed = Geom_RectangularTrimmedSurface(BRep_Tool.Surface_s(face), u0, u1, v0, v1)
        return GeomConvert.SurfaceToBSplineSurface_s(trimmed)
    except Exception:  # OCCT's Standard_Failure: no B-spline for this surface
        return None


def min_radius(ad: Any, n: int = 7) -> float:
    """Smallest principal curvature radius at ``n x n`` samples of a face's surface
    (``BRepAdaptor_Surface``)."""
    from OCP.BRepLProp import BRepLProp_SLProps

    kmax = 0.0
    for u in np.linspace(ad.FirstUParameter(), ad.LastUParameter(), n):
        for v in np.linspace(ad.FirstVParameter(), ad.LastVParameter(), n):
            props = BRepLProp_SLProps(ad, float(u), float(v), 2, 1e-9)
            if props.IsCurvatureDefined():
                kmax = max(kmax, abs(props.MaxCurvature()), abs(props.MinCurvature()))
    return 1.0 / kmax if kmax > 0 else float("inf")


def _heights(m: _Member, q: Array, n: Array) -> tuple[Array, np.ndarray]:
    """Signed distance ``t`` along ``n`` from points ``q`` (k, 3) to member ``m``'s surface
    (the root nearest the plane) and where it is defined with a moderate slope."""
    if m.kind == "plane":
        den = float(n @ m.axis)
        if abs(den) < np.cos(MAX_SLOPE_ANGLE):
            return np.zeros(len(q)), np.zeros(len(q), bool)
        return ((m.centre - q) @ m.axis) / den, np.ones(len(q), bool)
    if m.kind == "torus":
        return _torus_heights(m, q, n)
    if m.nurbs is not None:
        ex, ey = m.plane_axes
        zero = np.zeros(3)
        xy = np.column_stack([q @ ex, q @ ey])
        scale = float(np.ptp(m.nurbs.poles.reshape(-1, 3), axis=0).max())
        t, ok, normal = graph_heights(m.nurbs, (zero, ex, ey, n), xy, m.uv_box, 1e-12 * scale)
        return t - q @ n, ok & (np.abs(normal @ n) >= np.cos(MAX_SLOPE_ANGLE))
    w = q - m.centre
    if m.kind == "cylinder":
        w = w - np.outer(w @ m.axis, m.axis)
        d = n - (n @ m.axis) * m.axis
    else:
        d = n
    a = float(d @ d)
    if a < 1e-24:
        return np.zeros(len(q)), np.zeros(len(q), bool)
    b = w @ d
    c = np.einsum("ij,ij->i", w, w) - m.radius**2
    disc = b * b - a * c
    ok = disc >= 0
    root = np.sqrt(np.maximum(disc, 0.0))
    t1, t2 = (-b - root) / a, (-b + root) / a
    t = np.where(np.abs(t1) < np.abs(t2), t1, t2)
    # slope: the surface normal at the hit against n
    x = w + np.outer(t, d)
    normal = x / np.maximum(np.linalg.norm(x, axis=1), 1e-300)[:, None]
    cos = np.abs(normal @ n)
    return t, ok & (cos >= np.cos(MAX_SLOPE_ANGLE))


def _torus_heights(m: _Member, q: Array, n: Array) -> tuple[Array, np.ndarray]:
    """Line-torus intersections for many lines at once: the quartic
    ``(|X|^2 + R^2 - r^2)^2 = 4 R^2 (|X|^2 - (X.a)^2)``, ``X = w + t n``, solved by the
    eigenvalues of its companion matrices (one (k, 4, 4) batch), the real root nearest the
    plane polished by two Newton steps."""
    big, r, a = m.major, m.radius, m.axis
    w = q - m.centre
    b, za, na = w @ n, w @ a, float(n @ a)
    if abs(abs(na) - 1.0) < 1e-12 or abs(na) < 1e-12:
        t, ok = _torus_heights_aligned(m, w, n, na)
        return _torus_slope(m, w, n, t, ok)
    ww = np.einsum("ij,ij->i", w, w)
    c0 = ww + big * big - r * r
    k4 = 4 * big * big
    coef = np.stack(
        [
            4 * b,
            4 * b * b + 2 * c0 - k4 * (1 - na * na),
            4 * b * c0 - 2 * k4 * (b - za * na),
            c0 * c0 - k4 * (ww - za * za),
        ],
        axis=1,
    )
    comp = np.zeros((len(q), 4, 4))
    comp[:, 0, :] = -coef
    comp[:, 1, 0] = comp[:, 2, 1] = comp[:, 3, 2] = 1.0
    roots = np.linalg.eigvals(comp) if len(q) else np.zeros((0, 4), complex)
    real = np.abs(roots.imag) <= 1e-6 * (big + r)
    cand = np.where(real, np.abs(roots.real), np.inf)
    pick = np.argmin(cand, axis=1)
    ok = np.isfinite(cand[np.arange(len(q)), pick])
    t = roots.real[np.arange(len(q)), pick]
    for _ in range(2):
        p = (((t + coef[:, 0]) * t + coef[:, 1]) * t + coef[:, 2]) * t + coef[:, 3]
        dp = ((4 * t + 3 * coef[:, 0]) * t + 2 * coef[:, 1]) * t + coef[:, 2]
        t = t - np.where(np.abs(dp) > 1e-300, p / np.where(dp == 0, 1.0, dp), 0.0)
    return _torus_slope(m, w, n, t, ok)


def _torus_heights_aligned(m: _Member, w: Array, n: Array, na: float) -> tuple[Array, Array]:
    """Line-torus intersections in closed form when the lines are parallel to the axis
    (``|n.a| = 1``: a constant radial distance, so ``z = +-sqrt(r^2 - (rho - R)^2)``) or
    normal to it (``n.a = 0``: at height ``z`` the torus is the two circles of radius
    ``R +- sqrt(r^2 - z^2)``, each met by a quadratic). The root nearest the plane; ``ok``
    where there is one. ``w``: the points relative to the torus centre (k, 3)."""
    big, r, a = m.major, m.radius, m.axis
    za = w @ a
    roots = []
    if abs(na) > 0.5:
        rho = np.linalg.norm(w - np.outer(za, a), axis=1)
        half = np.sqrt(np.maximum(r * r - (rho - big) ** 2, 0.0))
        real = r * r - (rho - big) ** 2 >= 0
        for z in (half, -half):
            roots.append(np.where(real, (z - za) / na, np.inf))
    else:
        flat = w - np.outer(za, a)  # in the plane normal to the axis, as n is
        b = flat @ n
        c0 = np.einsum("ij,ij->i", flat, flat)
        across = np.sqrt(np.maximum(r * r - za * za, 0.0))
        for rc in (big + across, big - across):
            disc = b * b - (c0 - rc * rc)
            real = (disc >= 0) & (r * r - za * za >= 0) & (rc >= 0)
            root = np.sqrt(np.maximum(disc, 0.0))
            roots += [np.where(real, -b - root, np.inf), np.where(real, -b + root, np.inf)]
    cand = np.stack(roots, axis=1)
    pick = np.argmin(np.abs(cand), axis=1)
    t = cand[np.arange(len(w)), pick]
    ok = np.isfinite(t)
    return np.where(ok, t, 0.0), ok


def _torus_slope(m: _Member, w: Array, n: Array, t: Array, ok: Array) -> tuple[Array, Array]:
    """``(t, ok)`` with ``ok`` cleared where the torus' normal at the hit is steeper than
    ``MAX_SLOPE_ANGLE`` from ``n``."""
    x = w + np.outer(t, n)
    radial = x - np.outer(x @ m.axis, m.axis)
    core = m.major * radial / np.maximum(np.linalg.norm(radial, axis=1), 1e-300)[:, None]
    normal = (x - core) / m.radius
    cos = np.abs(normal @ n)
    return t, ok & (cos >= np.cos(MAX_SLOPE_ANGLE))


def _frame(
    plane_face: Any, members: Sequence[Any], tol: float
) -> tuple[Array, Array, Array, Array]:
    """(origin, ex, ey, n): n the plane's normal, ex along the group's longest straight
    smooth edge (an edge two members share: where the curvature jumps, so it lies on a knot
    line; a variable-radius fillet's contact line may be oblique to the face's own edges),
    else along its longest straight edge normal to n (box-like parts: every edge on a knot
    line). Straight: a line, or samples within ``tol`` of their chord."""
    ad = BRepAdaptor_Surface(plane_face)
    if ad.GetType() == GeomAbs_Plane:
        pl = ad.Plane()
        o, n = xyz(pl.Location()), xyz(pl.Axis().Direction())
        ex = xyz(pl.XAxis().Direction())
    else:
        o, n, ex = _mean_plane(ad)
    seen: dict[Any, int] = {}
    edges: list[Any] = []
    for f in members:
        for e in edges_of(f):
            key = e.TShape()
            seen[key] = seen.get(key, 0) + 1
            edges.append(e)
    best = (False, 0.0)
    for e in edges:
        d = _straight_direction(e, tol)
        if d is None or abs(d @ n) > 1e-9 * float(np.linalg.norm(d)):
            continue
        length = float(np.linalg.norm(d))
        rank = (seen[e.TShape()] > 1, length)
        if rank > best:
            best, ex = rank, d / length
    ex = ex - (ex @ n) * n
    ex /= np.linalg.norm(ex)
    return o, ex, np.cross(n, ex), n


def _mean_plane(ad: Any, n: int = 9) -> tuple[Array, Array, Array]:
    """(origin, normal, x axis) of the plane that a curved supporting face is a height field
    over: its mean point and unit normal over ``n x n`` samples of its UV box (``ad``:
    ``BRepAdaptor_Surface``). Whether the merged face really is a graph over it, the fit
    decides (steep or missing heights refuse it)."""
    from OCP.gp import gp_Pnt, gp_Vec

    us = np.linspace(ad.FirstUParameter(), ad.LastUParameter(), n)
    vs = np.linspace(ad.FirstVParameter(), ad.LastVParameter(), n)
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    pts, normals = [], []
    for u in us:
        for v in vs:
            ad.D1(float(u), float(v), p, du, dv)
            c = np.cross(xyz(du), xyz(dv))
            size = float(np.linalg.norm(c))
            if size > 0.0:
                pts.append(xyz(p))
                normals.append(c / size)
    mean = np.sum(normals, axis=0)
    normal = mean / max(float(np.linalg.norm(mean)), 1e-300)
    ex = np.eye(3)[int(np.argmin(np.abs(normal)))]
    ex = ex - (ex @ normal) * normal
    return np.mean(pts, axis=0), normal, ex / float(np.linalg.norm(ex))


def _straight_direction(edge: Any, tol: float) -> Array | None:
    """End-to-end vector of a straight edge (a line, or 9 samples within ``tol`` of the
    chord), else None."""
    c = BRepAdaptor_Curve(edge)
    if c.GetType() == GeomAbs_Line:
        d = xyz(c.Line().Direction())
        return d * abs(c.LastParameter() - c.FirstParameter())
    p = edge_points(edge, 9)
    chord = p[-1] - p[0]
    length = float(np.linalg.norm(chord))
    if length < 100 * tol:
        return None
    w = p - p[0]
    off = w - np.outer(w @ chord / length**2, chord)
    return chord if float(np.abs(off).max()) <= tol else None


def _breaks(members: Sequence[_Member], tol: float) -> tuple[list[float], list[float]]:
    """Coordinates of projected straight boundary edges parallel to the frame's axes."""
    xs: list[float] = []
    ys: list[float] = []
    for m in members:
        for e in m.edges:
            if np.ptp(e, axis=0).max() < tol:
                continue  # an edge seen end-on
            if np.ptp(e[:, 0]) < tol:
                xs.append(float(e[:, 0].mean()))
            if np.ptp(e[:, 1]) < tol:
                ys.append(float(e[:, 1].mean()))
    return _dedup(xs, tol), _dedup(ys, tol)


def _dedup(vals: list[float], tol: float) -> list[float]:
    out: list[float] = []
    for v in sorted(vals):
        if not out or v - out[-1] > 100 * tol:
            out.append(v)
    return out


def _point_labels(pts: Array, ms: Sequence[_Member], boxes: list[tuple[Array, Array]]) -> Array:
    """Index (n,) of the member whose projected boundary contains each point (n, 2), or
    -1; the first member wins on shared edges."""
    label = np.full(len(pts), -1)
    for i, m in enumerate(ms):
        # only the points in the member's bounding box go to the polygon test
        blo, bhi = boxes[i]
        cand = np.flatnonzero((label < 0) & np.all(pts >= blo, axis=1) & np.all(pts <= bhi, axis=1))
        if cand.size == 0:
            continue
        inside = m.outer.contains_points(pts[cand], radius=0.0)
        for hole in m.inner:
            inside &= ~hole.contains_points(pts[cand])
        label[cand[inside]] = i
    return label


def _grid_labels(
    x: Array, y: Array, ms: Sequence[_Member], boxes: list[tuple[Array, Array]]
) -> Array | None:
    """:func:`_point_labels` for points on a tensor grid (``x``, ``y`` (nx, ny) from
    ``meshgrid(..., indexing="ij")``) by scanlines (:func:`inside_grid`: the fit grids
    have 10^5 - 10^6 points); None when they are not a grid."""
    if x.ndim != 2 or not (np.all(x == x[:, :1]) and np.all(y == y[:1, :])):
        return None
    xs, ys = x[:, 0], y[0, :]
    label = np.full(x.shape, -1)
    for i, m in enumerate(ms):
        blo, bhi = boxes[i]
        ix = np.flatnonzero((xs >= blo[0]) & (xs <= bhi[0]))
        iy = np.flatnonzero((ys >= blo[1]) & (ys <= bhi[1]))
        if ix.size == 0 or iy.size == 0:
            continue
        sx, sy = xs[ix], ys[iy]
        inside = inside_grid(sx, sy, np.asarray(m.outer.vertices, dtype=np.float64))
        for hole in m.inner:
            inside &= ~inside_grid(sx, sy, np.asarray(hole.vertices, dtype=np.float64))
        block = label[np.ix_(ix, iy)]
        block[inside & (block < 0)] = i
        label[np.ix_(ix, iy)] = block
    return label.ravel()


@dataclass(frozen=True)
class GraphSetup:
    """What the fits of one merged face share (:func:`graph_setup`): the plane's frame
    ``o, ex, ey`` and normal ``n`` (each (3,)), and the fitter of the height over it."""

    o: Array
    ex: Array
    ey: Array
    n: Array
    fitter: HeightFitter
    members: tuple[_Member, ...] = ()


class Refusal(str):
    """A fitted route's reason for refusing a merged face, with the members it is traced
    to (``culprits``: indices into the members; empty when no member is to blame alone)."""

    culprits: frozenset[int]

    def __new__(cls, why: str, culprits: Iterable[int] = ()) -> Refusal:
        obj = super().__new__(cls, why)
        obj.culprits = frozenset(culprits)
        return obj


def graph_setup(plane_face: Any, members: Sequence[Any], geom_tol: float) -> GraphSetup | str:
    """The frame, the members' projected boundaries and heights, and the knot placement of
    the merged face made of ``members`` over the plane of ``plane_face`` (see
    :func:`graph_surface`); the reason (str) when a member cannot be merged."""
    o, ex, ey, n = _frame(plane_face, members, geom_tol)
    frame = (o, ex, ey)
    ms: list[_Member] = []
    for f in members:
        m = _member(f, frame)
        if isinstance(m, str):
            return m
        ms.append(m)
    curved = [m.radius for m in ms if m.kind != "plane"]
    if not curved:
        return "no curved piece to merge"
    rmin = min(curved)
    if not rmin > geom_tol:  # a pole or apex of a freeform blend piece (seen: 6e-23)
        return (
            f"a merged piece has a degenerate curvature radius ({rmin:.1e}): no height-field "
            "fit spacing follows from it"
        )
    bnds = [m.boundary for m in ms]
    allb = np.vstack(bnds)
    margin = 0.25 * rmin
    lo, hi = allb.min(axis=0) - margin, allb.max(axis=0) + margin
    boxes = [(b.min(axis=0) - geom_tol, b.max(axis=0) + geom_tol) for b in bnds]

    def h(x: Array, y: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        pts = np.column_stack([x.ravel(), y.ravel()])
        label = _grid_labels(x, y, ms, boxes)
        if label is None:
            label = _point_labels(pts, ms, boxes)
        face_mask = label >= 0
        z = np.zeros(len(pts))
        ok = np.zeros(len(pts), bool)
        q = o + np.outer(pts[:, 0], ex) + np.outer(pts[:, 1], ey)
        for i, m in enumerate(ms):
            sel = label == i
            if sel.any():
                z[sel], ok[sel] = _heights(m, q[sel], n)
        return z.reshape(x.shape), ok.reshape(x.shape), face_mask.reshape(x.shape)

    xb, yb = _breaks(ms, geom_tol)
    # probe lines through every curved piece's boundary samples
    rim = np.vstack([b for m, b in zip(ms, bnds, strict=True) if m.kind != "plane"])
    probes = (rim[:, 0], rim[:, 1])
    fitter = HeightFitter((lo[0], hi[0]), (lo[1], hi[1]), xb, yb, h, rmin / 4, probes)
    return GraphSetup(o, ex, ey, n, fitter, tuple(ms))


def graph_surface(
    plane_face: Any,
    members: Sequence[Any],
    fit_tol: float,
    geom_tol: float,
    probe: bool = False,
    setup: GraphSetup | str | None = None,
    accept: float | None = None,
) -> FittedSurface | str:
    """Fitted surface of the merged face made of ``members`` (faces of the split solid, one of
    them on the supporting plane of ``plane_face``), to ``fit_tol`` (length unit); the reason
    (str) when the pieces are not a height field over the plane or the fit misses ``fit_tol``.
    ``geom_tol``: length tolerance of the geometric tests. With ``probe`` only the coarsest
    fit is made and only a face that is no height field is refused (a cheap first check).
    ``setup``: :func:`graph_setup` of the same face and members, when the caller keeps it
    (the probe's fit is then not made again by the full fit). ``accept``: the largest error
    taken when the fit cannot reach ``fit_tol`` (``fit_tol`` when None)."""
    if setup is None:
        setup = graph_setup(plane_face, members, geom_tol)
    if isinstance(setup, str):
        return setup
    o, ex, ey, n = setup.o, setup.ex, setup.ey, setup.n
    fit = setup.fitter.fit(fit_tol, levels=1 if probe else 4)
    if fit is None:
        return Refusal(
            f"the fitted surface would need more than {MAX_COEFFICIENTS} coefficients "
            "(curved pieces spread over the whole face, e.g. many filleted bosses)",
            _finest(setup.members),
        )
    limit = fit_tol if accept is None else max(accept, fit_tol)
    if not np.isfinite(fit.error):
        return Refusal(
            "the merged face is not a height field over its plane (steep or undefined)",
            _culprits(setup, fit, limit),
        )
    if fit.error > limit and not probe:
        return Refusal(
            f"fitted surface error {fit.error:.2e} above {limit:.2e} (curvature jumps off the "
            "knot lines, e.g. along circles, a step at a cross edge, or a crease where two "
            "fillets meet in a mitre)",
            _culprits(setup, fit, limit),
        )
    outward = _outward_sign(plane_face, n)
    return FittedSurface(
        _bspline_surface(fit, o, ex, ey, n),
        fit.error,
        fit.spacing,
        outward * fit.volume if outward else float("nan"),
    )


def _finest(members: Sequence[_Member]) -> frozenset[int]:
    """The curved members of the smallest curvature radius (within 1 %): they set the fit's
    knot spacing (a quarter of it). Empty when every curved member has it (keeping them all
    is no partial answer)."""
    curved = {i: m.radius for i, m in enumerate(members) if m.kind != "plane"}
    if not curved:
        return frozenset()
    rmin = min(curved.values())
    fine = frozenset(i for i, r in curved.items() if r <= 1.01 * rmin)
    return fine if len(fine) < len(curved) else frozenset()


def _culprits(setup: GraphSetup, fit: TensorFit, limit: float) -> frozenset[int]:
    """The curved members the misfit of ``fit`` lies on: each check point inside the face
    whose error is above ``limit`` (or whose height is undefined) goes to the nearest curved
    member in the plane's projection (0 inside its boundary); a member is blamed when its
    worst point is at least a quarter of the worst of all (a step or a crease dominates; a
    member whose error only rides on it is tried again without it). Where a coarser fit was
    made, only the points whose error it did not halve count, when there are any: a step or
    a crease stays, a curved piece not yet resolved by the knots converges."""
    curved = [i for i, m in enumerate(setup.members) if m.kind != "plane"]
    if not curved:
        return frozenset()
    xc, yc = fit.check_samples()
    x, y = np.meshgrid(xc, yc, indexing="ij")
    z, ok, inside = setup.fitter.h(x, y)
    err = np.where(ok, np.abs(fit(xc, yc) - z), np.inf)
    bad = inside & (err > limit)
    if not bad.any():
        return frozenset()
    prev = setup.fitter.coarser(fit)
    if prev is not None:
        stalled = bad & ~(err < STALLED * np.abs(prev(xc, yc) - z))
        bad = stalled if stalled.any() else bad
    e = err[bad]
    order = np.argsort(-e, kind="stable")[:CULPRIT_POINTS]
    pts, e = np.column_stack([x[bad], y[bad]])[order], e[order]
    dist = np.empty((len(curved), len(pts)))
    for row, i in enumerate(curved):
        m = setup.members[i]
        d, _ = cKDTree(m.boundary).query(pts)
        inner = m.outer.contains_points(pts)
        for hole in m.inner:
            inner &= ~hole.contains_points(pts)
        dist[row] = np.where(inner, 0.0, d)
    near = np.argmin(dist, axis=0)
    worst = np.full(len(curved), -1.0)
    np.maximum.at(worst, near, e)
    top = worst.max()
    blamed = worst >= (0.25 * top if np.isfinite(top) else np.inf)
    return frozenset(curved[r] for r in np.flatnonzero(blamed))


def _outward_sign(plane_face: Any, n: Array) -> float:
    """+1 when ``n`` is the solid's outward normal on ``plane_face``, else -1 (heights along
    ``n`` then grow the solid); 0 when it cannot be told (no volume estimate then)."""
    p = face_inside_point(plane_face)
    out = None if p is None else face_normal_at(plane_face, p)
    return 0.0 if out is None else float(np.sign(out @ n))


def _bspline_surface(fit: TensorFit, o: Array, ex: Array, ey: Array, n: Array) -> Any:
    """``Geom_BSplineSurface`` of the fit: poles ``o + gx ex + gy ey + c n``."""
    gx, gy = greville(fit.tx), greville(fit.ty)
    poles = o + gx[:, None, None] * ex + gy[None, :, None] * ey + fit.coef[:, :, None] * n
    return bspline_surface(poles, fit.tx, fit.ty, 3, 3)
