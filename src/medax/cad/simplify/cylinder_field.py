"""A fitted surface for a cylindrical supporting face merged with any blend halves: the
*cylinder field* route (after the ring route, which takes one B-spline half all the way
round, refused the group).

The merged face is a field over the support's cylinder (:mod:`medax.geometry.cylinder_field`):
at the arc length ``s = R (theta - theta0)`` and the axial ``z`` it lies on the radial line,
at the offset ``h(s, z)`` off the cylinder. The support piece may be any part of the
cylinder (a STEP cylinder split into two 180-degree faces, a partial arc), the halves
fillets along its rulings or round its foot, several of them, on cylinders, tori, spheres,
planes or B-splines. A member's offset is where the radial line meets its surface: in
closed form for planes, cylinders, spheres and coaxial tori, on the NURBS copy otherwise
(Newton on the rays: :func:`medax.geometry.ring_heights.ray_points`); the member above a
point is found by point-in-polygon on the members' boundaries in ``(s, z)`` (unwrapped
along each wire, so a ring member with its seam is one polygon two periods wide). Knot
lines (C1) lie on the members' rulings and circles, where the curvature jumps. The fit is
of the points themselves (x, y, z on one knot grid), measured on the check grid like the
plane route's; periodic in ``theta`` when a member has a seam (the face goes all the way
round: :func:`medax.geometry.periodic_fit.fit_radial_height`, no ruling knots then),
clamped over the face's angular span otherwise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from matplotlib.path import Path
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.GeomAbs import (
    GeomAbs_Cylinder,
)
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopoDS import TopoDS
from scipy.interpolate import CubicSpline
from scipy.spatial import cKDTree

from medax.cad.simplify.fitted import FittedSurface, face_loops, piece_surface
from medax.cad.simplify.occ import (
    Array,
    bspline_surface,
    edge_points,
    edges_of,
    face_inside_point,
    face_normal_at,
    xyz,
)
from medax.cad.simplify.ring import periodic_surface
from medax.geometry.cylinder_field import (
    PERIOD,
    CylinderFrame,
    PointFit,
    PointFitter,
    largest_gap,
    radial_heights,
    signed_volume,
)
from medax.geometry.periodic_fit import PeriodicFit, fit_radial_height, periodic_knots
from medax.geometry.ring_heights import RingFrame, ray_points
from medax.geometry.surfaces import NurbsSurface
from medax.geometry.tensor_fit import CHECK_PER_SPAN, DEGREE, MAX_COEFFICIENTS, span_samples

#: Samples per boundary edge.
EDGE_SAMPLES = 48
#: The fit's range beyond the face, as a share of the smallest blend radius.
MARGIN = 0.25
#: A member's surface gives data this share of the smallest blend radius past its edges.
CONTINUE = 0.1
#: First spacing, as a share of the smallest blend radius; halvings at most.
FIRST_SPACING, LEVELS = 0.25, 4


@dataclass(frozen=True)
class _Member:
    kind: str  # "plane" | "cylinder" | "sphere" | "torus" (coaxial) | "nurbs"
    centre: Array
    axis: Array
    radius: float
    major: float
    nurbs: NurbsSurface | None
    uv_box: tuple[float, float, float, float]
    outer: Path
    inner: tuple[Path, ...]
    edges: tuple[Array, ...]  # (EDGE_SAMPLES, 2) (s, z) samples of each boundary edge


def _wire_sz(wire: Any, frame: CylinderFrame, periodic: bool) -> list[Array]:
    """(s, z) samples (EDGE_SAMPLES, 2) of each edge of ``wire`` in order (degenerated
    edges left out), ``s`` unwrapped along the whole wire when ``periodic``."""
    parts = []
    exp = BRepTools_WireExplorer(TopoDS.Wire(wire))
    while exp.More():
        e = exp.Current()
        if not BRep_Tool.Degenerated_s(e):
            p = edge_points(e, EDGE_SAMPLES)
            parts.append(p[::-1] if e.Orientation() == TopAbs_REVERSED else p)
        exp.Next()
    if not parts:
        return []
    allp = np.vstack(parts)
    s = frame.unwrapped(allp) if periodic else frame.coords(allp)[0]
    z = frame.coords(allp)[1]
    sz = np.column_stack([s, z])
    return [sz[k * EDGE_SAMPLES : (k + 1) * EDGE_SAMPLES] for k in range(len(parts))]


def _member(face: Any, frame: CylinderFrame, periodic: bool, tol: float) -> _Member | str:
    # (a torus off the frame's axis is taken as a NURBS piece)
    pc = piece_surface(face, lambda ad: _coaxial(ad, frame, tol))
    if isinstance(pc, str):
        return pc
    samples, outer, inner, edges = face_loops(face, lambda w: _wire_sz(w, frame, periodic))
    if not samples:
        return "a member without boundary edges"
    return _Member(
        pc.kind, pc.centre, pc.axis, pc.radius, pc.major, pc.nurbs, pc.uv_box, outer, inner, edges
    )


def _coaxial(ad: Any, frame: CylinderFrame, tol: float) -> bool:
    """Whether a torus (``BRepAdaptor_Surface``) has the frame's axis."""
    ax = ad.Torus().Axis()
    a, c = xyz(ax.Direction()), xyz(ax.Location()) - frame.origin
    off = c - (c @ frame.axis) * frame.axis
    return bool(np.linalg.norm(np.cross(a, frame.axis)) < 1e-9 and np.linalg.norm(off) <= tol)


def _is_periodic(members: Sequence[Any]) -> bool:
    """Whether the group goes all the way round the axis: a member has a seam."""
    for f in members:
        for e in edges_of(f):
            if not BRep_Tool.Degenerated_s(e) and BRep_Tool.IsClosed_s(e, f):
                return True
    return False


def _breaks(ms: Sequence[_Member], tol: float) -> tuple[list[float], list[float]]:
    """``s`` of the members' rulings and ``z`` of their circles (edges along iso-lines)."""
    ss: list[float] = []
    zs: list[float] = []
    for m in ms:
        for e in m.edges:
            if np.ptp(e, axis=0).max() < tol:
                continue
            if np.ptp(e[:, 0]) < tol:
                ss.append(float(e[:, 0].mean()))
            if np.ptp(e[:, 1]) < tol:
                zs.append(float(e[:, 1].mean()))
    return _dedup(ss, tol), _dedup(zs, tol)


def _dedup(vals: list[float], tol: float) -> list[float]:
    out: list[float] = []
    for v in sorted(vals):
        if not out or v - out[-1] > 100 * tol:
            out.append(v)
    return out


@dataclass(frozen=True)
class _Field:
    """The data of one merged face: its frame, members, ranges and knot lines."""

    frame: CylinderFrame
    ring: RingFrame  # the same cylinder as ring coordinates (rays for the NURBS members)
    members: tuple[_Member, ...]
    periodic: bool
    s_range: tuple[float, float]
    z_range: tuple[float, float]
    s_breaks: list[float]
    z_breaks: list[float]
    rmin: float
    outward: float  # +1 when the solid lies inside the cylinder (its outward normal radial)
    tree: cKDTree  # the members' boundary samples, densified to reach / 2 ((s, z))
    owner: Array  # the member of each sample
    reach: float  # how far past its boundary a member's surface gives data

    def labels(self, s: Array, z: Array) -> Array:
        """Index (n,) of the member whose (s, z) polygon holds each point, or -1."""
        pts = np.column_stack([s, z])
        label = np.full(len(pts), -1)
        shifts = (0.0, -PERIOD * self.frame.radius, PERIOD * self.frame.radius)
        for i, m in enumerate(self.members):
            for shift in shifts if self.periodic else (0.0,):
                cand = np.flatnonzero(label < 0)
                if cand.size == 0:
                    return label
                q = pts[cand] + np.array([shift, 0.0])
                inside = m.outer.contains_points(q, radius=0.0)
                for hole in m.inner:
                    inside &= ~hole.contains_points(q)
                label[cand[inside]] = i
        return label

    def continued(self, s: Array, z: Array, label: Array) -> Array:
        """``label`` with the points outside every member but within ``reach`` of a
        member's boundary given to that member (its surface continued: without data there
        the fit's spans across an edge of the face are held by one side only, and rows of
        samples that end at different places there bent the fit between them: 9e-3 on a
        fillet along a partial cylinder, growing as the spans shrank)."""
        out = np.flatnonzero(label < 0)
        if out.size == 0:
            return label
        dist, k = self.tree.query(np.column_stack([s[out], z[out]]))
        near = dist <= self.reach
        label = label.copy()
        label[out[near]] = self.owner[k[near]]
        return label

    def offsets(self, s: Array, z: Array, tol: float) -> tuple[Array, np.ndarray, np.ndarray]:
        """Radial offsets ``h``, where they are found (``ok``: the face and its members
        continued by ``reach``) and where the face is (``inside``) at the points
        ``(s, z)`` (any shape, raveled)."""
        s, z = s.ravel(), z.ravel()
        face = self.labels(s, z)
        label = self.continued(s, z, face)
        h = np.zeros(len(s))
        ok = np.zeros(len(s), bool)
        for i, m in enumerate(self.members):
            sel = np.flatnonzero(label == i)
            if sel.size == 0:
                continue
            if m.nurbs is None:
                h[sel], ok[sel] = radial_heights(
                    self.frame, m.kind, s[sel], z[sel], m.centre, m.axis, m.radius, m.major
                )
            else:
                theta = self.frame.theta0 + s[sel] / self.frame.radius
                x, found = ray_points(m.nurbs, self.ring, theta, z[sel], m.uv_box, tol)
                h[sel] = self.frame.coords(x)[2]
                ok[sel] = found
        return h, ok, face >= 0


def _field(support: Any, members: Sequence[Any], tol: float) -> _Field | str:
    ad = BRepAdaptor_Surface(support)
    if ad.GetType() != GeomAbs_Cylinder:
        return "the cylinder field takes cylindrical supports only"
    cyl = ad.Cylinder()
    pos = cyl.Position()
    frame = CylinderFrame.make(
        xyz(pos.Location()), xyz(pos.Direction()), xyz(pos.XDirection()), float(cyl.Radius())
    )
    periodic = _is_periodic(members)
    if not periodic:  # s = 0 at the middle of the gap the face leaves
        allp = np.vstack([edge_points(e, EDGE_SAMPLES) for f in members for e in edges_of(f)])
        start, width = largest_gap(frame.angle(allp))
        if width < 1e-3:
            return "the cylinder field's face has no gap round the axis and no seam"
        frame = replace(frame, theta0=start + 0.5 * width)
    ms: list[_Member] = []
    for f in members:
        m = _member(f, frame, periodic, tol)
        if isinstance(m, str):
            return m
        ms.append(m)
    curved = [m.radius for m in ms if m.kind != "plane"]
    curved = [r for r in curved if r > tol]
    if not curved:
        return "no curved piece to merge"
    rmin = min(min(curved), frame.radius)
    bnd = np.vstack([e for m in ms for e in m.edges])
    margin = MARGIN * rmin
    if periodic:
        s_range = (0.0, PERIOD * frame.radius)
    else:
        s_range = (float(bnd[:, 0].min()) - margin, float(bnd[:, 0].max()) + margin)
    z_range = (float(bnd[:, 1].min()) - margin, float(bnd[:, 1].max()) + margin)
    sb, zb = _breaks(ms, tol)
    zero = CubicSpline([0.0, np.pi, PERIOD], [0.0, 0.0, 0.0], bc_type="periodic")
    ring = RingFrame(
        "cylinder", frame.origin, frame.e1, frame.e2, frame.axis, zero, 1.0, frame.radius
    )
    p = face_inside_point(support)
    out = None if p is None else face_normal_at(support, p)
    outward = 0.0
    if p is not None and out is not None:
        w = p - frame.origin
        outward = float(np.sign(out @ (w - (w @ frame.axis) * frame.axis)))
    reach = CONTINUE * rmin
    samples, owner = _boundary_samples(ms, 0.5 * reach, PERIOD * frame.radius if periodic else 0.0)
    return _Field(
        frame,
        ring,
        tuple(ms),
        periodic,
        s_range,
        z_range,
        sb,
        zb,
        rmin,
        outward,
        cKDTree(samples),
        owner,
        reach,
    )


def _boundary_samples(ms: Sequence[_Member], step: float, period: float) -> tuple[Array, Array]:
    """The members' boundary polylines in ``(s, z)`` resampled at most ``step`` apart
    (shifted by ``+-period`` too when it is not 0), and the member of each sample."""
    pts, owner = [], []
    for i, m in enumerate(ms):
        for e in m.edges:
            seg = np.linalg.norm(np.diff(e, axis=0), axis=1)
            t = np.concatenate([[0.0], np.cumsum(seg)])
            n = max(2, int(np.ceil(t[-1] / max(step, 1e-300))) + 1)
            u = np.linspace(0.0, t[-1], n)
            q = np.column_stack([np.interp(u, t, e[:, 0]), np.interp(u, t, e[:, 1])])
            for shift in (0.0, -period, period) if period else (0.0,):
                pts.append(q + np.array([shift, 0.0]))
                owner.append(np.full(len(q), i))
    return np.vstack(pts), np.concatenate(owner)


def cylinder_surface(
    support: Any,
    members: Sequence[Any],
    fit_tol: float,
    geom_tol: float,
    probe: bool = False,
    accept: float | None = None,
) -> FittedSurface | str:
    """The fitted surface of the merged face made of ``members`` (faces of the split solid:
    a piece of the cylinder of ``support`` and blend halves) to ``fit_tol`` (length unit);
    the reason (str) when the pieces are no field over the cylinder or the fit misses.
    ``probe``: the first level only, refusing only missing data inside the face.
    ``accept``: the largest error taken when the fit cannot reach ``fit_tol``."""
    fld = _field(support, members, geom_tol)
    if isinstance(fld, str):
        return fld
    ray_tol = 1e-2 * fit_tol

    def points(ss: Array, zz: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        h, ok, inside = fld.offsets(ss, zz, ray_tol)
        pts = fld.frame.point(ss.ravel(), zz.ravel(), h)
        return pts.reshape((*ss.shape, 3)), ok.reshape(ss.shape), inside.reshape(ss.shape)

    def height(ss: Array, zz: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        h, ok, inside = fld.offsets(ss, zz, ray_tol)
        return h.reshape(ss.shape), ok.reshape(ss.shape), inside.reshape(ss.shape)

    spacing = FIRST_SPACING * fld.rmin
    levels = 1 if probe else LEVELS
    fit: PointFit | PeriodicFit | None
    if fld.periodic:
        fit = _periodic(fld, points, height, fit_tol, spacing, levels)
    else:
        fitter = PointFitter(
            fld.s_range,
            fld.z_range,
            fld.s_breaks,
            fld.z_breaks,
            points,
            height,
            spacing,
            fld.frame,
            _rims(fld),
        )
        fit = fitter.fit(fit_tol, levels)
    if fit is None:
        return f"the cylinder field would need more than {MAX_COEFFICIENTS} coefficients"
    if not np.isfinite(fit.error):
        return "the merged face is no field over its cylinder (radial lines miss a piece)"
    limit = fit_tol if accept is None else max(accept, fit_tol)
    if fit.error > limit and not probe:
        return (
            f"cylinder field fit error {fit.error:.2e} above {limit:.2e} (curvature jumps "
            "off the rulings and circles)"
        )
    if isinstance(fit, PointFit):
        surface = _clamped_surface(fit)
        volume, spacing_used = fit.volume, fit.spacing
    else:
        surface = periodic_surface(fit)
        volume = _periodic_volume(fit, points, fld)
        spacing_used = float(np.diff(np.unique(fit.ts)).min())
    dv = fld.outward * volume if fld.outward else float("nan")
    return FittedSurface(surface, fit.error, spacing_used, dv)


def _periodic(
    fld: _Field, points: Any, height: Any, tol: float, spacing: float, levels: int
) -> PeriodicFit | None:
    """The periodic fit in ``(theta, z)`` (``theta`` from ``theta0``): z knot lines at the
    circles, one span in z where the offset is linear (see :class:`PointFitter`)."""
    from medax.geometry.tensor_fit import UNIFORM_PROBES, curved_intervals, probe_lines

    r = fld.frame.radius
    z0, z1 = fld.z_range
    zb = sorted(b for b in fld.z_breaks if z0 < b < z1)
    period = PERIOD * r
    lines = probe_lines(
        np.linspace(0.0, period, UNIFORM_PROBES), np.mod(_rims(fld), period), spacing
    )
    zb, fine = curved_intervals(z0, z1, zb, height, lines, 1, spacing)

    def by_angle(th: Array, zz: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        return points(np.asarray(th) * r, zz)

    def on_cylinder(th: Array, zz: Array) -> Array:  # where the fit has no data
        s = np.asarray(th) * r
        return fld.frame.point(s.ravel(), np.asarray(zz).ravel()).reshape((*s.shape, 3))

    return fit_radial_height(
        (z0, z1), zb, by_angle, tol, spacing, r, levels=levels, s_fine=fine, outside=on_cylinder
    )


def _rims(fld: _Field) -> Array:
    """``s`` of the curved members' boundary samples: lines there cross every curved piece
    (41 uniform ones can all miss a thin strip)."""

    def support(m: _Member) -> bool:  # the supporting cylinder's own piece: no offset
        return m.kind == "cylinder" and abs(m.radius - fld.frame.radius) <= 1e-9 * m.radius

    rims = [e[:, 0] for m in fld.members if m.kind != "plane" and not support(m) for e in m.edges]
    return np.concatenate(rims) if rims else np.zeros(0)


def _periodic_volume(fit: PeriodicFit, points: Any, fld: _Field) -> float:
    """:func:`signed_volume` of a periodic fit on its check grid (``u = theta``)."""
    tt = np.unique(periodic_knots(fit.n_theta)[DEGREE : fit.n_theta + DEGREE + 1])
    th, zz = span_samples(tt, CHECK_PER_SPAN), span_samples(fit.ts, CHECK_PER_SPAN)
    r = fld.frame.radius
    pts, ok, inside = points(*np.meshgrid(th * r, zz, indexing="ij"))
    wt = np.repeat(np.diff(tt) / CHECK_PER_SPAN, CHECK_PER_SPAN)
    wz = np.repeat(np.diff(np.unique(fit.ts)) / CHECK_PER_SPAN, CHECK_PER_SPAN)
    return signed_volume(fit, th, zz, pts, inside & ok, (wt, wz), fld.frame.origin, fld.frame.axis)


def _clamped_surface(fit: PointFit) -> Any:
    """``Geom_BSplineSurface`` of a clamped point fit: ``u = s``, ``v = z``."""
    return bspline_surface(fit.coef, fit.ts, fit.tz, DEGREE, DEGREE)
