"""Elementary surfaces recognised behind other representations.

CAD systems write many cylinders and tori as surfaces of revolution (a line parallel to the
axis, a circle in a plane through it), as extrusions of circles, or as B-splines; STEP
keeps what they wrote. The exact merged surfaces (:mod:`.surfaces`) need the axis and
radii of the fillets and supports, so these faces are seen here as the elementary surface
they are: :func:`canonical_adaptor` answers ``GetType()``, ``Cylinder()``, ``Torus()``,
``Sphere()``, ``Cone()`` and ``Plane()`` like OCCT's face adaptor. Only the geometry of
the answer is used (axes, radii), never its parametrisation.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_CylindricalSurface, Geom_SphericalSurface, Geom_ToroidalSurface
from OCP.GeomAbs import (
    GeomAbs_BezierSurface,
    GeomAbs_BSplineSurface,
    GeomAbs_Circle,
    GeomAbs_Line,
    GeomAbs_SurfaceOfExtrusion,
    GeomAbs_SurfaceOfRevolution,
)
from OCP.GeomAdaptor import GeomAdaptor_Surface
from OCP.GeomConvert import GeomConvert_SurfToAnaSurf
from OCP.gp import gp_Ax3, gp_Dir

from medax.cad.simplify.occ import pnt, xyz

#: Directions closer than this (sine of the angle) count as parallel.
PARALLEL = 1e-9


def canonical_adaptor(face: Any, tol: float) -> Any:
    """An adaptor of ``face``'s surface, elementary where the surface is one within ``tol``
    (length): a revolution of a line parallel to its axis (a cylinder) or of a circle in a
    plane through it (a torus, or a sphere), an extrusion of a circle along its normal (a
    cylinder), a B-spline or Bezier surface that OCCT's ``GeomConvert_SurfToAnaSurf``
    converts within ``tol``; else OCCT's own face adaptor."""
    ad = BRepAdaptor_Surface(face)
    kind = ad.GetType()
    surf = None
    if kind == GeomAbs_SurfaceOfRevolution:
        surf = _revolved(ad, tol)
    elif kind == GeomAbs_SurfaceOfExtrusion:
        surf = _extruded(ad, tol)
    elif kind in (GeomAbs_BSplineSurface, GeomAbs_BezierSurface):
        surf = _converted(face, tol)
    return ad if surf is None else GeomAdaptor_Surface(surf)


def _revolved(ad: Any, tol: float) -> Any | None:
    ax = ad.AxeOfRevolution()
    o, a = xyz(ax.Location()), xyz(ax.Direction())
    basis = ad.BasisCurve()
    if basis.GetType() == GeomAbs_Line:
        line = basis.Line()
        if np.linalg.norm(np.cross(xyz(line.Direction()), a)) > PARALLEL:
            return None
        p = xyz(line.Location())
        c = o + ((p - o) @ a) * a
        r = float(np.linalg.norm(p - c))
        if r <= tol:
            return None
        return Geom_CylindricalSurface(_frame(c, a, (p - c) / r), r)
    if basis.GetType() == GeomAbs_Circle:
        circ = basis.Circle()
        n, q = xyz(circ.Axis().Direction()), xyz(circ.Location())
        if abs(n @ a) > PARALLEL:  # the circle's plane does not contain the axis's direction
            return None
        if abs((q - o) @ n) > tol:  # ... or not the axis itself
            return None
        c = o + ((q - o) @ a) * a
        big, small = float(np.linalg.norm(q - c)), circ.Radius()
        if big <= tol:
            return Geom_SphericalSurface(_frame(c, a, _normal_to(a)), small)
        return Geom_ToroidalSurface(_frame(c, a, (q - c) / big), big, small)
    return None


def _extruded(ad: Any, tol: float) -> Any | None:
    basis = ad.BasisCurve()
    if basis.GetType() != GeomAbs_Circle:
        return None
    circ = basis.Circle()
    d = xyz(ad.Direction())
    if np.linalg.norm(np.cross(xyz(circ.Axis().Direction()), d)) > PARALLEL:
        return None
    c = xyz(circ.Location())
    return Geom_CylindricalSurface(_frame(c, d, _normal_to(d)), circ.Radius())


def _converted(face: Any, tol: float) -> Any | None:
    u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
    conv = GeomConvert_SurfToAnaSurf(BRep_Tool.Surface_s(face))
    try:
        out = conv.ConvertToAnalytical(tol, u0, u1, v0, v1)
    except Exception:  # OCCT's Standard_Failure (seen: a null adaptor inside the converter)
        return None
    if out is None or conv.Gap() > tol:
        return None
    return out


def _normal_to(a: np.ndarray) -> np.ndarray:
    """A unit vector normal to the unit vector ``a`` (3,)."""
    e = np.eye(3)[int(np.argmin(np.abs(a)))]
    v = np.cross(a, e)
    return v / np.linalg.norm(v)


def _frame(c: np.ndarray, z: np.ndarray, x: np.ndarray) -> Any:
    return gp_Ax3(pnt(c), gp_Dir(*map(float, z)), gp_Dir(*map(float, x)))
