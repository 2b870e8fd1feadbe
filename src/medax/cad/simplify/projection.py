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

from collections.abc import Callable
from typing import Any

import numpy as np
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from scipy.spatial import cKDTree

from medax.cad.face_region import bspline_embedding
from medax.cad.simplify.occ import Array, xyz
from medax.geometry.tensor_fit import greville

#: Grid samples per direction: at least MIN_SAMPLES, one per knot span, at most MAX_SAMPLES.
MIN_SAMPLES, MAX_SAMPLES = 40, 240


class GridProjection:
    """Projection onto a ``Geom_BSplineSurface`` over ``[u0, u1] x [v0, v1]`` (the grid of
    a periodic one sampled on its non-periodic copy, the same geometry and parameters)
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
        """The projection for a B-spline surface, else None."""
        from OCP.Geom import Geom_BSplineSurface

        if not isinstance(surf, Geom_BSplineSurface):
            return None
        return cls(surf, bounds)

    def project(self, p: Array) -> tuple[tuple[float, float], float]:
        """Foot parameters and distance of point ``p`` (3,)."""
        uv, dist = self.project_many(np.asarray(p, dtype=np.float64)[None])
        return (float(uv[0, 0]), float(uv[0, 1])), float(dist[0])

    def project_many(self, points: Array) -> tuple[Array, Array]:
        """Foot parameters (n, 2) and distances (n,) of ``points`` (n, 3): the starts from
        one k-d tree query, then OCCT's local refinement point by point."""
        _, ks = self.tree.query(points)
        uv = np.empty((len(points), 2))
        dist = np.empty(len(points))
        for i, (p, k) in enumerate(zip(points, ks, strict=True)):
            start = gp_Pnt2d(float(self.us[k // self.nv]), float(self.vs[k % self.nv]))
            q = self.sas.NextValueOfUV(start, gp_Pnt(*map(float, p)), 1e-12, -1.0)
            uv[i] = q.X(), q.Y()
            dist[i] = self.sas.Gap()
        return uv, dist

    def project_near(
        self, p: Array, start: tuple[float, float], accept: float
    ) -> tuple[tuple[float, float], float]:
        """Foot parameters and distance of ``p`` (3,) from the grid's nearest sample; when
        that foot is farther than ``accept``, also refined from ``start`` (a neighbour's
        foot, when points follow a curve: the grid's nearest sample can lie on another part
        of the surface near in space, and its foot there), the nearer kept."""
        grid = self.project(p)
        if grid[1] <= accept:
            return grid
        q = self.sas.NextValueOfUV(gp_Pnt2d(*start), gp_Pnt(*map(float, p)), 1e-12, -1.0)
        near = (q.X(), q.Y()), float(self.sas.Gap())
        return near if near[1] < grid[1] else grid

    def Perform(self, point: Any) -> None:  # noqa: N802 - GeomAPI's spelling
        self.uv, self.dist = self.project(np.array([point.X(), point.Y(), point.Z()]))

    def NbPoints(self) -> int:  # noqa: N802
        return 1

    def LowerDistanceParameters(self) -> tuple[float, float]:  # noqa: N802
        return self.uv

    def LowerDistance(self) -> float:  # noqa: N802
        return self.dist


def batch_projection(face: Any) -> Callable[[Array], tuple[Array, Array]] | None:
    """Orthogonal projection of many points at once onto the surface of ``face``, in numpy,
    where it has a closed form or a numpy curve: planes, cylinders and linear extrusions
    of a B-spline profile normal to the direction (the merged faces). Returns a function
    ``points (n, 3) -> (uv (n, 2), distance (n,))`` in OCCT's parameters of the surface
    (cylinder angles within pi of the face's middle ``u``), or None for other surfaces.

    The deviation check projects thousands of points per face group; one OCCT call per
    point and face (``GeomAPI_ProjectPointOnSurf`` or the profile projection) cost
    30 us each, 1.4 s of the 586-face grid plate's 8 s.
    """
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane

    ad = BRepAdaptor_Surface(face)
    kind = ad.GetType()
    if kind == GeomAbs_Plane:
        ax = ad.Plane().Position()
        o, x, y, n = _frame(ax)

        def plane(p: Array) -> tuple[Array, Array]:
            r = p - o
            return np.column_stack((r @ x, r @ y)), np.abs(r @ n)

        return plane
    if kind == GeomAbs_Cylinder:
        cyl = ad.Cylinder()
        ax, radius = cyl.Position(), cyl.Radius()
        o, x, y, a = _frame(ax)
        mid = 0.5 * (ad.FirstUParameter() + ad.LastUParameter())

        def cylinder(p: Array) -> tuple[Array, Array]:
            r = p - o
            v = r @ a
            u = np.arctan2(r @ y, r @ x)
            u = mid + np.mod(u - mid + np.pi, 2.0 * np.pi) - np.pi
            rho = np.linalg.norm(r - np.outer(v, a), axis=1)
            return np.column_stack((u, v)), np.abs(rho - radius)

        return cylinder
    return _extrusion_projection(BRep_Tool.Surface_s(face))


def _frame(ax: Any) -> tuple[Array, Array, Array, Array]:
    """Origin, x, y and main direction (3,) each of a ``gp_Ax3``."""
    return xyz(ax.Location()), xyz(ax.XDirection()), xyz(ax.YDirection()), xyz(ax.Direction())


def _extrusion_projection(surf: Any) -> Callable[[Array], tuple[Array, Array]] | None:
    """:func:`batch_projection` for a linear extrusion of a B-spline profile in a plane
    normal to its direction: a (trimmed) ``Geom_SurfaceOfLinearExtrusion`` (profile in
    ``u``) or its exact B-spline with the straight direction in ``u``
    (:func:`.surfaces.extruded_bspline`, the merged faces). The points are moved along ``d``
    into the profile's plane and their global closest points on the profile found
    (:meth:`medax.geometry.curve.Curve.closest`)."""
    from OCP.Geom import Geom_RectangularTrimmedSurface

    from medax.cad.face_region import curve_copy

    if isinstance(surf, Geom_RectangularTrimmedSurface):
        surf = surf.BasisSurface()
    found = extrusion_parts(surf)
    if found is None:
        return None
    bc, d, along_u = found
    curve = curve_copy(bc)
    k0, k1 = bc.FirstParameter(), bc.LastParameter()
    ends = curve.evaluate(np.array([0.0, 0.5, 1.0]))
    if np.max(np.abs((ends - ends[0]) @ d)) > 1e-12 * max(1.0, float(np.abs(ends).max())):
        return None  # the profile is not in a plane normal to d
    c0 = ends[0]

    def extrusion(p: Array) -> tuple[Array, Array]:
        q = p - np.outer((p - c0) @ d, d)
        c = curve.closest(q)
        a = (p - c.foot) @ d
        t = k0 + c.t * (k1 - k0)
        return np.column_stack((a, t) if along_u else (t, a)), c.distance

    return extrusion


def extrusion_parts(surf: Any) -> tuple[Any, Array, bool] | None:
    """(profile ``Geom_BSplineCurve`` at offset 0, unit direction (3,), whether the straight
    direction is ``u``) of a linear extrusion surface, or None."""
    from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface, Geom_SurfaceOfLinearExtrusion
    from OCP.gp import gp_Vec

    if isinstance(surf, Geom_SurfaceOfLinearExtrusion):
        bc = surf.BasisCurve()
        if not isinstance(bc, Geom_BSplineCurve):
            return None
        return bc, xyz(surf.Direction()), False
    if not isinstance(surf, Geom_BSplineSurface) or surf.UDegree() != 1 or surf.NbUPoles() != 2:
        return None
    if surf.IsUPeriodic() or surf.IsVPeriodic() or surf.NbUKnots() != 2:
        return None
    a0, a1 = surf.UKnot(1), surf.UKnot(2)
    n = surf.NbVPoles()
    rows = np.array([[xyz(surf.Pole(i, j)) for j in range(1, n + 1)] for i in (1, 2)])
    step = rows[1] - rows[0]
    scale = max(1.0, float(np.abs(rows).max()))
    if np.abs(step - step[0]).max() > 1e-12 * scale or a1 <= a0:
        return None
    if any(surf.Weight(1, j) != surf.Weight(2, j) for j in range(1, n + 1)):
        return None
    d = step[0] / (a1 - a0)
    if abs(float(np.linalg.norm(d)) - 1.0) > 1e-12:
        return None
    iso = surf.UIso(a0)
    bc = Geom_BSplineCurve.DownCast(iso) if not isinstance(iso, Geom_BSplineCurve) else iso
    if bc is None:
        return None
    bc = bc.Translated(gp_Vec(*map(float, -a0 * d)))
    return bc, d, True


#: Largest relative residual of a surface's poles off ``A + u X + v Y + c N`` for it to be
#: taken as a graph over its parameter plane (the fitted merged faces: 1e-15 measured).
GRAPH_RTOL = 1e-12


def graph_frame(surf: Any) -> tuple[Array, Array] | None:
    """``(a, m)`` such that a point ``p`` (3,) of ``surf`` has the parameters ``m @ (p - a)``
    ((2, 3) @ (3,)), when ``surf`` is a polynomial B-spline surface that is a graph over its
    parameter plane: ``S(u, v) = a + u X + v Y + c(u, v) N`` for fixed vectors ``X``, ``Y``,
    ``N`` (the fitted merged faces: poles at the Greville abscissae of their knots, heights
    along the plane's normal). Then the projection along ``N`` is the surface's inverse,
    exact and affine. None for any other surface."""
    from OCP.Geom import Geom_BSplineSurface

    if not isinstance(surf, Geom_BSplineSurface) or surf.IsURational() or surf.IsVRational():
        return None
    if surf.IsUPeriodic() or surf.IsVPeriodic():
        return None
    emb = bspline_embedding(surf)
    gu, gv = greville(emb.uknots, emb.udeg), greville(emb.vknots, emb.vdeg)
    u, v = np.meshgrid(gu, gv, indexing="ij")
    design = np.column_stack([np.ones(u.size), u.ravel(), v.ravel()])
    poles = emb.poles.reshape(-1, 3)
    coef, *_ = np.linalg.lstsq(design, poles, rcond=None)
    rest = poles - design @ coef
    _, sv, vt = np.linalg.svd(rest, full_matrices=False)
    limit = GRAPH_RTOL * float(np.abs(poles - poles.mean(axis=0)).max()) * np.sqrt(len(poles))
    if not sv[1] <= limit:  # the residuals are no multiples of one direction: no graph
        return None
    a, x, y = coef
    n = vt[0] if sv[0] > limit else np.cross(x, y)  # (a plane: any direction off it)
    basis = np.column_stack([x, y, n])
    if abs(np.linalg.det(basis)) <= 1e-9 * float(np.prod(np.linalg.norm(basis, axis=0))):
        return None
    return a, np.linalg.inv(basis)[:2]
