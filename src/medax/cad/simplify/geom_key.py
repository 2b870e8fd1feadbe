"""Exact keys of OCCT curves and surfaces: their kind and every number that defines them
(positions, radii, poles, weights, knots, trims), as bytes. Two objects with one key are the
same geometry to the bit, whatever their handles, so a value computed on one (a projected
pcurve, :func:`.rebuild._add_pcurves`) holds for the other. Kinds not handled give None:
nothing is reused for them.

A key costs a few Python calls per pole (0.7 ms CPU for a surface of 500 poles; once per
face), against 4 ms CPU on average per edge for the pcurve it stands for (its projection,
fit and sampled error, on isolated_blends_test_13).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.Geom import (
    Geom_BezierCurve,
    Geom_BezierSurface,
    Geom_BSplineCurve,
    Geom_BSplineSurface,
    Geom_Circle,
    Geom_ConicalSurface,
    Geom_CylindricalSurface,
    Geom_Ellipse,
    Geom_Line,
    Geom_OffsetSurface,
    Geom_Plane,
    Geom_RectangularTrimmedSurface,
    Geom_SphericalSurface,
    Geom_SurfaceOfLinearExtrusion,
    Geom_SurfaceOfRevolution,
    Geom_ToroidalSurface,
    Geom_TrimmedCurve,
)
from OCP.Geom2d import (
    Geom2d_BezierCurve,
    Geom2d_BSplineCurve,
    Geom2d_Circle,
    Geom2d_Ellipse,
    Geom2d_Line,
    Geom2d_TrimmedCurve,
)

Key = tuple[Any, ...]


def _bytes(values: list[float]) -> bytes:
    return np.array(values, dtype=np.float64).tobytes()


def _xyz(p: Any) -> list[float]:
    return [p.X(), p.Y(), p.Z()]


def _ax3(a: Any) -> list[float]:
    """A 3-D frame (``gp_Ax2``/``gp_Ax3``): origin, main, X and Y directions (12 numbers)."""
    return [
        *_xyz(a.Location()),
        *_xyz(a.Direction()),
        *_xyz(a.XDirection()),
        *_xyz(a.YDirection()),
    ]


def _ax22d(a: Any) -> list[float]:
    """A 2-D frame (``gp_Ax22d``): origin, X and Y directions (6 numbers)."""
    return [
        a.Location().X(),
        a.Location().Y(),
        a.XDirection().X(),
        a.XDirection().Y(),
        a.YDirection().X(),
        a.YDirection().Y(),
    ]


def _knots(nb: Any, knot: Any, mult: Any) -> list[float]:
    """The knots, then their multiplicities, by OCCT's accessors (1-based)."""
    n = nb()
    return [float(knot(i)) for i in range(1, n + 1)] + [float(mult(i)) for i in range(1, n + 1)]


def surface_key(s: Any) -> Key | None:
    """The key of the ``Geom_Surface`` ``s`` (None for a kind not handled)."""
    name = type(s).__name__
    nums: list[float]
    if isinstance(s, Geom_BSplineSurface):
        nu, nv = s.NbUPoles(), s.NbVPoles()
        nums = [s.UDegree(), s.VDegree(), s.IsUPeriodic(), s.IsVPeriodic(), nu, nv]
        nums += _knots(s.NbUKnots, s.UKnot, s.UMultiplicity)
        nums += _knots(s.NbVKnots, s.VKnot, s.VMultiplicity)
        for i in range(1, nu + 1):
            for j in range(1, nv + 1):
                nums += _xyz(s.Pole(i, j))
        if s.IsURational() or s.IsVRational():
            nums += [s.Weight(i, j) for i in range(1, nu + 1) for j in range(1, nv + 1)]
    elif isinstance(s, Geom_BezierSurface):
        nu, nv = s.NbUPoles(), s.NbVPoles()
        nums = [nu, nv]
        for i in range(1, nu + 1):
            for j in range(1, nv + 1):
                nums += [*_xyz(s.Pole(i, j)), s.Weight(i, j)]
    elif isinstance(s, Geom_Plane):
        nums = _ax3(s.Position())
    elif isinstance(s, Geom_CylindricalSurface | Geom_SphericalSurface):
        nums = [*_ax3(s.Position()), s.Radius()]
    elif isinstance(s, Geom_ConicalSurface):
        nums = [*_ax3(s.Position()), s.RefRadius(), s.SemiAngle()]
    elif isinstance(s, Geom_ToroidalSurface):
        nums = [*_ax3(s.Position()), s.MajorRadius(), s.MinorRadius()]
    elif isinstance(s, Geom_SurfaceOfLinearExtrusion):
        basis = curve_key(s.BasisCurve())
        return None if basis is None else (name, basis, _bytes(_xyz(s.Direction())))
    elif isinstance(s, Geom_SurfaceOfRevolution):
        basis = curve_key(s.BasisCurve())
        ax = s.Axis()
        if basis is None:
            return None
        return (name, basis, _bytes([*_xyz(ax.Location()), *_xyz(ax.Direction())]))
    elif isinstance(s, Geom_RectangularTrimmedSurface | Geom_OffsetSurface):
        basis = surface_key(s.BasisSurface())
        extra = s.Offset() if isinstance(s, Geom_OffsetSurface) else 0.0
        if basis is None:
            return None
        return (name, basis, _bytes([*s.Bounds(), extra]))
    else:
        return None
    return (name, _bytes([*nums, *s.Bounds()]))


def curve_key(c: Any) -> Key | None:
    """The key of the ``Geom_Curve`` ``c`` (None for a kind not handled)."""
    name = type(c).__name__
    nums: list[float]
    if isinstance(c, Geom_BSplineCurve):
        n = c.NbPoles()
        nums = [c.Degree(), c.IsPeriodic(), n, *_knots(c.NbKnots, c.Knot, c.Multiplicity)]
        for i in range(1, n + 1):
            nums += _xyz(c.Pole(i))
        if c.IsRational():
            nums += [c.Weight(i) for i in range(1, n + 1)]
    elif isinstance(c, Geom_BezierCurve):
        nums = [v for i in range(1, c.NbPoles() + 1) for v in (*_xyz(c.Pole(i)), c.Weight(i))]
    elif isinstance(c, Geom_Line):
        p = c.Position()
        nums = [*_xyz(p.Location()), *_xyz(p.Direction())]
    elif isinstance(c, Geom_Circle):
        nums = [*_ax3(c.Position()), c.Radius()]
    elif isinstance(c, Geom_Ellipse):
        nums = [*_ax3(c.Position()), c.MajorRadius(), c.MinorRadius()]
    elif isinstance(c, Geom_TrimmedCurve):
        basis = curve_key(c.BasisCurve())
        if basis is None:
            return None
        return (name, basis, _bytes([c.FirstParameter(), c.LastParameter()]))
    else:
        return None
    return (name, _bytes(nums))


def curve2d_key(c: Any) -> Key | None:
    """The key of the ``Geom2d_Curve`` ``c`` (None for a kind not handled)."""
    name = type(c).__name__
    nums: list[float]
    if isinstance(c, Geom2d_BSplineCurve):
        n = c.NbPoles()
        nums = [c.Degree(), c.IsPeriodic(), n, *_knots(c.NbKnots, c.Knot, c.Multiplicity)]
        for i in range(1, n + 1):
            p = c.Pole(i)
            nums += [p.X(), p.Y()]
        if c.IsRational():
            nums += [c.Weight(i) for i in range(1, n + 1)]
    elif isinstance(c, Geom2d_BezierCurve):
        nums = []
        for i in range(1, c.NbPoles() + 1):
            p = c.Pole(i)
            nums += [p.X(), p.Y(), c.Weight(i)]
    elif isinstance(c, Geom2d_Line):
        p = c.Position()
        nums = [p.Location().X(), p.Location().Y(), p.Direction().X(), p.Direction().Y()]
    elif isinstance(c, Geom2d_Circle):
        nums = [*_ax22d(c.Position()), c.Radius()]
    elif isinstance(c, Geom2d_Ellipse):
        nums = [*_ax22d(c.Position()), c.MajorRadius(), c.MinorRadius()]
    elif isinstance(c, Geom2d_TrimmedCurve):
        basis = curve2d_key(c.BasisCurve())
        if basis is None:
            return None
        return (name, basis, _bytes([c.FirstParameter(), c.LastParameter()]))
    else:
        return None
    return (name, _bytes(nums))
