"""The area of a face on a polynomial B-spline surface by medax's own rule
(:mod:`medax.geometry.trimmed_area`: Green's theorem over its pcurves, the inner integral
split at the surface's knots), for the faces on which OCCT's adaptive integrator is slow
(fitted merged faces of hundreds of knot spans: 2 - 16 s each)."""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.Geom import Geom_BSplineSurface
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FORWARD, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from medax.cad.face_region import _pcurve, _to_bspline, bspline_embedding
from medax.geometry.curve import Curve
from medax.geometry.line import Line
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
    curves: list[Curve] = []
    wires = TopExp_Explorer(fwd, TopAbs_WIRE)
    while wires.More():
        loop = _loop(fwd, TopoDS.Wire(wires.Current()))
        if loop is None:
            return None
        curves += loop
        wires.Next()
    emb = bspline_embedding(surf)
    uv, w = boundary_rule(curves, emb.uknots, emb.vknots, max(emb.udeg, emb.vdeg))
    area = abs(trimmed_area(emb, uv, w))  # (a reversed face's loops all run the other way)
    return area if np.isfinite(area) else None


def _loop(face: Any, wire: Any) -> list[Curve] | None:
    """The pcurves of ``wire`` on ``face`` in travel order (numpy copies), with a straight
    piece across each gap between one's end and the next one's start: a loose input's
    pcurves miss each other by up to its tolerances (3e-5 of the parameter range seen),
    and Green's theorem needs a closed loop (else the area depends on the direction of
    integration: 4e-7 of a face's area). None when an edge has no pcurve, or the wire's
    edges do not chain (the explorer does not reach them all)."""
    out: list[Curve] = []
    exp = BRepTools_WireExplorer(wire, face)
    while exp.More():
        e = exp.Current()
        exp.Next()
        if BRep_Tool.CurveOnSurface_s(e, face, 0.0, 0.0) is None:
            return None
        out.append(_to_bspline(_pcurve(e, face), 2))
    every = TopExp_Explorer(wire, TopAbs_EDGE)
    n = 0
    while every.More():
        n += 1
        every.Next()
    if n != len(out) or not out:
        return None
    ends = [(c.evaluate(np.array([0.0]))[0], c.evaluate(np.array([1.0]))[0]) for c in out]
    closed: list[Curve] = []
    for i, c in enumerate(out):
        closed.append(c)
        a, b = ends[i][1], ends[(i + 1) % len(out)][0]
        if np.any(a != b):
            closed.append(Line(a, b))
    return closed


def pcurve_gap(face: Any) -> float:
    """Largest distance (parameter units) between the end of one pcurve of ``face`` and the
    start of the next along its wires: 0 where they meet, as Green's theorem (and OCCT's
    area integrator, which integrates along the pcurves) assume; NaN when a wire's edges
    do not chain."""
    fwd = TopoDS.Face(face.Oriented(TopAbs_FORWARD))
    worst = 0.0
    wires = TopExp_Explorer(fwd, TopAbs_WIRE)
    while wires.More():
        loop = _loop(fwd, TopoDS.Wire(wires.Current()))
        wires.Next()
        if loop is None:
            return float("nan")
        for c in loop:
            if isinstance(c, Line):  # the straight pieces close the gaps
                worst = max(worst, float(np.linalg.norm(c.b - c.a)))
    return worst
