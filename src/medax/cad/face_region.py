"""A 4-sided CAD face as a :class:`~medax.geometry.Region` on its surface, and a fillet's axis.

A face is 4-sided when its one (outer) wire has four corners once chains of G1 edges are
joined (:func:`face_sides`). The region's sides are the face's pcurves in ``(u, v)``
chained per side, its embedding is the face's surface as a numpy
:mod:`medax.geometry.surfaces` object, and its ``space_sides`` are the exact 3-D edge curves
(as rational B-splines), so the tracer and the mesher measure distances in space to the true
edges (:func:`face_region`, :func:`side_region`). A fillet's sides come from its
classification instead (smooth side 0, cross edge, smooth side 1, cross edge:
:func:`fillet_region`); its axis is traced by :func:`medax.axis.trace_axis` with
constraints (0, 2): no second copy of the tracer.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.Geom import Geom_TrimmedCurve
from OCP.Geom2d import Geom2d_TrimmedCurve
from OCP.Geom2dConvert import Geom2dConvert, Geom2dConvert_CompCurveToBSplineCurve
from OCP.GeomAbs import (
    GeomAbs_BezierCurve,
    GeomAbs_BezierSurface,
    GeomAbs_BSplineCurve,
    GeomAbs_BSplineSurface,
    GeomAbs_Circle,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_Ellipse,
    GeomAbs_Hyperbola,
    GeomAbs_Line,
    GeomAbs_Parabola,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_SurfaceOfExtrusion,
    GeomAbs_SurfaceOfRevolution,
    GeomAbs_Torus,
)
from OCP.GeomAdaptor import GeomAdaptor_Surface
from OCP.GeomConvert import GeomConvert, GeomConvert_CompCurveToBSplineCurve
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_EDGE, TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from medax import tolerances
from medax.axis import MedialAxis, trace_axis
from medax.cad.model import Classification, FilletRecord
from medax.errors import CadError
from medax.geometry._types import FloatArray
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve
from medax.geometry.embedding import Embedding
from medax.geometry.line import Line
from medax.geometry.region import Region
from medax.geometry.surfaces import (
    ConeSurface,
    CylinderSurface,
    ExtrusionSurface,
    Frame,
    NurbsSurface,
    PlaneSurface,
    Profile,
    RevolutionSurface,
    SphereSurface,
    TorusSurface,
)


# ---- surfaces -----------------------------------------------------------------------------
def _frame(ax3: Any) -> Frame:
    o, x, y, z = ax3.Location(), ax3.XDirection(), ax3.YDirection(), ax3.Direction()
    return Frame.make(
        (o.X(), o.Y(), o.Z()), (x.X(), x.Y(), x.Z()), (y.X(), y.Y(), y.Z()), (z.X(), z.Y(), z.Z())
    )


def exact_embedding(face: Any) -> Embedding:
    """The numpy embedding ``S(u, v)`` of ``face``'s surface in OCCT's own parameters, so
    that the face's pcurves apply to it as they are: analytic surfaces exactly, B-spline and
    Bezier surfaces by their poles, surfaces of revolution and of linear extrusion by their
    axis or direction and their generatrix (:class:`~medax.geometry.surfaces.Profile`: a
    line, conic or B-spline curve). :class:`CadError` (why) for other kinds (offset
    surfaces, sweeps of offset curves), whose B-spline copy has parameters of its own."""
    s = BRepAdaptor_Surface(face, False)
    kind = s.GetType()
    if kind == GeomAbs_Plane:
        return PlaneSurface(_frame(s.Plane().Position()))
    if kind == GeomAbs_Cylinder:
        c = s.Cylinder()
        return CylinderSurface(_frame(c.Position()), c.Radius())
    if kind == GeomAbs_Cone:
        k = s.Cone()
        return ConeSurface(_frame(k.Position()), k.RefRadius(), k.SemiAngle())
    if kind == GeomAbs_Sphere:
        sp = s.Sphere()
        return SphereSurface(_frame(sp.Position()), sp.Radius())
    if kind == GeomAbs_Torus:
        t = s.Torus()
        return TorusSurface(_frame(t.Position()), t.MajorRadius(), t.MinorRadius())
    if kind == GeomAbs_BSplineSurface:
        return bspline_embedding(s.BSpline())
    if kind == GeomAbs_BezierSurface:  # (its B-spline copy keeps the parameters [0, 1])
        return bspline_embedding(GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(face)))
    if kind in (GeomAbs_SurfaceOfRevolution, GeomAbs_SurfaceOfExtrusion):
        # (the surface with the face's location applied, as the analytic kinds above have it)
        g = GeomAdaptor_Surface(BRep_Tool.Surface_s(face))
        profile = _profile(g.BasisCurve())
        if kind == GeomAbs_SurfaceOfRevolution:
            ax = g.AxeOfRevolution()
            return RevolutionSurface(_xyz(ax.Location()), _xyz(ax.Direction()), profile)
        return ExtrusionSurface(profile, _xyz(g.Direction()))
    name = kind.name.removeprefix("GeomAbs_").lower()
    raise CadError(f"a {name} surface has no numpy copy in OCCT's parameters")


def _xyz(p: Any) -> FloatArray:
    return np.array([p.X(), p.Y(), p.Z()])


def _profile(c: Any) -> Profile:
    """The generatrix ``c`` (an ``Adaptor3d_Curve``) of a swept surface as a numpy
    :class:`Profile` in OCCT's parameter; :class:`CadError` for other curve kinds."""
    kind = c.GetType()
    if kind == GeomAbs_Line:
        lin = c.Line()
        d = _xyz(lin.Direction())
        other = np.eye(3)[int(np.argmin(np.abs(d)))]
        return Profile("line", Frame.make(_xyz(lin.Location()), d, other - d * float(d @ other)))
    conics = {GeomAbs_Circle: "Circle", GeomAbs_Ellipse: "Ellipse", GeomAbs_Hyperbola: "Hyperbola"}
    if kind in conics:
        g = getattr(c, conics[kind])()
        a, b = (g.Radius(),) * 2 if kind == GeomAbs_Circle else (g.MajorRadius(), g.MinorRadius())
        name = "hyperbola" if kind == GeomAbs_Hyperbola else "ellipse"
        return Profile(name, _frame(g.Position()), a, b)
    if kind == GeomAbs_Parabola:
        g = c.Parabola()
        return Profile("parabola", _frame(g.Position()), g.Focal())
    if kind in (GeomAbs_BSplineCurve, GeomAbs_BezierCurve):
        bs = c.BSpline() if kind == GeomAbs_BSplineCurve else c.Bezier()
        bs = GeomConvert.CurveToBSplineCurve_s(bs)  # (a copy; a Bezier keeps [0, 1])
        periodic = bool(bs.IsPeriodic())
        if periodic:  # (one period, the same parameters)
            bs.SetNotPeriodic()
        knots = _values(bs.KnotSequence())
        deg = bs.Degree()
        return Profile("nurbs", _frame_any(), spline=_to_bspline(bs, 3), t0=knots[deg],
                       t1=knots[-deg - 1], periodic=periodic)  # fmt: skip
    name = kind.name.removeprefix("GeomAbs_").lower()
    raise CadError(f"a sweep of a {name}: no numpy copy in OCCT's parameters")


def _frame_any() -> Frame:
    return Frame.make((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))


def surface_embedding(face: Any) -> Embedding:
    """The numpy embedding ``S(u, v)`` of ``face``'s surface: :func:`exact_embedding`
    (OCCT's parameters) where there is one, else (offset surfaces, sweeps of offset curves)
    the same geometry through ``GeomConvert.SurfaceToBSplineSurface_s``, in the B-spline
    copy's parameters."""
    try:
        return exact_embedding(face)
    except CadError:
        pass
    kind = BRepAdaptor_Surface(face, False).GetType()
    try:
        bs = GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(face))
    except Exception as err:
        raise CadError(f"cannot convert a {kind.name} surface to a B-spline ({err})") from err
    return bspline_embedding(bs)


#: Numpy copies of the B-spline surfaces read last (:func:`bspline_embedding`), by the
#: Python object of the OCCT surface (OCP hands out one object per surface while it lives;
#: the entry keeps it alive, so its ``id`` is not reused) and a stamp of its poles.
_EMBEDDINGS: OrderedDict[int, tuple[Any, tuple[Any, ...], NurbsSurface]] = OrderedDict()
#: Surfaces kept (a fitted face of 10^5 poles: 5 MB).
EMBEDDING_CACHE = 32


def bspline_embedding(bs: Any) -> NurbsSurface:
    """The numpy copy of a ``Geom_BSplineSurface`` (a periodic one made non-periodic). The
    copies of the surfaces read last are kept: reading the poles one OCCT call each took
    10 s of a 555-face part's simplification, where the same fitted surfaces are read by
    the projection, the area and the gap measure in turn."""
    stamp = _stamp(bs)
    hit = _EMBEDDINGS.get(id(bs))
    if hit is not None and hit[0] is bs and hit[1] == stamp:
        _EMBEDDINGS.move_to_end(id(bs))
        return hit[2]
    emb = _bspline_copy(bs)
    _EMBEDDINGS[id(bs)] = (bs, stamp, emb)
    while len(_EMBEDDINGS) > EMBEDDING_CACHE:
        _EMBEDDINGS.popitem(last=False)
    return emb


def _stamp(bs: Any) -> tuple[Any, ...]:
    """What tells a changed surface from the one copied: its sizes, degrees, periodicity,
    first, middle and last poles and knots."""
    nu, nv = bs.NbUPoles(), bs.NbVPoles()
    poles = tuple(bs.Pole(a, b).Coord() for a, b in ((1, 1), (nu // 2 + 1, nv // 2 + 1), (nu, nv)))
    knots = (bs.UKnot(1), bs.UKnot(bs.NbUKnots()), bs.VKnot(1), bs.VKnot(bs.NbVKnots()))
    flags = (bs.UDegree(), bs.VDegree(), bs.IsUPeriodic(), bs.IsVPeriodic(), bs.IsURational())
    return (nu, nv, *flags, bs.IsVRational(), *poles, *knots)


def _bspline_copy(bs: Any) -> NurbsSurface:
    """The numpy copy of a ``Geom_BSplineSurface``, read pole by pole."""
    if bs.IsUPeriodic() or bs.IsVPeriodic():
        bs = bs.Copy()
        if bs.IsUPeriodic():
            bs.SetUNotPeriodic()
        if bs.IsVPeriodic():
            bs.SetVNotPeriodic()
    nu, nv = bs.NbUPoles(), bs.NbVPoles()
    rows, cols = range(1, nu + 1), range(1, nv + 1)
    # (one OCCT call per pole and none for unit weights: fitted faces have 10^3 poles)
    poles = np.array([[bs.Pole(a, b).Coord() for b in cols] for a in rows], dtype=float)
    poles = poles.reshape(nu, nv, 3)
    uk = _values(bs.UKnotSequence())
    vk = _values(bs.VKnotSequence())
    weights = None
    if bs.IsURational() or bs.IsVRational():
        weights = np.array([[bs.Weight(a, b) for b in cols] for a in rows], dtype=float)
    return NurbsSurface(poles, bs.UDegree(), bs.VDegree(), uk, vk, weights)


# ---- curves -------------------------------------------------------------------------------
def curve_copy(bs: Any) -> BSpline:
    """The numpy copy of a 3-D ``Geom_BSplineCurve`` (its knot range mapped onto [0, 1])."""
    return _to_bspline(bs, 3)


def _values(arr: Any) -> FloatArray:
    """The values of an OCCT ``TColStd_Array1OfReal`` (n,), read by index: iterating the
    OCP array (``list(arr)``) costs ~0.25 ms per array, 30x the indexed reads."""
    return np.array([arr.Value(i) for i in range(arr.Lower(), arr.Upper() + 1)], dtype=float)


def _to_bspline(bs: Any, dim: int) -> BSpline:
    if bs.IsPeriodic():
        bs = bs.Copy()
        bs.SetNotPeriodic()
    n = bs.NbPoles()
    poles = [bs.Pole(i) for i in range(1, n + 1)]  # (one OCCT call per pole)
    if dim == 2:
        ctrl = np.array([[p.X(), p.Y()] for p in poles])
    else:
        ctrl = np.array([[p.X(), p.Y(), p.Z()] for p in poles])
    knots = _values(bs.KnotSequence())
    weights = np.array([bs.Weight(i) for i in range(1, n + 1)]) if bs.IsRational() else None
    return BSpline(ctrl, bs.Degree(), knots, weights)


def _pcurve(edge: Any, face: Any) -> Any:
    """The edge's pcurve on ``face`` as a Geom2d B-spline, in the wire's travel direction."""
    c = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    ad = BRepAdaptor_Curve2d(edge, face)
    a, b = ad.FirstParameter(), ad.LastParameter()
    if c is None:
        raise CadError("edge has no pcurve on its face")
    bs = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(c, a, b))
    if edge.Orientation() == TopAbs_REVERSED:
        bs.Reverse()
    return bs


def _curve3d(edge: Any) -> Any:
    """The edge's 3-D curve as a Geom B-spline, in the wire's travel direction."""
    c = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    ad = BRepAdaptor_Curve(edge)
    a, b = ad.FirstParameter(), ad.LastParameter()
    if c is None:
        raise CadError("edge has no 3-D curve")
    bs = GeomConvert.CurveToBSplineCurve_s(Geom_TrimmedCurve(c, a, b))
    if edge.Orientation() == TopAbs_REVERSED:
        bs.Reverse()
    return bs


def _chain(pieces: list[Any], two_d: bool) -> Any:
    if len(pieces) == 1:
        return pieces[0]
    comp = (
        Geom2dConvert_CompCurveToBSplineCurve(pieces[0])
        if two_d
        else GeomConvert_CompCurveToBSplineCurve(pieces[0])
    )
    for p in pieces[1:]:
        if not comp.Add(p, 1e-7):
            raise CadError("a side's edges do not chain")
    return comp.BSplineCurve()


# ---- the region ---------------------------------------------------------------------------
#: Consecutive edges of a wire whose tangents differ by less than this (radians) join into one
#: side (G1); a larger turn is a corner.
CORNER_ANGLE = 1e-2


def _end_tangents(edge: Any) -> tuple[FloatArray, FloatArray]:
    """Unit tangents (3,) of ``edge`` at its start and end, in the wire's travel direction."""
    c = BRepAdaptor_Curve(edge)
    p, v = gp_Pnt(), gp_Vec()
    out = []
    for t in (c.FirstParameter(), c.LastParameter()):
        c.D1(t, p, v)
        out.append(np.array([v.X(), v.Y(), v.Z()]))
    a, b = out
    if edge.Orientation() == TopAbs_REVERSED:
        a, b = -b, -a
    return a / np.linalg.norm(a), b / np.linalg.norm(b)


def not_four_sided(face: Any, angle_tol: float = CORNER_ANGLE) -> str | None:
    """Why ``face`` is not a 4-sided region (inner wires, a seam, a pole, other than four
    corners), or None when it is: see :func:`face_sides`."""
    try:
        sides = face_sides(face, angle_tol)
    except CadError as err:
        return str(err)
    return None if len(sides) == 4 else f"{len(sides)} sides"


def face_sides(face: Any, angle_tol: float = CORNER_ANGLE, seams: bool = False) -> list[list[Any]]:
    """The outer wire's oriented edges, in wire order, grouped into sides: consecutive
    edges whose tangents turn by less than ``angle_tol`` (radians, in space) form one side.
    Raises :class:`CadError` for a face with inner wires, a degenerate edge or, unless
    ``seams``, a seam edge (no corner structure), or a wire with no corner. With ``seams`` a
    run of seam edges is a side of its own each time the wire runs along it (a cylinder's
    lateral face cut by one seam: circle, seam, circle, seam; a merged face's seam may be
    several edges in a G1 chain)."""
    wires = TopExp_Explorer(face, TopAbs_WIRE)
    n_wires = 0
    while wires.More():
        n_wires += 1
        wires.Next()
    if n_wires != 1:
        raise CadError(f"{n_wires - 1} inner wires")
    edges: list[Any] = []
    exp = BRepTools_WireExplorer(BRepTools.OuterWire_s(face), face)
    while exp.More():
        e = exp.Current()
        exp.Next()
        if BRep_Tool.Degenerated_s(e):
            raise CadError("a degenerate edge (pole)")
        if not seams and BRep_Tool.IsClosed_s(e, face):
            raise CadError("a seam edge (closed surface)")
        edges.append(e)
    tangents = [_end_tangents(e) for e in edges]
    cos = np.cos(angle_tol)
    on_seam = [seams and _is_seam(e, face) for e in edges]
    corner = [
        float(tangents[k - 1][1] @ tangents[k][0]) < cos or on_seam[k] != on_seam[k - 1]
        for k in range(len(edges))
    ]
    if not any(corner):
        raise CadError("no corner in the outer wire")
    k0 = corner.index(True)
    sides: list[list[Any]] = []
    for k in range(k0, k0 + len(edges)):
        if corner[k % len(edges)]:
            sides.append([])
        sides[-1].append(edges[k % len(edges)])
    return sides


def has_seam(face: Any) -> bool:
    """Whether ``face`` has a seam edge (one edge twice in its wire: a closed surface)."""
    exp = TopExp_Explorer(face, TopAbs_EDGE)
    while exp.More():
        if _is_seam(TopoDS.Edge(exp.Current()), face):
            return True
        exp.Next()
    return False


def _is_seam(edge: Any, face: Any) -> bool:
    return bool(BRep_Tool.IsClosed_s(edge, face))


@dataclass(frozen=True)
class Development:
    """A face's surface over its parameters scaled to lengths: plane point ``p`` (n, 2) is
    the surface point at ``(u, v) = p / scale``; ``scale`` (2,) the lengths of the surface's
    parameter derivatives ``|S_u|, |S_v|`` at the middle of the face's parameter box (model
    units per parameter unit). Exact in length along both parameters on a cylinder, and
    along iso-lines of constant speed (a circle of a surface of revolution) on others."""

    surface: Embedding
    scale: FloatArray
    dim = 3
    is_identity = False

    def evaluate(self, p: FloatArray) -> FloatArray:
        """Surface points (n, 3) of plane points ``p`` (n, 2) (as an embedding)."""
        return self.points(p)

    def jacobian(self, p: FloatArray) -> FloatArray:
        """``d points / d p`` (n, 3, 2)."""
        return np.asarray(self.surface.jacobian(self.uv(p))) / self.scale

    def uv(self, p: FloatArray) -> FloatArray:
        """Surface parameters (n, 2) of plane points ``p`` (n, 2)."""
        return np.asarray(p, dtype=np.float64) / self.scale

    def points(self, p: FloatArray) -> FloatArray:
        """Surface points (n, 3) of plane points ``p`` (n, 2)."""
        return self.surface.evaluate(self.uv(p))


def seam_region(
    face: Any, sides: list[list[Any]], name: str
) -> tuple[Region, list[list[Any]], Development]:
    """A 4-sided ``face`` with a seam (its sides from :func:`face_sides` with ``seams``) as
    a planar Region of its pcurves scaled to lengths (:class:`Development`): the seam's two
    sides are its two pcurves, so the distance from the seam, which is the same on both
    sides in space, is measured across the face instead. Also the oriented edges of each
    region side in the side's direction, and the development that maps the region's
    points onto the surface."""
    try:
        sides2d = [_to_bspline(_chain([_pcurve(e, face) for e in s], True), 2) for s in sides]
        emb = exact_embedding(face)  # (the pcurves are in OCCT's parameters)
    except CadError as err:
        raise CadError(f"{name}: {err}") from err
    except Exception as err:
        raise CadError(f"{name}: OCCT ({err})") from err
    box = np.concatenate([c.control_points for c in sides2d])
    mid = 0.5 * (box.min(axis=0) + box.max(axis=0))
    scale = np.linalg.norm(emb.jacobian(mid[None])[0], axis=0)
    if not np.all(scale > 0.0):
        raise CadError(f"{name}: the surface is singular at the middle of the face")
    flat = [_scaled(c, scale) for c in sides2d]
    region = Region.build(flat, name=name)
    if region.reoriented:  # sides (0, 3, 2, 1), each reversed
        sides = [[TopoDS.Edge(e.Reversed()) for e in reversed(sides[k])] for k in (0, 3, 2, 1)]
    return region, sides, Development(emb, scale)


def _scaled(c: BSpline, scale: FloatArray) -> Curve:
    """Plane curve ``c`` with its coordinates multiplied by ``scale`` (2,): a :class:`Line`
    where it is straight (degree 1, collinear control points: the pcurve of a circle or a
    seam on a cylinder), which the mesher solves in closed form, else a B-spline."""
    ctrl = c.control_points * scale
    if c.degree == 1:
        a, b = ctrl[0], ctrl[-1]
        d = b - a
        off = np.abs(d[0] * (ctrl[:, 1] - a[1]) - d[1] * (ctrl[:, 0] - a[0]))
        ahead = np.diff((ctrl - a) @ d)  # (no folding back along the line)
        if np.all(off <= 1e-12 * float(d @ d)) and np.all(ahead > 0.0):
            return Line(a, b)
    return BSpline(ctrl, c.degree, c.knots, c.weights)


#: Corners of pcurve sides are closed only where their ends are this close in the
#: parameter plane, relative to the sides' extent (a seam's period apart is no gap).
CORNER_SNAP_UV = 1e-3


def _vertex_tolerance(face: Any) -> float:
    """The largest tolerance (length unit) of ``face``'s vertices."""
    from OCP.TopAbs import TopAbs_VERTEX

    tol, exp = 0.0, TopExp_Explorer(face, TopAbs_VERTEX)
    while exp.More():
        tol = max(tol, BRep_Tool.Tolerance_s(TopoDS.Vertex(exp.Current())))
        exp.Next()
    return tol


def closed_corners(sides: list[BSpline], surface: Any, tol: float) -> list[BSpline]:
    """Pcurve sides (clamped B-splines in the face's parameters, in order round the face)
    whose consecutive ends lie apart, but within ``tol`` (length unit: the face's vertex
    tolerance) in space on ``surface`` (``evaluate((n, 2)) -> (n, 3)``), made to meet at
    the mean of the two ends. A loose input's pcurves may miss each other by up to its own
    tolerance (seen: 2e-7 - 1.2e-5 mm on imported parts), which the region's corner check
    would refuse; the move is the gap's half at most, within the input's tolerance."""
    out = list(sides)
    ends = np.vstack([c.control_points[[0, -1]] for c in out])
    extent = float(np.ptp(ends, axis=0).max())
    for k in range(len(out)):
        a, b = out[k], out[(k + 1) % len(out)]
        pa, pb = a.control_points[-1], b.control_points[0]
        if np.array_equal(pa, pb) or np.linalg.norm(pa - pb) > CORNER_SNAP_UV * extent:
            continue
        gap = float(np.linalg.norm(np.diff(surface.evaluate(np.vstack([pa, pb])), axis=0)))
        if gap > tol:
            continue
        mid = 0.5 * (pa + pb)
        out[k] = _with_end(a, -1, mid)
        out[(k + 1) % len(out)] = _with_end(out[(k + 1) % len(out)], 0, mid)
    return out


def _with_end(c: BSpline, i: int, point: FloatArray) -> BSpline:
    """``c`` with its first (``i`` 0) or last (-1) control point, its end, at ``point``."""
    ctrl = c.control_points.copy()
    ctrl[i] = point
    return BSpline(ctrl, c.degree, c.knots, c.weights)


def side_region(face: Any, sides: list[list[Any]], name: str) -> tuple[Region, list[list[Any]]]:
    """The Region of ``face`` with the given four sides (oriented edges in wire order):
    pcurve sides, the face's surface as embedding, the exact 3-D edge curves as space
    sides; and the oriented edges of each region side in the side's direction (the region
    may be reoriented counter-clockwise, see :meth:`Region.build`)."""
    try:
        sides2d = [_to_bspline(_chain([_pcurve(e, face) for e in s], True), 2) for s in sides]
        sides3d = [_to_bspline(_chain([_curve3d(e) for e in s], False), 3) for s in sides]
        emb = exact_embedding(face)  # (the pcurves are in OCCT's parameters)
        sides2d = closed_corners(sides2d, emb, _vertex_tolerance(face))
    except CadError as err:
        raise CadError(f"{name}: {err}") from err
    except Exception as err:
        raise CadError(f"{name}: OCCT ({err})") from err
    region = Region.build(sides2d, name=name, embedding=emb, space_sides=sides3d)
    if region.reoriented:  # sides (0, 3, 2, 1), each reversed
        sides = [[TopoDS.Edge(e.Reversed()) for e in reversed(sides[k])] for k in (0, 3, 2, 1)]
    return region, sides


def face_region(face: Any, name: str = "face", angle_tol: float = CORNER_ANGLE) -> Region:
    """A 4-sided CAD ``face`` (see :func:`face_sides`) as a Region on its surface: pcurve
    sides, exact 3-D space sides; :class:`CadError` when the face is not 4-sided."""
    try:
        sides = face_sides(face, angle_tol)
    except CadError as err:
        raise CadError(f"{name} is not 4-sided: {err}") from err
    if len(sides) != 4:
        raise CadError(f"{name} is not 4-sided: {len(sides)} sides")
    return side_region(face, sides, name)[0]


def fillet_sides(c: Classification, rec: FilletRecord) -> list[list[Any]]:
    """The oriented edges of each of the 4 sides of fillet ``rec``, in outer-wire order
    (smooth side 0, a cross edge, smooth side 1, the other cross edge)."""
    smooth = [[c.edge_map.FindKey(j + 1) for j in side] for side in rec.smooth_edges]
    return smooth_cross_sides(c.face(rec.face), smooth[0], smooth[1], f"face {rec.face}")


def smooth_cross_sides(
    face: Any, smooth0: Sequence[Any], smooth1: Sequence[Any], where: str
) -> list[list[Any]]:
    """The oriented edges of each of the 4 sides of the fillet ``face`` whose smooth sides
    are the edges ``smooth0`` and ``smooth1``, in outer-wire order (smooth side 0, a cross
    edge, smooth side 1, the other cross edge); :class:`CadError` naming ``where`` when the
    outer wire is not so."""
    wire = BRepTools.OuterWire_s(face)
    occ: list[tuple[str, Any]] = []
    exp = BRepTools_WireExplorer(wire, face)
    while exp.More():
        e = exp.Current()
        exp.Next()
        if BRep_Tool.Degenerated_s(e):
            continue
        label = (
            "S0"
            if any(e.IsSame(x) for x in smooth0)
            else "S1"
            if any(e.IsSame(x) for x in smooth1)
            else "C"
        )
        occ.append((label, e))
    k = next((i for i in range(len(occ)) if occ[i][0] == "S0" and occ[i - 1][0] != "S0"), None)
    if k is None:
        raise CadError(f"{where}: smooth side 0 not found in its outer wire")
    occ = occ[k:] + occ[:k]
    sides: list[list[Any]] = []
    for label, e in occ:
        if sides and sides[-1][0] == label:
            sides[-1][1].append(e)
        else:
            sides.append((label, [e]))  # type: ignore[arg-type]
    if [s[0] for s in sides] != ["S0", "C", "S1", "C"]:
        raise CadError(f"{where}: outer wire is not smooth/cross/smooth/cross")
    return [s[1] for s in sides]


def fillet_region(c: Classification, rec: FilletRecord) -> Region:
    """Fillet ``rec`` as a Region on its surface: pcurve sides, exact 3-D space sides (its
    sides by the classification's smooth edges, not by corners: see :func:`side_region`)."""
    where = f"{c.source or 'shape'}: fillet face {rec.face}"
    try:
        sides = fillet_sides(c, rec)
    except CadError as err:
        raise CadError(f"{where}: {err}") from err
    region = side_region(c.face(rec.face), sides, where)[0]
    return replace(region, name=f"face {rec.face}")


def fillet_axis(
    c: Classification, rec: FilletRecord, tol: float = tolerances.CURVE_TOL
) -> MedialAxis:
    """The medial axis of fillet ``rec`` between its two smooth edges (``tol`` relative
    to the region's diagonal), from cross edge 1 to cross edge 0 in the region's order."""
    return trace_axis(fillet_region(c, rec), pair=(0, 2), tol=tol)
