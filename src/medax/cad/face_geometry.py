"""Per-face geometry for classification: surface type, area, centroid, principal
curvature directions along the boundary, normal sweep and blend radius.

Everything is read from OCCT and returned as numpy values or small tuples.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepGProp import BRepGProp
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.GeomAbs import (
    GeomAbs_BezierSurface,
    GeomAbs_BSplineSurface,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_OffsetSurface,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_SurfaceOfExtrusion,
    GeomAbs_SurfaceOfRevolution,
    GeomAbs_Torus,
)
from OCP.gp import gp_Dir
from OCP.GProp import GProp_GProps

from medax.cad.topology import Topology, edge_params, edge_points, edge_uv, face_normals
from medax.geometry._types import FloatArray

SURFACE_NAMES = {
    GeomAbs_Plane: "plane",
    GeomAbs_Cylinder: "cylinder",
    GeomAbs_Cone: "cone",
    GeomAbs_Sphere: "sphere",
    GeomAbs_Torus: "torus",
    GeomAbs_BSplineSurface: "bspline",
    GeomAbs_BezierSurface: "bezier",
    GeomAbs_SurfaceOfRevolution: "revolution",
    GeomAbs_SurfaceOfExtrusion: "extrusion",
    GeomAbs_OffsetSurface: "offset",
}

#: samples per edge for the spring/cross direction test
DIRECTION_SAMPLES = 3
#: samples across a face for the sweep and radius measurements
SWEEP_SAMPLES = 8


@dataclass(frozen=True)
class WireEdge:
    """One edge occurrence in a face's outer wire, in wire order.

    ``kind`` is ``"spring"`` (runs along the direction of least curvature), ``"cross"``
    (along the direction of most curvature) or ``"unknown"`` (umbilic or undefined).
    ``mid_uv`` is the edge's middle in the face's parameters.
    """

    edge: int
    kind: str
    mid_uv: tuple[float, float]


def curve_type(edge: Any) -> str:
    """Lower-case OCCT curve type of ``edge``: line, circle, ellipse, hyperbola, parabola,
    bezier, bspline, offset or other."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve

    name = str(BRepAdaptor_Curve(edge).GetType().name)  # e.g. GeomAbs_BSplineCurve
    return name.removeprefix("GeomAbs_").removesuffix("Curve").lower() or "other"


def surface_type(face: Any) -> str:
    """Lower-case OCCT surface type name of ``face`` (see :data:`SURFACE_NAMES`)."""
    return SURFACE_NAMES.get(BRepAdaptor_Surface(face, False).GetType(), "other")


def area_centroid(face: Any) -> tuple[float, tuple[float, float, float]]:
    """Area and centroid of ``face``."""
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    c = props.CentreOfMass()
    return float(props.Mass()), (float(c.X()), float(c.Y()), float(c.Z()))


def curvature_frames(
    surf: Any, uv: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Principal curvatures and directions at parameters ``uv`` (n, 2).

    Returns ``kmax`` (n,), ``kmin`` (n,) (signed, ``|kmax| >= |kmin|``), ``dmax`` (n, 3) and
    ``dmin`` (n, 3); rows are NaN where curvature is undefined or the point is umbilic.
    """
    n = len(uv)
    kmax, kmin = np.full(n, np.nan), np.full(n, np.nan)
    dmax, dmin = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
    props = BRepLProp_SLProps(surf, 2, 1e-9)
    d1, d2 = gp_Dir(), gp_Dir()
    for k, (u, v) in enumerate(uv):
        props.SetParameters(float(u), float(v))
        if not props.IsCurvatureDefined() or props.IsUmbilic():
            continue
        a, b = props.MaxCurvature(), props.MinCurvature()
        props.CurvatureDirections(d1, d2)
        va, vb = (d1.X(), d1.Y(), d1.Z()), (d2.X(), d2.Y(), d2.Z())
        if abs(b) > abs(a):
            a, b, va, vb = b, a, vb, va
        kmax[k], kmin[k], dmax[k], dmin[k] = a, b, va, vb
    return kmax, kmin, dmax, dmin


def outer_wire_edges(topo: Topology, i: int) -> list[WireEdge]:
    """Edges of face ``i``'s outer wire in order, each labelled spring/cross/unknown.

    Degenerate edges (poles) are skipped. Seam edges appear twice.
    """
    face = topo.face(i)
    surf = BRepAdaptor_Surface(face, False)
    metric = _iso_metric(surf)
    wire = BRepTools.OuterWire_s(face)
    out: list[WireEdge] = []
    exp = BRepTools_WireExplorer(wire, face)
    while exp.More():
        e = exp.Current()
        exp.Next()
        if BRep_Tool.Degenerated_s(e):
            continue
        j = topo.edge_index(e)
        t = edge_params(e, DIRECTION_SAMPLES)
        uv, duv = edge_uv(e, face, t)
        mid = uv[len(uv) // 2]
        if metric is not None:
            # analytic surfaces: principal directions are the iso-lines (see _iso_metric)
            su, sv, spring_is_v = metric(uv)
            along_v = np.mean(np.abs(duv[:, 1]) * sv) > np.mean(np.abs(duv[:, 0]) * su)
            kind = "spring" if along_v == spring_is_v else "cross"
            out.append(WireEdge(j, kind, (float(mid[0]), float(mid[1]))))
            continue
        _, tan = edge_points(e, t)
        _, _, dmax, dmin = curvature_frames(surf, uv)
        tan = tan / np.maximum(np.linalg.norm(tan, axis=1, keepdims=True), 1e-300)
        cmax = np.abs(np.sum(tan * dmax, axis=1))
        cmin = np.abs(np.sum(tan * dmin, axis=1))
        ok = np.isfinite(cmax) & np.isfinite(cmin)
        if not np.any(ok):
            kind = "unknown"
        else:
            kind = "cross" if float(np.mean(cmax[ok] - cmin[ok])) > 0.0 else "spring"
        out.append(WireEdge(j, kind, (float(mid[0]), float(mid[1]))))
    return out


def _iso_metric(surf: Any) -> Any:
    """For a cylinder, cone, or torus with ``R >= 2 r``: a function ``uv (n, 2) -> (|Su|,
    |Sv|, spring_is_v)``. Their principal directions are the parameter iso-lines: the
    least-curvature (spring) direction is ``v`` (the generator) on cylinders and cones and
    ``u`` (the major circle) on such tori. None for other surfaces (use curvature)."""
    kind = surf.GetType()
    if kind == GeomAbs_Cylinder:
        r = surf.Cylinder().Radius()
        return lambda uv: (r, 1.0, True)
    if kind == GeomAbs_Cone:
        c = surf.Cone()
        r0, a = c.RefRadius(), c.SemiAngle()
        return lambda uv: (np.abs(r0 + uv[:, 1] * np.sin(a)), 1.0, True)
    if kind == GeomAbs_Torus:
        t = surf.Torus()
        big, r = t.MajorRadius(), t.MinorRadius()
        if big >= 2.0 * r:
            return lambda uv: (np.abs(big + r * np.cos(uv[:, 1])), r, False)
    return None


def normal_sweep(face: Any, uv0: FloatArray, uv1: FloatArray) -> float:
    """Total turning (radians) of the outward normal along the straight parameter segment
    from ``uv0`` to ``uv1`` (each (2,)): the angle a blend's cross-section sweeps."""
    s = np.linspace(0.0, 1.0, SWEEP_SAMPLES + 1)[:, None]
    uv = (1.0 - s) * uv0[None, :] + s * uv1[None, :]
    n = face_normals(face, uv)
    n = n[np.all(np.isfinite(n), axis=1)]
    if len(n) < 2:
        return float("nan")
    cos = np.clip(np.sum(n[:-1] * n[1:], axis=1), -1.0, 1.0)
    return float(np.sum(np.arccos(cos)))


#: freeform blends approximate the rolling ball (OCCT's are within ~0.3 %): a radius spread
#: below this fraction counts as constant
FREEFORM_RADIUS_TOL = 1e-2


def blend_radius(face: Any, rel_tol: float = FREEFORM_RADIUS_TOL) -> float | None:
    """The constant rolling-ball radius of a blend face, or None if it varies.

    Exact for cylinders (radius), tori (minor radius) and spheres; for other surfaces the
    mean of ``1 / |kmax|`` on a 5 x 5 parameter grid, constant when its spread is below
    ``rel_tol`` times the mean (an approximation, like the surface itself).
    """
    surf = BRepAdaptor_Surface(face, True)
    kind = surf.GetType()
    if kind == GeomAbs_Cylinder:
        return float(surf.Cylinder().Radius())
    if kind == GeomAbs_Torus:
        return float(surf.Torus().MinorRadius())
    if kind == GeomAbs_Sphere:
        return float(surf.Sphere().Radius())
    if kind in (GeomAbs_Plane, GeomAbs_Cone):
        return None
    u0, u1 = surf.FirstUParameter(), surf.LastUParameter()
    v0, v1 = surf.FirstVParameter(), surf.LastVParameter()
    g = np.linspace(0.1, 0.9, 5)
    uu, vv = np.meshgrid(u0 + g * (u1 - u0), v0 + g * (v1 - v0))
    kmax, _, _, _ = curvature_frames(surf, np.column_stack((uu.ravel(), vv.ravel())))
    k = np.abs(kmax[np.isfinite(kmax)])
    if len(k) < 3 or np.min(k) <= 0.0:
        return None
    r = 1.0 / k
    if (r.max() - r.min()) <= rel_tol * r.mean():
        return float(r.mean())
    return None
