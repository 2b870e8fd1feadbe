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
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepLib import BRepLib
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.GeomProjLib import GeomProjLib
from OCP.gp import gp_Pnt
from OCP.ShapeFix import ShapeFix_Shape
from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shell, TopoDS_Solid, TopoDS_Wire

from medax.cad.simplify.geom_key import Key, curve_key, surface_key
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
    reader_spans,
    xyz,
)
from medax.cad.simplify.projection import GridProjection, graph_frame
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


#: A fitted pcurve on a fitted face is taken without OCCT's projection when its error is
#: within this factor of the 3-D curve's own largest distance from the surface (no pcurve
#: can be nearer): on a 555-face part OCCT projected 412 circles onto fitted faces in 25 s.
NEAR_FLOOR = 1.05


def _curve_gap(c: Any, f: float, l: float, grid: GridProjection) -> float:
    """Largest distance of the 3-D curve ``c`` on ``[f, l]`` from the grid's surface, at the
    samples :func:`_pcurve_error` takes. The grid's feet are never nearer than the true
    ones: a foot found on another part of the surface overstates it, so the caller takes
    it only when it is small (within the fits' tolerances)."""
    spans = c.NbKnots() - 1 if hasattr(c, "NbKnots") else 1
    n = int(np.clip(4 * spans + 1, 41, 2001))
    pts = np.array([xyz(c.Value(float(t))) for t in np.linspace(f, l, n)])
    _, dist = grid.project_many(pts)
    return float(dist.max())


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


def _add_pcurves(face: Any, tol: float, cache: Measures | None = None) -> None:
    """Explicit pcurves of every edge of ``face`` on its surface: on a graph surface (the
    fitted faces) the affine image of the 3-D curve where it is exact; else OCCT's
    projection, replaced by a fitted one when that is closer (each checked at samples
    against the 3-D curve).

    The pcurves follow the 3-D curves, also where the input's old faces place a loose edge
    up to its tolerance away. Following those old boundaries instead, adjacent pcurves
    taken from different old faces missed each other at the vertices (2 - 3e-3 on a loose
    52-fillet part): OCCT's integrators then read the merged faces 1.4e-3 short in area
    (their points, a parameter grid and a triangulation, agreed with each other) and the
    attempts were refused. A STEP file keeps no tolerances either, and OCCT's reader
    projects such pcurves again: that part's file read 8.5e-5 off in volume, the shape
    unchanged by rays (5e-9). Following the 3-D curves, the file reads 8.0e-7 (Gauss-
    Kronrod on a NURBS copy) and the rays 7e-9.

    ``cache``: each edge's pcurve and its measured error kept by what determines them
    (:func:`_pcurve_key`), so that an attempt rebuilding a face on the same surface with
    the same edges projects nothing again (each edge gets its own copy of the pcurve)."""
    builder = BRep_Builder()
    surf = BRep_Tool.Surface_s(face)  # placed by the face's location (its parameters kept)
    grids: list[GridProjection | None] = []
    frames: list[tuple[np.ndarray, np.ndarray] | None] = []

    def frame() -> tuple[np.ndarray, np.ndarray] | None:  # made once when first needed
        if not frames:
            frames.append(graph_frame(surf))
        return frames[0]

    def grid() -> GridProjection | None:  # the surface's grid, made once when first needed
        if not grids:
            u0, u1, v0, v1 = (float(x) for x in surf.Bounds())
            grids.append(GridProjection.of(surf, (u0, u1, v0, v1)))
        return grids[0]

    skey: list[Key | None] = []
    for e in edges_of(face):
        edge = TopoDS.Edge(e)
        if BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0):
            continue  # an original edge of an original surface: its pcurve is there
        c, f, l = edge_curve(e)
        compute = partial(_edge_pcurve, c, f, l, surf, tol, grid, frame)
        key = None
        if cache is not None:
            if not skey:
                skey.append(surface_key(surf))
            key = _pcurve_key(skey[0], c, f, l, tol)
        if cache is None or key is None:
            pc, err = compute()
        else:
            pc, err = cache.get(key, compute)
            pc = None if pc is None else pc.Copy()  # (OCP gives the concrete kind)
        if pc is None:
            raise CadError("projecting a boundary edge onto a new surface failed")
        _set_pcurve(builder, edge, face, pc, f, l, err, tol)  # (err measured)


def _edge_pcurve(
    c: Any,
    f: float,
    l: float,
    surf: Any,
    tol: float,
    grid: Callable[[], GridProjection | None],
    frame: Callable[[], tuple[np.ndarray, np.ndarray] | None] = lambda: None,
) -> tuple[Any | None, float]:
    """(pcurve, its error) of the 3-D curve ``c`` on ``[f, l]`` on ``surf``: its affine
    image when ``surf`` is a graph over its parameter plane (``frame``:
    :func:`.projection.graph_frame`) and the curve has one on its own parameter; else, or
    when that is farther than a tenth of ``tol``, on such a surface a 2-D B-spline through
    the feet of the curve's samples (:func:`_fitted_pcurve`) when it is as near as the
    curve's own distance from the surface allows (``NEAR_FLOOR``, that distance within
    ``100 tol``); else OCCT's projection, replaced by the fitted one when that is closer
    (None, inf: all failed)."""
    g = frame()
    pc = None if g is None else _affine_pcurve(c, f, l, *g)
    if pc is not None:
        err = _pcurve_error(pc, c, surf, f, l)
        if err <= 0.1 * tol:
            return pc, err
    fitted: tuple[Any | None, float] | None = None  # (made once: first here on fitted faces)
    near = None if g is None else grid()
    if near is not None:  # a fitted face: the grid's feet first (OCCT's projection: 60 ms)
        fitted = _fitted_with_error(c, surf, f, l, tol, near)
        floor = _curve_gap(c, f, l, near)
        if floor <= 100 * tol and fitted[1] <= max(0.1 * tol, NEAR_FLOOR * floor):
            return fitted
    pc = _projected_pcurve(c, f, l, surf, tol)
    err = float("inf") if pc is None else _pcurve_error(pc, c, surf, f, l)
    if err > 0.1 * tol:
        alt, alt_err = fitted or _fitted_with_error(c, surf, f, l, tol, grid())
        if alt_err < err:
            pc, err = alt, alt_err
    return pc, err


def _fitted_with_error(
    c: Any, surf: Any, f: float, l: float, tol: float, grid: GridProjection | None
) -> tuple[Any | None, float]:
    """:func:`_fitted_pcurve` and its :func:`_pcurve_error` (None, inf when it failed)."""
    pc = _fitted_pcurve(c, surf, f, l, tol, grid)
    return pc, float("inf") if pc is None else _pcurve_error(pc, c, surf, f, l)


def _affine_pcurve(c: Any, f: float, l: float, a: np.ndarray, m: np.ndarray) -> Any | None:
    """The pcurve ``t -> m @ (c(t) - a)`` of the 3-D curve ``c`` on ``[f, l]`` ((3,),
    (2, 3): :func:`.projection.graph_frame`), on the curve's own parameter: a B-spline's
    poles mapped (weights and knots kept), a line's end points (a degree-1 B-spline), a
    circle whose image is a circle; None for other curves (their affine image has no
    2-D curve on the same parameter here). Exact: an affine map commutes with the
    B-spline's rational combination of its poles."""
    from OCP.collections import Array1_double, Array1_gp_Pnt2d, Array1_int
    from OCP.Geom import Geom_BSplineCurve, Geom_Circle, Geom_Line, Geom_TrimmedCurve
    from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_Circle
    from OCP.gp import gp_Ax22d, gp_Dir2d, gp_Pnt2d

    if isinstance(c, Geom_TrimmedCurve):
        c = c.BasisCurve()

    def image(p: Any) -> np.ndarray:
        return m @ (xyz(p) - a)

    if isinstance(c, Geom_BSplineCurve):
        n = c.NbPoles()
        poles = Array1_gp_Pnt2d(1, n)
        for i in range(1, n + 1):
            poles.SetValue(i, gp_Pnt2d(*map(float, image(c.Pole(i)))))
        nk = c.NbKnots()
        knots, mults = Array1_double(1, nk), Array1_int(1, nk)
        for i in range(1, nk + 1):
            knots.SetValue(i, c.Knot(i))
            mults.SetValue(i, c.Multiplicity(i))
        periodic = bool(c.IsPeriodic())
        if c.IsRational():
            weights = Array1_double(1, n)
            for i in range(1, n + 1):
                weights.SetValue(i, c.Weight(i))
            return Geom2d_BSplineCurve(poles, weights, knots, mults, c.Degree(), periodic)
        return Geom2d_BSplineCurve(poles, knots, mults, c.Degree(), periodic)
    if isinstance(c, Geom_Line):
        poles = Array1_gp_Pnt2d(1, 2)
        poles.SetValue(1, gp_Pnt2d(*map(float, image(c.Value(f)))))
        poles.SetValue(2, gp_Pnt2d(*map(float, image(c.Value(l)))))
        knots, mults = Array1_double(1, 2), Array1_int(1, 2)
        for i, t in ((1, f), (2, l)):
            knots.SetValue(i, float(t))
            mults.SetValue(i, 2)
        return Geom2d_BSplineCurve(poles, knots, mults, 1)
    if isinstance(c, Geom_Circle):
        pos = c.Position()
        centre = image(pos.Location())
        ex, ey = m @ xyz(pos.XDirection()), m @ xyz(pos.YDirection())
        rx, ry = float(np.linalg.norm(ex)), float(np.linalg.norm(ey))
        if abs(rx - ry) > 1e-12 * rx or abs(float(ex @ ey)) > 1e-12 * rx * ry:
            return None  # an ellipse, whose own angle is not the circle's
        ax = gp_Ax22d(gp_Pnt2d(*map(float, centre)), gp_Dir2d(*ex), gp_Dir2d(*ey))
        return Geom2d_Circle(ax, c.Radius() * rx)
    return None


def _pcurve_key(skey: Key | None, c: Any, f: float, l: float, tol: float) -> Key | None:
    """What determines an edge's pcurve, as a key: the surface's key ``skey``, the 3-D
    curve ``c``, its range ``[f, l]`` and ``tol``; None where a part has no key."""
    ckey = curve_key(c)
    if skey is None or ckey is None:
        return None
    return ("pcurve", skey, ckey, np.array([f, l, tol], dtype=np.float64).tobytes())


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
            surf = reader_spans(surfaces[g.support])
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
        _add_pcurves(face, tol, pcurves)
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
