"""gmsh's transfinite quad mesh of a planar region, the peer the random-region test and
``benchmarks/bench_regions.py`` compare with: the same exact sides (lines, circle arcs,
the same polynomial B-splines; other curves through 401 samples), the same boundary counts,
transfinite surface + recombine, optionally ``Mesh.Smoothing``."""

from __future__ import annotations

from typing import Any

import numpy as np

from medax.geometry._types import FloatArray, IntArray
from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve
from medax.geometry.line import Line
from medax.geometry.region import Region
from medax.mesh.gmsh_session import gmsh_session


def gmsh_curve(gmsh: Any, side: Curve, p0: int, p1: int) -> int:
    """The gmsh OCC curve (its tag) of ``side`` between the point tags ``p0`` and ``p1``:
    exact for lines, arcs and polynomial B-splines, else a spline through 401 samples."""
    occ = gmsh.model.occ
    if isinstance(side, Line):
        return int(occ.addLine(p0, p1))
    if isinstance(side, Arc):
        c = occ.addPoint(*side.center, 0.0)
        return int(occ.addCircleArc(p0, c, p1))
    if isinstance(side, BSpline) and side.weights is None:
        ctrl = side.control_points
        tags = [p0] + [occ.addPoint(x, y, 0.0) for x, y in ctrl[1:-1]] + [p1]
        knots, mult = np.unique(side.knots, return_counts=True)
        return int(
            occ.addBSpline(
                tags, degree=side.degree, knots=knots.tolist(), multiplicities=mult.tolist()
            )
        )
    pts = side.sample(401)  # polylines and others: a spline through dense samples
    tags = [p0] + [occ.addPoint(x, y, 0.0) for x, y in pts[1:-1]] + [p1]
    return int(occ.addSpline(tags))


def gmsh_transfinite(
    region: Region, n1: int, n2: int, smoothing: int = 0
) -> tuple[FloatArray, IntArray]:
    """gmsh transfinite + recombine of the planar ``region`` with ``n1`` divisions on S0 and
    S2, ``n2`` on S1 and S3: nodes (n, 2) and quads (m, 4), counter-clockwise (gmsh's own
    orientation flipped when its normal points to -z)."""
    with gmsh_session() as gmsh:
        gmsh.model.add("medax-tfi")
        try:
            occ = gmsh.model.occ
            corners = [occ.addPoint(x, y, 0.0) for x, y in region.corners]
            curves = [
                gmsh_curve(gmsh, region.sides[k], corners[k], corners[(k + 1) % 4])
                for k in range(4)
            ]
            surf = occ.addPlaneSurface([occ.addCurveLoop(curves)])
            occ.synchronize()
            for k, c in enumerate(curves):
                gmsh.model.mesh.setTransfiniteCurve(c, (n1 if k % 2 == 0 else n2) + 1)
            gmsh.model.mesh.setTransfiniteSurface(surf, cornerTags=corners)
            gmsh.model.mesh.setRecombine(2, surf)
            gmsh.option.setNumber("Mesh.Smoothing", smoothing)
            gmsh.model.mesh.generate(2)
            tags, xyz, _ = gmsh.model.mesh.getNodes()
            etypes, _, enodes = gmsh.model.mesh.getElements(2)
        finally:
            gmsh.model.remove()
    pts = np.zeros((int(tags.max()) + 1, 2))
    pts[tags.astype(np.int64)] = xyz.reshape(-1, 3)[:, :2]
    quads = np.asarray(enodes[list(etypes).index(3)], dtype=np.int64).reshape(-1, 4)
    p = pts[quads]
    area = np.sum(p[..., 0] * np.roll(p[..., 1], -1, 1) - np.roll(p[..., 0], -1, 1) * p[..., 1], 1)
    return pts, (quads[:, ::-1] if np.median(area) < 0 else quads)


__all__ = ["gmsh_transfinite"]
