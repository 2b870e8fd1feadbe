"""The area of a face on a polynomial B-spline surface by medax's own rule
(:mod:`medax.geometry.trimmed_area`: Green's theorem over its pcurves, the inner integral
split at the surface's knots), for the faces on which OCCT's adaptive integrator is slow
(fitted merged faces of hundreds of knot spans: 2 - 16 s each)."""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.Geom import Geom_BSplineSurface
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FORWARD
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from medax.cad.face_region import _pcurve, _to_bspline, bspline_embedding
from medax.geometry.trimmed_area import boundary_rule, trimmed_area


def bspline_face_area(face: Any) -> float | None:
    """Area (length squared) of ``face`` when it lies on a polynomial, non-periodic
    ``Geom_BSplineSurface`` with pcurves on every edge; None otherwise (the caller
    measures it another way)."""
    surf = BRep_Tool.Surface_s(face)
    if not isinstance(surf, Geom_BSplineSurface):
        return None
    if surf.IsURational() or surf.IsVRational() or surf.IsUPeriodic() or surf.IsVPeriodic():
        return None
    fwd = TopoDS.Face(face.Oriented(TopAbs_FORWARD))
    curves = []
    exp = TopExp_Explorer(fwd, TopAbs_EDGE)
    for e in _explored(exp):
        if BRep_Tool.CurveOnSurface_s(e, fwd, 0.0, 0.0) is None:
            return None
        curves.append(_to_bspline(_pcurve(e, fwd), 2))
    emb = bspline_embedding(surf)
    uv, w = boundary_rule(curves, emb.uknots, emb.vknots, max(emb.udeg, emb.vdeg))
    area = abs(trimmed_area(emb, uv, w))  # (a reversed face's loops all run the other way)
    return area if np.isfinite(area) else None


def _explored(exp: Any) -> Any:
    """The edges a ``TopExp_Explorer`` visits, orientation composed with the face's."""
    while exp.More():
        yield TopoDS.Edge(exp.Current())
        exp.Next()
