"""The medial curve of a fillet whose smooth edges are no iso-lines of its surface.

A fillet trimmed by a slanted face, or a torus fillet whose smooth edges wind across its
parameter lines, has no iso-line half-way between its smooth edges. Its medial curve is then
the paper's: the curve equidistant (in space) from the two smooth edges, traced across the
face from one cross edge to the other by :func:`medax.axis.trace_axis` on the fillet's
region (its pcurves, its surface, its exact edge curves; :func:`.face_region.side_region`).
The axis comes as a B-spline in the face's parameters; it becomes the edge's pcurve, and
OCCT builds the 3-D curve on the surface from it. The edge's equidistance is measured
again with OCCT's distances (``BRepExtrema``), independently of the tracer's own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepLib import BRepLib

from medax import tolerances
from medax.cad.face_region import side_region, smooth_cross_sides
from medax.cad.simplify.occ import compound, edge_points, pnt
from medax.cad.simplify.traced import geom_bspline
from medax.errors import MedaxError

#: Samples of the built edge at which its equidistance is measured by OCCT.
CHECK_SAMPLES = 21
#: The axis is traced to this share of the accepted equidistance error (its B-spline's
#: error adds the 3-D curve's approximation on the surface).
TRACE_SHARE = 0.1


def axis_medial_edge(
    face: Any, smooth0: Sequence[Any], smooth1: Sequence[Any], accept: float
) -> tuple[Any, float, float] | str:
    """The medial edge of the fillet ``face`` between its smooth sides ``smooth0`` and
    ``smooth1`` (lists of edges), from one cross edge to the other: (edge with its 3-D
    curve and its pcurve on ``face``, largest ``|d1 - d2|`` measured on it, smallest
    distance to a smooth side; lengths), or the reason when it cannot be traced or its
    error is above ``accept`` (length unit)."""
    try:
        sides = smooth_cross_sides(face, smooth0, smooth1, "fillet")
        region, _ = side_region(face, sides, "fillet")
        rel = max(TRACE_SHARE * accept / region.diagonal, tolerances.MIN_CURVE_TOL)
        axis = _trace_axis_quietly(region, rel)
    except MedaxError as why:
        return f"medial axis not traced ({why})"
    except Exception as why:  # a region the tracer was not built for: keep the fillet
        return f"medial axis not traced ({type(why).__name__}: {why})"
    spline = axis.spline
    if spline.weights is not None:
        return "medial axis not traced (a rational axis spline)"
    pcurve = geom_bspline(spline.knots, spline.control_points, spline.degree)
    surf = BRep_Tool.Surface_s(face)
    t0, t1 = float(spline.knots[0]), float(spline.knots[-1])
    mk = BRepBuilderAPI_MakeEdge(pcurve, surf, t0, t1)
    if not mk.IsDone():
        return "could not build the medial edge from the traced axis"
    edge = mk.Edge()
    if not BRepLib.BuildCurves3d_s(edge, 1e-2 * accept):
        return "could not build the medial edge's 3-D curve on the fillet surface"
    err, near = _equidistance(edge, compound(list(smooth0)), compound(list(smooth1)))
    if err > accept:
        return f"traced medial axis not equidistant ({err:.2e} > {accept:.2e})"
    return edge, err, near


def _trace_axis_quietly(region: Any, rel: float) -> Any:
    """:func:`medax.axis.trace_axis` of ``region``'s pair (0, 2) to ``rel`` x diagonal,
    its warning (a fit slightly above ``rel``) silenced: the edge is measured after."""
    import logging

    from medax.axis import trace_axis

    logger = logging.getLogger("medax.axis.medial")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        return trace_axis(region, pair=(0, 2), tol=rel)
    finally:
        logger.setLevel(level)


def _equidistance(edge: Any, side0: Any, side1: Any) -> tuple[float, float]:
    """Largest ``|d1 - d2|`` and smallest distance from points of ``edge`` to ``side0``
    and ``side1`` (shapes), by OCCT, at ``CHECK_SAMPLES`` points inside its ends (an end
    lies on a cross edge, where the nearest point of a smooth side may be its end)."""
    pts = edge_points(edge, CHECK_SAMPLES + 2)[1:-1]
    err, near = 0.0, np.inf
    for p in pts:
        v = BRepBuilderAPI_MakeVertex(pnt(p)).Vertex()
        d = [BRepExtrema_DistShapeShape(v, s).Value() for s in (side0, side1)]
        err, near = max(err, abs(d[0] - d[1])), min(near, *d)
    return float(err), float(near)
