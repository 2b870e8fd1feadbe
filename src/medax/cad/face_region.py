"""A fillet face as a 4-sided :class:`~medax.geometry.Region` on its surface, and its axis.

The region's sides are the face's pcurves in ``(u, v)`` (side 0 = smooth side 0, side 1 =
cross edge 0, side 2 = smooth side 1, side 3 = cross edge 1, in outer-wire order), its
embedding is the face's surface as a numpy :mod:`medax.geometry.surfaces` object, and its
``space_sides`` are the exact 3-D edge curves (as rational B-splines), so the tracer
measures distances in space to the true edges. The axis is traced by
:func:`medax.axis.trace_axis` with constraints (0, 2): no second copy of the tracer.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.Geom import Geom_TrimmedCurve
from OCP.Geom2d import Geom2d_TrimmedCurve
from OCP.Geom2dConvert import Geom2dConvert, Geom2dConvert_CompCurveToBSplineCurve
from OCP.GeomAbs import (
    GeomAbs_BSplineSurface,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_Torus,
)
from OCP.GeomConvert import GeomConvert, GeomConvert_CompCurveToBSplineCurve
from OCP.TopAbs import TopAbs_REVERSED

from medax import tolerances
from medax.axis import MedialAxis, trace_axis
from medax.cad.model import Classification, FilletRecord
from medax.errors import CadError
from medax.geometry.bspline import BSpline
from medax.geometry.embedding import Embedding
from medax.geometry.region import Region
from medax.geometry.surfaces import (
    ConeSurface,
    CylinderSurface,
    Frame,
    NurbsSurface,
    PlaneSurface,
    SphereSurface,
    TorusSurface,
)


# ---- surfaces -----------------------------------------------------------------------------
def _frame(ax3: Any) -> Frame:
    o, x, y, z = ax3.Location(), ax3.XDirection(), ax3.YDirection(), ax3.Direction()
    return Frame.make(
        (o.X(), o.Y(), o.Z()), (x.X(), x.Y(), x.Z()), (y.X(), y.Y(), y.Z()), (z.X(), z.Y(), z.Z())
    )


def surface_embedding(face: Any) -> Embedding:
    """The numpy embedding ``S(u, v)`` of ``face``'s surface, in OCCT's parameters.

    Analytic surfaces map exactly; B-spline surfaces copy poles, weights and knots; other
    kinds (Bezier, revolution, extrusion, offset) go through
    ``GeomConvert.SurfaceToBSplineSurface_s``.
    """
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
        bs = s.BSpline()
    else:
        try:
            bs = GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(face))
        except Exception as err:
            raise CadError(f"cannot convert a {kind.name} surface to a B-spline ({err})") from err
    return bspline_embedding(bs)


def bspline_embedding(bs: Any) -> NurbsSurface:
    """The numpy copy of a ``Geom_BSplineSurface`` (a periodic one made non-periodic)."""
    if bs.IsUPeriodic() or bs.IsVPeriodic():
        bs = bs.Copy()
        if bs.IsUPeriodic():
            bs.SetUNotPeriodic()
        if bs.IsVPeriodic():
            bs.SetVNotPeriodic()
    nu, nv = bs.NbUPoles(), bs.NbVPoles()
    poles = np.empty((nu, nv, 3))
    weights = np.empty((nu, nv))
    for a in range(nu):
        for b in range(nv):
            p = bs.Pole(a + 1, b + 1)
            poles[a, b] = (p.X(), p.Y(), p.Z())
            weights[a, b] = bs.Weight(a + 1, b + 1)
    uk = np.array(list(bs.UKnotSequence()), dtype=float)
    vk = np.array(list(bs.VKnotSequence()), dtype=float)
    rational = bs.IsURational() or bs.IsVRational()
    return NurbsSurface(poles, bs.UDegree(), bs.VDegree(), uk, vk, weights if rational else None)


# ---- curves -------------------------------------------------------------------------------
def curve_copy(bs: Any) -> BSpline:
    """The numpy copy of a 3-D ``Geom_BSplineCurve`` (its knot range mapped onto [0, 1])."""
    return _to_bspline(bs, 3)


def _to_bspline(bs: Any, dim: int) -> BSpline:
    if bs.IsPeriodic():
        bs = bs.Copy()
        bs.SetNotPeriodic()
    n = bs.NbPoles()
    if dim == 2:
        ctrl = np.array([[bs.Pole(i).X(), bs.Pole(i).Y()] for i in range(1, n + 1)])
    else:
        ctrl = np.array([[bs.Pole(i).X(), bs.Pole(i).Y(), bs.Pole(i).Z()] for i in range(1, n + 1)])
    knots = np.array(list(bs.KnotSequence()), dtype=float)
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
            raise CadError("a fillet side's edges do not chain")
    return comp.BSplineCurve()


# ---- the region ---------------------------------------------------------------------------
def fillet_sides(c: Classification, rec: FilletRecord) -> list[list[Any]]:
    """The oriented edges of each of the 4 sides of fillet ``rec``, in outer-wire order
    (smooth side 0, a cross edge, smooth side 1, the other cross edge)."""
    face = c.face(rec.face)
    wire = BRepTools.OuterWire_s(face)
    occ: list[tuple[str, Any]] = []
    s0, s1 = set(rec.smooth_edges[0]), set(rec.smooth_edges[1])
    exp = BRepTools_WireExplorer(wire, face)
    while exp.More():
        e = exp.Current()
        exp.Next()
        if BRep_Tool.Degenerated_s(e):
            continue
        j = c.edge_map.FindIndex(e) - 1
        occ.append(("S0" if j in s0 else "S1" if j in s1 else "C", e))
    k = next((i for i in range(len(occ)) if occ[i][0] == "S0" and occ[i - 1][0] != "S0"), None)
    if k is None:
        raise CadError(f"face {rec.face}: smooth side 0 not found in its outer wire")
    occ = occ[k:] + occ[:k]
    sides: list[list[Any]] = []
    for label, e in occ:
        if sides and sides[-1][0] == label:
            sides[-1][1].append(e)
        else:
            sides.append((label, [e]))  # type: ignore[arg-type]
    if [s[0] for s in sides] != ["S0", "C", "S1", "C"]:
        raise CadError(f"face {rec.face}: outer wire is not smooth/cross/smooth/cross")
    return [s[1] for s in sides]


def fillet_region(c: Classification, rec: FilletRecord) -> Region:
    """Fillet ``rec`` as a Region on its surface: pcurve sides, exact 3-D space sides."""
    face = c.face(rec.face)
    try:
        sides = fillet_sides(c, rec)
        sides2d = [_to_bspline(_chain([_pcurve(e, face) for e in s], True), 2) for s in sides]
        sides3d = [_to_bspline(_chain([_curve3d(e) for e in s], False), 3) for s in sides]
        emb = surface_embedding(face)
    except CadError as err:
        raise CadError(f"{c.source or 'shape'}: fillet face {rec.face}: {err}") from err
    except Exception as err:
        raise CadError(f"{c.source or 'shape'}: fillet face {rec.face}: OCCT ({err})") from err
    return Region.build(sides2d, name=f"face {rec.face}", embedding=emb, space_sides=sides3d)


def fillet_axis(
    c: Classification, rec: FilletRecord, tol: float = tolerances.CURVE_TOL
) -> MedialAxis:
    """The medial axis of fillet ``rec`` between its two smooth edges (``tol`` relative
    to the region's diagonal), from cross edge 1 to cross edge 0 in the region's order."""
    return trace_axis(fillet_region(c, rec), pair=(0, 2), tol=tol)
