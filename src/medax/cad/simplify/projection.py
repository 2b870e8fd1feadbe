"""Fast orthogonal projection of many points onto one large B-spline surface.

``GeomAPI_ProjectPointOnSurf`` searches the whole surface for every point: on a fitted
merged face (a cubic B-spline with 100 - 200 poles each way) that costs 2 - 20 ms per point,
which made the deviation check and the pcurve fits the slowest steps of a simplification.
Here the surface is sampled once on a grid (one sample per knot span at least, evaluated
by its numpy copy, in a k-d tree); each point starts from its nearest sample and is refined
locally by OCCT (``ShapeAnalysis_Surface.NextValueOfUV``), about 10 microseconds per point.
A local refinement can only stop at a foot no nearer than the true one, so distances are
never underestimated.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from scipy.spatial import cKDTree

from medax.cad.face_region import bspline_embedding
from medax.cad.simplify.occ import Array

#: Grid samples per direction: at least MIN_SAMPLES, one per knot span, at most MAX_SAMPLES.
MIN_SAMPLES, MAX_SAMPLES = 40, 240


class GridProjection:
    """Projection onto a non-periodic ``Geom_BSplineSurface`` over ``[u0, u1] x [v0, v1]``
    with ``GeomAPI_ProjectPointOnSurf``'s calls (``Perform``, ``NbPoints``,
    ``LowerDistanceParameters``, ``LowerDistance``)."""

    def __init__(self, surf: Any, bounds: tuple[float, float, float, float]) -> None:
        u0, u1, v0, v1 = bounds
        nu = int(np.clip(surf.NbUKnots() * 2, MIN_SAMPLES, MAX_SAMPLES))
        nv = int(np.clip(surf.NbVKnots() * 2, MIN_SAMPLES, MAX_SAMPLES))
        self.us, self.vs = np.linspace(u0, u1, nu), np.linspace(v0, v1, nv)
        gu, gv = np.meshgrid(self.us, self.vs, indexing="ij")
        grid = bspline_embedding(surf).evaluate(np.column_stack([gu.ravel(), gv.ravel()]))
        self.nv = nv
        self.tree = cKDTree(grid)
        self.sas = ShapeAnalysis_Surface(surf)
        self.uv, self.dist = (0.0, 0.0), 0.0

    @classmethod
    def of(cls, surf: Any, bounds: tuple[float, float, float, float]) -> GridProjection | None:
        """The projection for a non-periodic B-spline surface, else None."""
        from OCP.Geom import Geom_BSplineSurface

        if not isinstance(surf, Geom_BSplineSurface) or surf.IsUPeriodic() or surf.IsVPeriodic():
            return None
        return cls(surf, bounds)

    def project(self, p: Array) -> tuple[tuple[float, float], float]:
        """Foot parameters and distance of point ``p`` (3,)."""
        _, k = self.tree.query(p)
        start = gp_Pnt2d(float(self.us[k // self.nv]), float(self.vs[k % self.nv]))
        uv = self.sas.NextValueOfUV(start, gp_Pnt(*map(float, p)), 1e-12, -1.0)
        return (float(uv.X()), float(uv.Y())), float(self.sas.Gap())

    def Perform(self, point: Any) -> None:  # noqa: N802 - GeomAPI's spelling
        self.uv, self.dist = self.project(np.array([point.X(), point.Y(), point.Z()]))

    def NbPoints(self) -> int:  # noqa: N802
        return 1

    def LowerDistanceParameters(self) -> tuple[float, float]:  # noqa: N802
        return self.uv

    def LowerDistance(self) -> float:  # noqa: N802
        return self.dist
