"""Build the new faces on shared edges and assemble the simplified solid.

A group's boundary is made of the split solid's own edges, shared by the two faces they
separate. Runs of edges are not joined into one B-spline edge: a line - arc run joined is
only C1, and OCCT's default mass properties (FreeCAD's, CadQuery's), which integrate each
edge with a fixed number of Gauss points and no split at knots, lose 1e-4 of the volume
on such an edge; unjoined, each piece is smooth. Faces are built on
their (new or original) surface with pcurves projected explicitly, then healed
(``ShapeFix_Shape``) and made same-parameter.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepLib import BRepLib
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.GeomProjLib import GeomProjLib
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.ShapeFix import ShapeFix_Shape
from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shell, TopoDS_Solid, TopoDS_Wire

from medax.cad.simplify.geom_key import Key, curve2d_key, curve_key, location_key, surface_key
from medax.cad.simplify.groups import Group, GroupError
from medax.cad.simplify.local_measure import Measures
from medax.cad.simplify.occ import (
    edge_curve,
    edge_ends,
    edge_points,
    edges_of,
    face_inside_point,
    face_normal_at,
    faces_of,
    xyz,
)
from medax.cad.simplify.projection import GridProjection
from medax.cad.simplify.split import SplitResult
from medax.errors import CadError

log = logging.getLogger(__name__)


def _surface_normal(surf: Any, p: np.ndarray) -> np.ndarray | None:
    """Unit normal of ``surf`` at the foot of ``p`` (3,); None where it is undefined."""
    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), surf)
    if proj.NbPoints() == 0:
        return None
    u, v = proj.LowerDistanceParameters()
    n = np.cross(xyz(surf.DN(u, v, 1, 0)), xyz(surf.DN(u, v, 0, 1)))
    size = float(np.linalg.norm(n))
    return n / size if size > 1e-12 else None


def _pcurve_error(pc: Any, c: Any, surf: Any, f: float, l: float, n: int = 0) -> float:
    """Largest distance between the 3-D curve ``c`` and ``surf`` along the pcurve ``pc`` at
    ``n`` samples of ``[f, l]``: by default 41, or 4 per knot span of ``c`` when it has
    more spans (at most 2001: a merged face's traced medial curve has hundreds of spans,
    and one bad projected sample had left a 0.35 mm bump between 41 samples)."""
    if n <= 0:
        spans = c.NbKnots() - 1 if hasattr(c, "NbKnots") else 1
        n = int(np.clip(4 * spans + 1, 41, 2001))
    err = 0.0
    for t in np.linspace(f, l, n):
        uv = pc.Value(float(t))
        err = max(err, surf.Value(uv.X(), uv.Y()).Distance(c.Value(float(t))))
    return err


def _fitted_pcurve(
    c: Any, surf: Any, f: float, l: float, tol: float, grid: GridProjection | None = None
) -> Any | None:
    """pcurve by projecting samples and fitting a 2-D B-spline on the edge's own parameter,
    span by span of the 3-D curve's knots (joined curves are only G1 at their joints); the
    spans are concatenated with a C0 knot at each break so the parameter is kept. ``grid``:
    the surface's grid projection when it has one (B-spline surfaces; much faster)."""
    from OCP.collections import Array1_double, Array1_gp_Pnt2d
    from OCP.Geom2dAPI import Geom2dAPI_PointsToBSpline
    from OCP.GeomAbs import GeomAbs_C2
    from OCP.gp import gp_Pnt2d

    breaks = [f, l]
    if hasattr(c, "NbKnots"):
        knots = [c.Knot(i) for i in range(1, c.NbKnots() + 1)]
        gap = 1e-6 * (l - f)
        breaks = [f]
        for k in sorted(knots):
            if breaks[-1] + gap < k < l - gap:
                breaks.append(k)
        breaks.append(l)
    proj = GeomAPI_ProjectPointOnSurf()
    bounds = [min(max(float(x), -1e7), 1e7) for x in surf.Bounds()]
    fits = []
    prev_u = None
    prev_uv: tuple[float, float] | None = None
    for a, b in zip(breaks[:-1], breaks[1:], strict=True):
        ts = np.linspace(a, b, 25)
        pts, pars = Array1_gp_Pnt2d(1, ts.size), Array1_double(1, ts.size)
        if grid is not None:  # the grid's feet of the span's samples, in one call
            xyzs = np.array([xyz(c.Value(float(t))) for t in ts])
            feet, gaps = grid.project_many(xyzs)
        for i, t in enumerate(ts):
            if grid is not None:
                if prev_uv is None or gaps[i] <= 100 * tol:
                    u, v = float(feet[i, 0]), float(feet[i, 1])
                else:  # from the previous sample's foot, unless the grid's is nearer
                    (u, v), _ = grid.project_near(xyzs[i], prev_uv, 100 * tol)
            else:
                proj.Init(c.Value(float(t)), surf, *bounds)
                if proj.NbPoints() == 0:
                    return None
                u, v = proj.LowerDistanceParameters()
            if prev_u is not None and surf.IsUPeriodic():  # stay on one sheet
                per = surf.UPeriod()
                u += per * round((prev_u - u) / per)
            prev_u, prev_uv = u, (u, v)
            pts.SetValue(i + 1, gp_Pnt2d(u, v))
            pars.SetValue(i + 1, float(t))
        fit = Geom2dAPI_PointsToBSpline(pts, pars, 3, 8, GeomAbs_C2, 1e-3 * tol)
        if not fit.IsDone():
            return None
        fits.append((fit.Curve(), a, b))
    return _concat_c0(fits)


def _concat_c0(curves: list[tuple[Any, float, float]]) -> Any:
    """One 2-D B-spline from consecutive B-splines, each mapped affinely from its own knot
    range onto ``[a, b]`` (the fitter normalises to [0, 1]), C0 at the joints."""
    from OCP.collections import Array1_double, Array1_gp_Pnt2d, Array1_int
    from OCP.Geom2d import Geom2d_BSplineCurve
    from OCP.gp import gp_Pnt2d

    deg = max(cv.Degree() for cv, _, _ in curves)
    poles: list[tuple[float, float]] = []
    knots: list[float] = []
    mults: list[int] = []
    for k, (cv, a, b) in enumerate(curves):
        cv.IncreaseDegree(deg)
        ps = [(cv.Pole(i).X(), cv.Pole(i).Y()) for i in range(1, cv.NbPoles() + 1)]
        k0, k1 = cv.FirstParameter(), cv.LastParameter()
        ks = [a + (b - a) * (cv.Knot(i) - k0) / (k1 - k0) for i in range(1, cv.NbKnots() + 1)]
        ms = [cv.Multiplicity(i) for i in range(1, cv.NbKnots() + 1)]
        if k == 0:
            poles, knots, mults = ps, ks, ms
            continue
        joint = ((poles[-1][0] + ps[0][0]) / 2, (poles[-1][1] + ps[0][1]) / 2)
        poles[-1] = joint
        poles += ps[1:]
        mults[-1] = deg
        knots += ks[1:]
        mults += ms[1:]
    ap = Array1_gp_Pnt2d(1, len(poles))
    for i, (x, y) in enumerate(poles):
        ap.SetValue(i + 1, gp_Pnt2d(x, y))
    ak, am = Array1_double(1, len(knots)), Array1_int(1, len(knots))
    for i, (kv, m) in enumerate(zip(knots, mults, strict=True)):
        ak.SetValue(i + 1, kv)
        am.SetValue(i + 1, m)
    return Geom2d_BSplineCurve(ap, ak, am, deg)


def _add_pcurves(
    face: Any, tol: float, old: Sequence[Any] = (), cache: Measures | None = None
) -> None:
    """Explicit pcurves of every edge of ``face`` on its surface: OCCT's projection, replaced
    by a fitted one when that is closer (checked at samples against the 3-D curve).

    ``old``: the faces the new one replaces. Where one of them placed an edge's boundary
    farther than ``tol`` from its 3-D curve (an input whose pcurves lie within a loose edge
    tolerance of its curves), the new pcurve follows that boundary, not the 3-D curve: the
    face then covers what the old faces covered, and the volume and area stay the same.

    ``cache``: each edge's pcurve and its measured error kept by what determines them
    (:func:`_pcurve_key`), so that an attempt rebuilding a face on the same surface with
    the same edges projects nothing again (each edge gets its own copy of the pcurve)."""
    builder = BRep_Builder()
    surf = BRep_Tool.Surface_s(face)  # placed by the face's location (its parameters kept)
    grids: list[GridProjection | None] = []

    def grid() -> GridProjection | None:  # the surface's grid, made once when first needed
        if not grids:
            u0, u1, v0, v1 = (float(x) for x in surf.Bounds())
            grids.append(GridProjection.of(surf, (u0, u1, v0, v1)))
        return grids[0]

    skey: list[Key | None] = []
    mine: list[Any] = []
    for e in edges_of(face):
        edge = TopoDS.Edge(e)
        if BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0):
            continue  # an original edge of an original surface: its pcurve is there
        mine.append(edge)
        c, f, l = edge_curve(e)
        loose = _loose_boundary(edge, c, f, l, old, tol)
        compute = partial(_edge_pcurve, c, f, l, surf, tol, loose, grid)
        key = None
        if cache is not None:
            if not skey:
                skey.append(surface_key(surf))
            key = _pcurve_key(skey[0], c, f, l, tol, loose)
        if cache is None or key is None:
            pc, err = compute()
        else:
            pc, err = cache.get(key, compute)
            pc = None if pc is None else pc.Copy()  # (OCP gives the concrete kind)
        if pc is None:
            raise CadError("projecting a boundary edge onto a new surface failed")
        _set_pcurve(builder, edge, face, pc, f, l, err, tol)  # (err measured)
    _close_uv_gaps(face, mine, surf, tol)


def _close_uv_gaps(face: Any, mine: Sequence[Any], surf: Any, tol: float) -> None:
    """Make consecutive pcurves of ``face``'s wires meet where they miss by more than
    ``tol`` on the surface ``surf``: the ends of the pcurves of ``mine`` (the edges given a
    pcurve on the new surface) are moved onto the end they miss (to the midpoint where
    both are in ``mine``) by the B-spline's end pole, the edge's tolerance kept or raised.

    OCCT's area and volume integrals run along the pcurves and need the loops closed. On a
    loose input whose pcurves missed each other by 2 - 3e-3 mm at the vertices (within
    the tolerances), the area integrator read a merged face 1.4e-3 smaller than its
    points measure (a grid in its parameters, a triangulation), and the volume integrator
    was 1.4e-4 of the part off the gaps' measure; joined, 5e-7. Pcurves that are not
    B-splines or lines (whose parameter a conversion would change) and seams stay."""
    from OCP.BRepTools import BRepTools_WireExplorer
    from OCP.TopAbs import TopAbs_WIRE
    from OCP.TopExp import TopExp_Explorer

    movable = [e for e in mine if not BRep_Tool.IsClosed_s(e, face)]

    def index(e: Any) -> int:  # the edge's place in ``movable``, -1 when not there
        return next((i for i, m in enumerate(movable) if m.IsSame(e)), -1)

    moves: dict[tuple[int, bool], np.ndarray] = {}  # (edge, its pcurve's last end): target
    exp = TopExp_Explorer(face, TopAbs_WIRE)
    while exp.More():
        ends = []  # per edge in wire order: (edge, start uv, end uv) as oriented
        walk = BRepTools_WireExplorer(TopoDS.Wire(exp.Current()), face)
        while walk.More():
            e = walk.Current()
            pc = BRep_Tool.CurveOnSurface_s(e, face, 0.0, 0.0)
            f, l = BRep_Tool.Range_s(e, face)
            a, b = np.array(pc.Value(f).Coord()), np.array(pc.Value(l).Coord())
            ends.append((e, *((b, a) if e.Orientation() == TopAbs_REVERSED else (a, b))))
            walk.Next()
        exp.Next()
        for (e1, _, p), (e2, q, _) in zip(ends, ends[1:] + ends[:1], strict=True):
            if e1.IsSame(e2) or surf.Value(*p).Distance(surf.Value(*q)) <= tol:
                continue
            i1, i2 = index(e1), index(e2)
            if i1 < 0 and i2 < 0:
                continue
            target = 0.5 * (p + q) if i1 >= 0 and i2 >= 0 else (q if i1 >= 0 else p)
            if i1 >= 0:  # e1's end as oriented: its pcurve's last point unless reversed
                moves[(i1, e1.Orientation() != TopAbs_REVERSED)] = target
            if i2 >= 0:
                moves[(i2, e2.Orientation() == TopAbs_REVERSED)] = target
    builder = BRep_Builder()
    for (i, last), target in moves.items():
        edge = movable[i]
        f, l = BRep_Tool.Range_s(edge, face)
        pc = _pole_movable(BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0), f, l)
        if pc is None:
            continue
        pc.SetPole(pc.NbPoles() if last else 1, gp_Pnt2d(float(target[0]), float(target[1])))
        c, cf, cl = edge_curve(edge)
        _set_pcurve(builder, edge, face, pc, f, l, _pcurve_error(pc, c, surf, cf, cl), tol)


def _pole_movable(pc: Any, f: float, l: float) -> Any | None:
    """A B-spline copy of the pcurve ``pc`` on ``[f, l]``, its own parameter kept (clamped:
    its end poles are its end points); None unless ``pc`` is a non-periodic B-spline or a
    line."""
    from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_Line, Geom2d_TrimmedCurve
    from OCP.Geom2dConvert import Geom2dConvert

    if isinstance(pc, Geom2d_TrimmedCurve):
        pc = pc.BasisCurve()
    if isinstance(pc, Geom2d_BSplineCurve) and not pc.IsPeriodic():
        copy = pc.Copy()
        if f != copy.FirstParameter() or l != copy.LastParameter():
            copy.Segment(f, l)
        return copy
    if isinstance(pc, Geom2d_Line):
        return Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(pc, f, l))
    return None


def _edge_pcurve(
    c: Any,
    f: float,
    l: float,
    surf: Any,
    tol: float,
    loose: _BoundaryOnFace | None,
    grid: Callable[[], GridProjection | None],
) -> tuple[Any | None, float]:
    """(pcurve, its error) of the 3-D curve ``c`` on ``[f, l]`` on ``surf``: fitted to the
    ``loose`` boundary when given and that fit succeeds; else OCCT's projection, replaced
    by a fitted one when that is closer (None, inf: both failed)."""
    if loose is not None:
        pc = _fitted_pcurve(loose, surf, f, l, tol, grid())
        if pc is not None:
            return pc, _pcurve_error(pc, c, surf, f, l)
    pc = _projected_pcurve(c, f, l, surf, tol)
    err = float("inf") if pc is None else _pcurve_error(pc, c, surf, f, l)
    if err > 0.1 * tol:
        alt = _fitted_pcurve(c, surf, f, l, tol, grid())
        alt_err = float("inf") if alt is None else _pcurve_error(alt, c, surf, f, l)
        if alt_err < err:
            pc, err = alt, alt_err
    return pc, err


def _pcurve_key(
    skey: Key | None, c: Any, f: float, l: float, tol: float, loose: _BoundaryOnFace | None
) -> Key | None:
    """What determines an edge's pcurve, as a key: the surface's key ``skey``, the 3-D
    curve ``c`` and its range ``[f, l]``, ``tol`` and the ``loose`` boundary followed (the
    old face's surface, location, pcurve and range); None where a part has no key."""
    ckey = curve_key(c)
    lkey = None if loose is None else loose.key()
    if skey is None or ckey is None or (loose is not None and lkey is None):
        return None
    return ("pcurve", skey, ckey, np.array([f, l, tol], dtype=np.float64).tobytes(), lkey)


def _set_pcurve(
    builder: Any, edge: Any, face: Any, pc: Any, f: float, l: float, err: float, tol: float
) -> None:
    """Give ``edge`` the pcurve ``pc`` on ``face`` over ``[f, l]``, its tolerance covering
    the measured distance ``err`` from the 3-D curve."""
    builder.UpdateEdge(edge, pc, face, max(tol, 2 * err, BRep_Tool.Tolerance_s(edge)))
    # the pcurve is on the edge's own parameter, its error measured: say so
    builder.Range(edge, face, f, l)
    builder.SameRange(edge, True)
    builder.SameParameter(edge, True)


class _BoundaryOnFace:
    """An edge as an old face's pcurve places it (``Value(t)``: a ``gp_Pnt``), with the
    3-D curve's knots (``NbKnots``/``Knot``) for :func:`_fitted_pcurve`'s spans."""

    def __init__(self, edge: Any, face: Any, curve: Any) -> None:
        from OCP.BRepAdaptor import BRepAdaptor_Curve

        self._on = BRepAdaptor_Curve(edge, face)
        self._edge, self._face = edge, face
        self._curve = curve
        if hasattr(curve, "NbKnots"):
            self.NbKnots = curve.NbKnots
            self.Knot = curve.Knot

    def Value(self, t: float) -> Any:  # noqa: N802 (OCCT's name, for _fitted_pcurve)
        return self._on.Value(t)

    def key(self) -> Key | None:
        """What places the boundary (as ``BRepAdaptor_Curve`` evaluates it: the old face's
        surface moved by its location, along the edge's pcurve on it) as a key; None where
        a part has no key."""
        loc = TopLoc_Location()
        skey = surface_key(BRep_Tool.Surface_s(self._face, loc))
        pc = BRep_Tool.CurveOnSurface_s(self._edge, self._face, 0.0, 0.0)
        a, b = BRep_Tool.Range_s(self._edge, self._face)
        pkey = None if pc is None else curve2d_key(pc)
        if skey is None or pkey is None:
            return None
        return (skey, location_key(loc), pkey, np.array([a, b], dtype=np.float64).tobytes())


def _loose_boundary(
    edge: Any, c: Any, f: float, l: float, old: Sequence[Any], tol: float
) -> _BoundaryOnFace | None:
    """The edge as the face of ``old`` it bounds places it, when that boundary lies
    farther than ``tol`` from the 3-D curve ``c`` on ``[f, l]`` but within the edge's own
    tolerance (a loose input edge; else None). Only faces that have the edge in their
    boundary count: OCCT finds a pcurve by the surface, and a face sharing its surface
    with another face the edge bounds returns that one (seen 1.0 off the edge)."""
    if not BRep_Tool.Tolerance_s(edge) > tol:
        return None
    for face in old:
        if not any(edge.IsSame(e) for e in edges_of(face)):
            continue
        pc = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if pc is None:
            continue
        a, b = BRep_Tool.Range_s(edge, face)
        if abs(a - f) > 1e-9 * (1 + abs(f)) or abs(b - l) > 1e-9 * (1 + abs(l)):
            continue  # not on the 3-D curve's parameter
        on = _BoundaryOnFace(edge, face, c)
        far = max(on.Value(float(t)).Distance(c.Value(float(t))) for t in np.linspace(f, l, 9))
        # (beyond the edge's own tolerance the two do not describe one boundary; that
        # tolerance is OCCT's own sampled measure of the same distance: 5 % slack)
        if tol < far <= 1.05 * BRep_Tool.Tolerance_s(edge):
            return on
    return None


def _projected_pcurve(c: Any, f: float, l: float, surf: Any, tol: float) -> Any:
    """OCCT's projection of the curve ``c`` on ``[f, l]`` onto ``surf`` (None when it
    fails). On the exact B-spline of an extrusion (straight direction in ``u``) it is
    projected onto the same extrusion as a ``Geom_SurfaceOfLinearExtrusion`` (profile in
    ``u``, the same parametrisation swapped), whose projection OCCT does on the profile,
    and mirrored back: on an oblique fillet end, the B-spline's own projection was
    1.5e-5 off (4e-7 x diagonal)."""
    from OCP.Geom import Geom_SurfaceOfLinearExtrusion
    from OCP.Geom2d import Geom2d_Curve
    from OCP.gp import gp_Ax2d, gp_Dir, gp_Dir2d, gp_Pnt2d

    from medax.cad.simplify.projection import extrusion_parts

    parts = extrusion_parts(surf)
    if parts is None or not parts[2]:
        return GeomProjLib.Curve2d_s(c, f, l, surf, tol)
    profile, d, _ = parts
    ext = Geom_SurfaceOfLinearExtrusion(profile, gp_Dir(*map(float, d)))
    pc = GeomProjLib.Curve2d_s(c, f, l, ext, tol)
    if pc is None:
        return None
    mirrored = pc.Mirrored(gp_Ax2d(gp_Pnt2d(0.0, 0.0), gp_Dir2d(1.0, 1.0)))
    return mirrored if isinstance(mirrored, Geom2d_Curve) else Geom2d_Curve.DownCast(mirrored)


def _pole_face(surf: Any, g: Group, tol: float) -> Any | None:
    """The face of a revolution surface whose profile starts on the axis (a filleted boss
    top): bounded by one closed edge, it contains the pole. Built on natural bounds (seam and
    degenerated pole edge by ``BRepBuilderAPI_MakeFace``), its circle replaced by the shared
    closed edge. None when ``g`` is not such a face."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRepTools import BRepTools_ReShape
    from OCP.Geom import Geom_SurfaceOfRevolution
    from OCP.Geom2d import Geom2d_Line
    from OCP.gp import gp_Dir2d, gp_Pnt2d

    if not isinstance(surf, Geom_SurfaceOfRevolution) or len(g.loops) != 1:
        return None
    (loop,) = g.loops
    if len(loop) != 1 or len(loop[0].edges) != 1:
        return None
    edge = loop[0].edges[0]
    v0, v1 = edge_ends(edge)
    if not v0.IsSame(v1):
        return None
    prof = surf.BasisCurve()
    ax = surf.Axis()
    c, a = xyz(ax.Location()), xyz(ax.Direction())

    def rho(t: float) -> float:
        r = xyz(prof.Value(t)) - c
        return float(np.linalg.norm(r - (r @ a) * a))

    f0, f1 = prof.FirstParameter(), prof.LastParameter()
    vpole = f0 if rho(f0) < rho(f1) else f1
    if rho(vpole) > tol:
        return None
    proj = GeomAPI_ProjectPointOnSurf(BRep_Tool.Pnt_s(v0), surf)
    u_v, vm = proj.LowerDistanceParameters()
    if min(abs(u_v), abs(u_v - 2 * np.pi)) > 1e-7:
        return None  # the closed edge's vertex is not on the seam
    lo, hi = min(vpole, vm), max(vpole, vm)
    mk = BRepBuilderAPI_MakeFace(surf, 0.0, 2 * np.pi, lo, hi, tol)
    if not mk.IsDone():
        return None
    face = mk.Face()
    circle = None
    for e in edges_of(face):
        if BRep_Tool.Degenerated_s(e) or BRep_Tool.IsClosed_s(e, face):
            continue
        circle = e
    if circle is None:
        return None
    shared = TopoDS.Edge(edge)
    # does the shared edge's parameter run the circle's way (+u)? Then traverse it the way
    # the face traverses the circle.
    tc = edge_points(circle, 3)
    te = edge_points(shared, 3)
    same = float((tc[1] - tc[0]) @ (te[1] - te[0])) > 0
    fwd = shared.Oriented(circle.Orientation())
    if not same:
        fwd = fwd.Reversed()
    reshape = BRepTools_ReShape()
    reshape.Replace(circle, fwd)
    reshape.Replace(edge_ends(circle)[0], v0)
    new_face = TopoDS.Face(reshape.Apply(face))
    e0 = TopoDS.Edge(edge)
    c3, f, l = edge_curve(e0)
    line = Geom2d_Line(gp_Pnt2d(0.0, vm), gp_Dir2d(1.0 if same else -1.0, 0.0))
    if _pcurve_error(line, c3, surf, f, l) > tol:
        line = GeomProjLib.Curve2d_s(c3, f, l, surf, tol)
    BRep_Builder().UpdateEdge(e0, line, new_face, tol)
    return new_face


def build_solid(
    split: SplitResult,
    groups: list[Group],
    surfaces: dict[int, Any],
    tol: float,
    pcurves: Measures | None = None,
) -> tuple[Any, list[Any]]:
    """The simplified solid and the new face of each group (same order as ``groups``).

    ``surfaces`` maps a supporting face (original index) to its merged ``Geom_Surface``;
    ``pcurves``: the new edges' pcurves kept across the attempts of one simplification
    (:func:`_add_pcurves`).
    """
    builder = BRep_Builder()
    faces: list[Any] = []
    for g in groups:
        member = TopoDS.Face(split.face_map.FindKey(g.members[0] + 1))
        if g.untouched:
            faces.append(member)
            continue
        loc = TopLoc_Location()
        if g.support is not None:
            surf = surfaces[g.support]
            ref = next(
                TopoDS.Face(split.face_map.FindKey(k + 1))
                for k in g.members
                if split.origin[k] == g.support
            )
            # an inside point, else a boundary point (smooth there); never a pole
            candidates = [face_inside_point(ref), edge_points(next(edges_of(ref)), 3)[1]]
            flip = None
            for p in candidates:
                if p is None:
                    continue
                n_out = face_normal_at(ref, p)
                n_new = _surface_normal(surf, p)
                if n_out is not None and n_new is not None:
                    flip = float(n_out @ n_new) < 0
                    break
            if flip is None:
                raise CadError(f"face {g.support}: no point with defined normals")
        else:  # the face's own surface (and location): its orientation says it all
            loc = TopLoc_Location()
            surf = BRep_Tool.Surface_s(member, loc)
            flip = member.Orientation() == TopAbs_REVERSED
        placed = surf if loc.IsIdentity() else BRep_Tool.Surface_s(member)
        pole = _pole_face(placed, g, tol)
        if pole is not None:
            faces.append(pole.Reversed() if flip else pole)
            continue
        face = TopoDS_Face()
        # an original surface keeps its handle and location, so the unchanged edges keep
        # their pcurves (a copy would have none: they would be projected again, and on an
        # input whose pcurves lie up to its edge tolerance from the 3-D curves, that moves
        # the face's boundary and its volume)
        builder.MakeFace(face, surf, loc, tol)
        for loop in g.loops:
            edges: list[Any] = []
            for run in loop:
                edges.extend(run.edges)
            if flip:
                edges = [e.Reversed() for e in reversed(edges)]
            wire = TopoDS_Wire()
            builder.MakeWire(wire)
            for e in edges:
                builder.Add(wire, e)
            wire.Closed(True)
            builder.Add(face, wire)
        old = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
        _add_pcurves(face, tol, old, pcurves)
        if flip:
            face.Reverse()
        faces.append(face)
    shell = TopoDS_Shell()
    builder.MakeShell(shell)
    for f in faces:
        builder.Add(shell, f)
    shell.Closed(True)
    solid = TopoDS_Solid()
    builder.MakeSolid(solid)
    builder.Add(solid, shell)
    result, ctx = _fixed(solid, tol)
    history = [ctx]
    if _has_rough_seams(result):
        result, more = _seams_split(result, tol)
        history += more
    try:
        BRepLib.SameParameter_s(result, tol, False)
    except Exception:  # OCCT failure on one edge: do the edges one by one
        for e in edges_of(result):
            try:
                BRepLib.SameParameter_s(e, tol)
            except Exception as err:
                log.info("SameParameter failed on an edge: %s", err)
    out = []
    for g, f in zip(groups, faces, strict=True):
        healed = _through(history, f)
        if healed.IsNull() or healed.ShapeType() != TopAbs_FACE:
            # the healing split the new face in several, or removed it: blame its fillets
            raise GroupError(
                f"group of face {g.members[0]}: the healed solid does not keep it as one face",
                {split.origin[k] for k in g.members},
            )
        out.append(TopoDS.Face(healed))
    return result, out


def _fixed(shape: Any, tol: float) -> tuple[Any, Any]:
    """``shape`` healed by ``ShapeFix_Shape`` at precision ``tol`` (it also adds the seams
    of closed faces), and the fix's context (what became of each sub-shape)."""
    fix = ShapeFix_Shape(shape)
    fix.SetPrecision(tol)
    fix.SetMaxTolerance(1e3 * tol)
    fix.Perform()
    return fix.Shape(), fix.Context()


def _through(contexts: list[Any], shape: Any) -> Any:
    """``shape`` as the modifications recorded in ``contexts`` (in order) left it."""
    for ctx in contexts:
        shape = ctx.Apply(shape)
    return shape


def _has_rough_seams(shape: Any) -> bool:
    """Whether a seam edge of ``shape`` has a 3-D curve that is not C2 (a revolved
    profile's line - arc joints: the seam that ``ShapeFix`` adds runs along the profile)."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.GeomAbs import GeomAbs_C0, GeomAbs_C1

    for f in faces_of(shape):
        for e in edges_of(f):
            edge = TopoDS.Edge(e)
            if BRep_Tool.Degenerated_s(edge) or not BRep_Tool.IsClosed_s(edge, f):
                continue
            if BRepAdaptor_Curve(edge).Continuity() in (GeomAbs_C0, GeomAbs_C1):
                return True
    return False


def _seams_split(shape: Any, tol: float) -> tuple[Any, list[Any]]:
    """``shape`` with its edges split where their 3-D curves are not C2, healed again; and
    the contexts of both steps. Faces are not split.

    OCCT's default mass properties (FreeCAD's, CadQuery's) integrate along each edge with a
    fixed number of Gauss points: along a seam that crosses a revolved profile's joints
    they lost 5e-4 of the volume (Gauss-Kronrod 1e-5); with the seam split there, both
    agree with the input to 1e-10. The other edges of a merged face are already the
    split solid's own, smooth pieces.
    """
    from OCP.GeomAbs import GeomAbs_C0, GeomAbs_C2
    from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideContinuity

    div = ShapeUpgrade_ShapeDivideContinuity(shape)
    div.SetBoundaryCriterion(GeomAbs_C2)
    div.SetPCurveCriterion(GeomAbs_C0)
    div.SetSurfaceCriterion(GeomAbs_C0)
    div.SetTolerance(tol)
    if not div.Perform():
        return shape, []
    fixed, ctx = _fixed(div.Result(), tol)
    return fixed, [div.GetContext(), ctx]
