"""Validation of a simplified solid against the original.

- ``BRepCheck_Analyzer`` validity and the shell count (one closed shell);
- the volume, by two integrators that must agree (:func:`volumes`);
- the boundary's area (:func:`area`): a face that covers more or less of its surface than
  the faces it replaces (a pcurve off its edge between the samples the other checks take);
- the largest distance between old and new boundary surfaces, both ways: points sampled on
  the faces of one solid (a UV grid, kept inside each face by the face classifier) and their
  distance to the other solid's boundary (``BRepExtrema_DistShapeShape`` against the faces
  of the corresponding group only, so it stays cheap).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepGProp import BRepGProp
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.GProp import GProp_GProps
from OCP.IntTools import IntTools_FClass2d
from OCP.TopAbs import TopAbs_IN, TopAbs_SHELL

from medax.cad.simplify.face_classifier import FaceClassifier
from medax.cad.simplify.occ import Array, compound, count, edges_of, faces_of, uv_bounds, xyz
from medax.cad.simplify.projection import GridProjection, batch_projection

#: Relative accuracy asked of the volume integration.
VOLUME_EPS = 1e-10
#: Relative accuracy asked of the area integration (on NURBS copies of swept faces the
#: simplified catalogue parts and their radius variants, the three shared STEP parts and
#: the 64-boss grid measured within 2.0e-7 of the original's area, the noise of the copies
#: of exact revolutions: 1.4e-8 with 1e-10 asked, at up to twice the time on fitted faces;
#: as built, extruded faces were 1e-4 - 3e-3 off).
AREA_EPS = 1e-9


@dataclass(frozen=True)
class Check:
    """Validity of a solid: ``valid`` (analyzer), ``shells``, ``closed`` and ``volume``
    (Gauss-Kronrod on the faces as they are: for information; the simplifier measures the
    volume with :func:`volumes`)."""

    valid: bool
    shells: int
    closed: bool
    volume: float


def volume(shape: Any) -> float:
    """Volume of ``shape`` (length unit cubed), Gauss-Kronrod to ``VOLUME_EPS`` relative;
    the adaptive integrator where there are fitted B-spline faces (Gauss-Kronrod took 32 s
    on the six faces of the simplified 12-edge box, the adaptive one 1 s)."""
    props = GProp_GProps()
    if _has_bspline_faces(shape):
        BRepGProp.VolumeProperties_s(shape, props, VOLUME_EPS)
    else:
        BRepGProp.VolumePropertiesGK_s(shape, props, VOLUME_EPS)
    return float(props.Mass())


def default_volume(shape: Any) -> float:
    """Volume of ``shape`` by OCCT's default mass properties (``VolumeProperties`` without
    a tolerance: fixed-order Gauss along the edges and across the faces), what FreeCAD and
    CadQuery report; fast, and exact on merged faces as they are written."""
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    return float(props.Mass())


def area(shape: Any, nurbs: bool | None = None) -> float:
    """Boundary area of ``shape`` (length unit squared), to ``AREA_EPS`` relative; on a
    NURBS copy (:func:`nurbs_copy`) with ``nurbs``, by default where the shape has faces of
    extrusion or revolution (the integrator is unreliable on them as built, as for the
    volume: 8.6e-4 off on the L-bracket's extruded faces, 4e-10 on the copy)."""
    if nurbs is None:
        nurbs = _has_swept_faces(shape)
    target = nurbs_copy(shape) if nurbs else shape
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(target, props, AREA_EPS, False)
    return float(props.Mass())


def area_change(shape: Any, before: float, tol: float) -> tuple[float, str]:
    """Relative change of the boundary area of ``shape`` against ``before``: (change, "")
    when a measure finds it within ``tol`` (:func:`area`, then on the faces as built where
    that was on a NURBS copy), else (the first measure's change, reason). The integrator's
    own error is not bounded by what is asked of it (1e-7 asked left the 64-boss grid's
    exact revolved faces over 1e-6 off): a second measure guards against a false refusal,
    a real change shows in both, with its sign (a face covering more or less of its
    surface is measured so by both); two measures beyond ``tol`` of opposite signs are
    the integrators' error, and the smaller one is returned without a reason."""
    swept = _has_swept_faces(shape)
    first = (area(shape, swept) - before) / before
    if abs(first) <= tol:
        return first, ""
    if swept:
        second = (area(shape, False) - before) / before
        if abs(second) <= tol:
            return second, ""
        if second * first < 0.0:
            # the two measures beyond ``tol`` on opposite sides: their own error, not a
            # change (on a loose 325-face part +2.2e-5 on the copy, -4.5e-5 as built on
            # the changed faces, where the gaps put the volume change at 9e-11)
            return min(first, second, key=abs), ""
    return first, (
        f"boundary area changed by {first:+.2e} (> {tol:g}): a new face covers more or "
        "less of its surface than the faces it replaces"
    )


def volumes(
    shape: Any, nurbs: bool = False, eps: float = VOLUME_EPS, eps_gk: float | None = None
) -> tuple[float, float]:
    """Volume of ``shape`` by two integrators, (Gauss-Kronrod, adaptive), each to ``eps``
    relative; with ``nurbs`` on a B-spline copy (:func:`nurbs_copy`).

    On faces of extruded or revolved B-spline profiles each integrator was 0.1 - 1 % off on
    some parts (a shape change that is not there); on the NURBS copy both agreed with the
    original volume to ~1e-9 on every part tried.
    """
    return _Volumes(shape).both(nurbs, eps, eps_gk)


class _Volumes:
    """The whole-solid volume integrals of one shape (and of its NURBS copy, made once),
    each computed at most once: :func:`volume_change` asks for the adaptive integral at
    ``tol / 100`` up to three times on the same faces (on a 444-face attempt with two
    fitted faces of 350 x 188 poles, 19 s each time)."""

    def __init__(self, shape: Any) -> None:
        self.shape = shape
        self._copy: Any = None
        self._done: dict[tuple[str, bool, float], float] = {}

    def target(self, nurbs: bool) -> Any:
        """The shape, or with ``nurbs`` its B-spline copy (:func:`nurbs_copy`)."""
        if not nurbs:
            return self.shape
        if self._copy is None:
            self._copy = nurbs_copy(self.shape)
        return self._copy

    def adaptive(self, nurbs: bool, eps: float) -> float:
        """``BRepGProp.VolumeProperties`` to ``eps`` relative (per face)."""
        return self._integral(False, nurbs, eps)

    def gk(self, nurbs: bool, eps: float) -> float:
        """``BRepGProp.VolumePropertiesGK`` to ``eps`` relative."""
        return self._integral(True, nurbs, eps)

    def _integral(self, gk: bool, nurbs: bool, eps: float) -> float:
        key = ("gk" if gk else "adaptive", nurbs, eps)
        if key not in self._done:
            props = GProp_GProps()
            run = BRepGProp.VolumePropertiesGK_s if gk else BRepGProp.VolumeProperties_s
            run(self.target(nurbs), props, eps)
            self._done[key] = float(props.Mass())
        return self._done[key]

    def both(self, nurbs: bool, eps: float, eps_gk: float | None = None) -> tuple[float, float]:
        """(Gauss-Kronrod to ``eps_gk`` or ``eps``, adaptive to ``eps``), as
        :func:`volumes`."""
        return self.gk(nurbs, eps if eps_gk is None else eps_gk), self.adaptive(nurbs, eps)


def nurbs_copy(shape: Any) -> Any:
    """The faces of ``shape`` on (rational) B-spline surfaces, as a compound: what
    ``BRepBuilderAPI_NurbsConvert`` gives, face by face.

    A face on a linear extrusion (not closed in ``u``) keeps its pcurves: the exact B-spline
    of an extrusion of a B-spline profile has the extrusion's own parameters (checked at
    three points per face), so only the surface is swapped (:func:`_extrusion_copy`).
    ``BRepBuilderAPI_NurbsConvert`` re-approximates every pcurve: on the 586-face grid plate's
    260 extruded faces it took 1.8 s, the swap 0.03 s, with the same volumes (1e-16 apart).
    """
    from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
    from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_SurfaceOfExtrusion
    from OCP.TopoDS import TopoDS_Compound

    builder = BRep_Builder()
    out = TopoDS_Compound()
    builder.MakeCompound(out)
    for f in faces_of(shape):
        copy = None
        kind = BRepAdaptor_Surface(f).GetType()
        if kind == GeomAbs_BSplineSurface:
            # already a B-spline: nothing to convert (on the ring route's periodic faces
            # the conversion threw, or the process died of a floating-point exception)
            builder.Add(out, f)
            continue
        if kind == GeomAbs_SurfaceOfExtrusion:
            copy = _extrusion_copy(f)
        if copy is None:
            try:
                copy = BRepBuilderAPI_NurbsConvert(f, True).Shape()
            except Exception:  # OCCT cannot convert this face (seen on a torus piece)
                copy = f  # measured as it is: the other integrator still checks it
        builder.Add(out, copy)
    return out


def _extrusion_copy(face: Any) -> Any | None:
    """A copy of the extrusion face ``face`` on the surface's exact B-spline, its pcurves
    kept; None where that is not the same parametrisation or an edge is a seam."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
    from OCP.GeomConvert import GeomConvert
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    surf = BRep_Tool.Surface_s(face)
    try:
        bs = GeomConvert.SurfaceToBSplineSurface_s(surf)
    except Exception:  # OCCT Standard_Failure: no conversion
        return None
    u0, u1, v0, v1 = uv_bounds(face)
    for a, b in ((0.0, 0.0), (1.0, 1.0), (0.3, 0.6)):
        u, v = u0 + a * (u1 - u0), v0 + b * (v1 - v0)
        p = surf.Value(u, v)
        if p.Distance(bs.Value(u, v)) > 1e-12 * max(1.0, float(np.abs(xyz(p)).max())):
            return None
    copy = TopoDS.Face(BRepBuilderAPI_Copy(face).Shape())
    if any(BRep_Tool.IsClosed_s(TopoDS.Edge(e), copy) for e in edges_of(copy)):
        return None
    builder, loc = BRep_Builder(), TopLoc_Location()
    for e in edges_of(copy):
        edge = TopoDS.Edge(e)
        pc = BRep_Tool.CurveOnSurface_s(edge, copy, 0.0, 0.0)
        if pc is None:
            return None
        first, last = BRep_Tool.Range_s(edge, copy)
        builder.UpdateEdge(edge, pc, bs, loc, BRep_Tool.Tolerance_s(edge))
        builder.Range(edge, bs, loc, first, last)
    builder.UpdateFace(copy, bs, loc, BRep_Tool.Tolerance_s(copy))
    return copy


def volume_change(
    shape: Any, before: float, tol: float, expected: float | None = None
) -> tuple[float, str]:
    """Relative volume change of ``shape`` against ``before``: (change, "") when two
    integrators agree on it within ``tol`` (first on the faces as they are, then on a NURBS
    copy, integrated to ``tol / 100``: ~3x faster than 1e-10 there), else (their larger
    change, reason). On fitted faces ``expected`` (the relative change the fits measured
    themselves) may stand in for the slow Gauss-Kronrod second opinion.

    First the two fast ones: OCCT's default integrator (fixed-order Gauss, exact on the
    merged faces as written, see :mod:`.rebuild`) and the adaptive one; when both are within
    ``tol`` and within ``tol / 10`` of each other that is the answer (Gauss-Kronrod took
    5 s per attempt on a 12-face part), and so is a change above ``tol`` that both find to
    within a tenth of it, on a solid without faces of extrusion or revolution."""
    d_def = (default_volume(shape) - before) / before
    integrals = _Volumes(shape)  # (each integral once: the same ones are asked again below)
    d_ad = (integrals.adaptive(False, 1e-2 * tol) - before) / before
    if max(abs(d_def), abs(d_ad)) <= tol and abs(d_ad - d_def) <= 0.1 * tol:
        return d_def, ""
    bspline, swept = _has_bspline_faces(shape), _has_swept_faces(shape)
    big = max(abs(d_def), abs(d_ad))
    if not swept and min(abs(d_def), abs(d_ad)) > tol and abs(d_ad - d_def) <= 0.1 * big:
        # a refusal the two fast integrators agree on (on a 1055-face part the
        # Gauss-Kronrod second opinion took 217 s); not where faces of extrusions and
        # revolutions are, on which both were 0.1 - 1 % off
        return d_ad, f"volume changed by {abs(d_ad):.2e} (> {tol:g})"
    if bspline and expected is not None and np.isfinite(expected):
        # a second measure independent of OCCT: the fits' own signed volumes against the
        # exact heights (``expected``, relative); the adaptive integrator must agree with it
        # (on a NURBS copy when there are swept faces too: as built, the adaptive integrator
        # was 1.5e-4 off on the rounded box chain's revolved faces)
        d_ad = (integrals.adaptive(swept, 1e-2 * tol) - before) / before
        if abs(d_ad) <= tol and abs(d_ad - expected) <= 0.1 * tol:
            return d_ad, ""
    if bspline:
        # on fitted B-spline faces (many knot spans) Gauss-Kronrod to 1e-10 took 200 s on
        # six faces, to 1e-8 31 s, to 1e-6 5 s (then 2e-7 off); the adaptive integrator
        # 0.25 s to 1e-8 (agreeing with Gauss-Kronrod to 1e-8 within 4e-10)
        gk, ad = integrals.both(False, 1e-2 * tol, eps_gk=tol)
        d_gk, d_ad = (gk - before) / before, (ad - before) / before
        if max(abs(d_gk), abs(d_ad)) <= tol:
            return d_ad, ""
    # on faces of extrusions and revolutions the integrators are unreliable (see
    # :func:`volumes`): the NURBS copy first, the faces as built only when the two disagree
    # there (the 64-boss grid: Gauss-Kronrod 1.3e-4 off on the copy, both within 1e-7 on
    # the faces as built)
    for nurbs in (True, False) if swept else (False, True):
        gk, ad = integrals.both(nurbs, 1e-2 * tol if nurbs else VOLUME_EPS)
        d_gk, d_ad = (gk - before) / before, (ad - before) / before
        if max(abs(d_gk), abs(d_ad)) <= tol:
            return d_gk, ""
    if abs(d_gk - d_ad) > tol:
        return max(
            d_gk, d_ad, key=abs
        ), f"volume uncertain: two integrators differ by {abs(d_gk - d_ad):.1e}"
    return max(
        d_gk, d_ad, key=abs
    ), f"volume changed by {max(abs(d_gk), abs(d_ad)):.2e} (> {tol:g})"


#: A B-spline face with more knot spans than this is "fitted" for the choice of integrators.
FEW_SPANS = 16


def _has_bspline_faces(shape: Any) -> bool:
    """Whether ``shape`` has a face on a B-spline surface of many knot spans (the fitted
    merged faces, or freeform faces of the input), where Gauss-Kronrod is slow. The exact
    B-splines of extrusions (one span along the extrusion) are not counted."""
    from OCP.GeomAbs import GeomAbs_BSplineSurface

    for f in faces_of(shape):
        ad = BRepAdaptor_Surface(f)
        if ad.GetType() != GeomAbs_BSplineSurface:
            continue
        b = ad.BSpline()
        if (b.NbUKnots() - 1) * (b.NbVKnots() - 1) > FEW_SPANS:
            return True
    return False


def _has_swept_faces(shape: Any) -> bool:
    """Whether ``shape`` has a face on a surface of linear extrusion or of revolution."""
    from OCP.GeomAbs import GeomAbs_SurfaceOfExtrusion, GeomAbs_SurfaceOfRevolution

    swept = (GeomAbs_SurfaceOfExtrusion, GeomAbs_SurfaceOfRevolution)
    return any(BRepAdaptor_Surface(f).GetType() in swept for f in faces_of(shape))


def check(shape: Any, with_volume: bool = True) -> Check:
    """Analyzer validity, number of shells, closedness (no free edges) and volume (NaN
    without ``with_volume``: the simplifier measures it separately, with two integrators)."""
    from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
    from OCP.TopAbs import TopAbs_EDGE

    valid = bool(BRepCheck_Analyzer(shape).IsValid())
    shells = count(shape, TopAbs_SHELL)
    fb = ShapeAnalysis_FreeBounds(shape)
    closed = (
        count(fb.GetClosedWires(), TopAbs_EDGE) == 0 and count(fb.GetOpenWires(), TopAbs_EDGE) == 0
    )
    return Check(valid, shells, closed, volume(shape) if with_volume else float("nan"))


def free_edge_faces(shape: Any) -> list[Any]:
    """The faces of ``shape`` that have an edge no other face shares (excluding seams and
    degenerated edges)."""
    from OCP.TopoDS import TopoDS

    from medax.cad.simplify.specs import edge_face_map

    m = edge_face_map(shape)
    out: list[Any] = []
    for i in range(1, m.Extent() + 1):
        edge = TopoDS.Edge(m.FindKey(i))
        owners = list(m.FindFromIndex(i))
        if len(owners) == 1 and not BRep_Tool.Degenerated_s(edge):
            face = TopoDS.Face(owners[0])
            if not BRep_Tool.IsClosed_s(edge, face):
                out.append(face)
    return out


def face_samples(face: Any, n: int = 12) -> Array:
    """Points inside ``face`` on an ``n x n`` UV grid (k, 3), k <= n*n."""
    u0, u1, v0, v1 = uv_bounds(face)
    surf = BRepAdaptor_Surface(face)
    cls = IntTools_FClass2d(face, 1e-9)
    us = u0 + (u1 - u0) * (np.arange(n) + 0.5) / n
    vs = v0 + (v1 - v0) * (np.arange(n) + 0.5) / n
    out = []
    for u in us.tolist():
        for v in vs.tolist():
            if cls.Perform(gp_Pnt2d(u, v)) == TopAbs_IN:
                p = surf.Value(u, v)
                out.append((p.X(), p.Y(), p.Z()))
    return np.array(out, dtype=np.float64).reshape(-1, 3)


def _edge_tolerance(face: Any) -> float:
    """The largest tolerance of ``face``'s edges (at least 1e-9): feet on a boundary edge
    then count as on the face from both sides, whatever its two pcurves' small errors."""

    return max([1e-9] + [BRep_Tool.Tolerance_s(e) for e in edges_of(face)])


def max_distance(points: Array, faces: Sequence[Any], enough: float = 0.0) -> float:
    """Largest distance from ``points`` (n, 3) to the union of ``faces``.

    Each point is projected on each face's surface: all points at once in numpy on planes,
    cylinders and extrusions (:func:`.projection.batch_projection`), else one by one
    (``GeomAPI_ProjectPointOnSurf``; from a grid start on B-spline surfaces:
    :class:`.projection.GridProjection`); a foot inside the face (to the face's edge
    tolerance, :class:`.face_classifier.FaceClassifier`: all feet at once) gives the
    distance. A point with no foot inside any face, or whose nearest foot is farther than
    ``enough`` and 1e-6 of the points' extent (a foot exactly on a shared edge may be OUT of
    both faces there, so only a far face answers), is measured exactly with
    ``BRepExtrema_DistShapeShape`` against all ``faces``, the farthest first, until no point
    left can raise the maximum (their bounds are no more than a distance measured: the same
    result as measuring them all). A point whose distance to some face is ``<= enough`` is
    not tried on the later faces (the result is then an upper bound, exact whenever it is
    above ``enough``).
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    best = np.full(len(points), np.inf)
    for f in faces:
        rows = np.flatnonzero(best > enough)
        if rows.size == 0:
            break
        uv, dist = _project(f, points[rows])
        closer = np.flatnonzero(dist < best[rows])
        if closer.size:
            closer = closer[FaceClassifier(f, _edge_tolerance(f)).inside(uv[closer])]
            best[rows[closer]] = dist[closer]
    extent = float(np.ptp(points, axis=0).max()) if len(points) else 0.0
    confirm = max(enough, 1e-6 * extent)
    far = np.flatnonzero(best > confirm)
    if far.size:
        target = compound(faces)
        # the largest first: once a point's bound is no more than a distance measured, the
        # rest cannot change the maximum (the same value; a fitted face's 144 samples
        # further than ``enough`` took ~4 s of BRepExtrema each time)
        done = -np.inf
        for r in far[np.argsort(-best[far], kind="stable")].tolist():
            if best[r] <= done:
                break
            v = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, points[r]))).Vertex()
            d = BRepExtrema_DistShapeShape(v, target)
            if not d.IsDone():
                return float("inf")
            best[r] = min(best[r], float(d.Value()))
            done = max(done, best[r])
    return float(best.max()) if len(best) else 0.0


def _project(face: Any, points: Array) -> tuple[Array, Array]:
    """Foot parameters (n, 2) and distances (n,) of ``points`` (n, 3) on ``face``'s
    surface (``inf`` where a projection finds no foot)."""
    batch = batch_projection(face)
    if batch is not None:
        return batch(points)
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf

    surf = BRep_Tool.Surface_s(face)
    u0, u1, v0, v1 = uv_bounds(face)
    du, dv = 0.1 * (u1 - u0), 0.1 * (v1 - v0)
    wide = (u0 - du, u1 + du, v0 - dv, v1 + dv)
    grid = GridProjection.of(surf, wide)
    if grid is not None:
        return grid.project_many(points)
    proj = GeomAPI_ProjectPointOnSurf()
    proj.Init(surf, *wide)
    uv = np.zeros((len(points), 2))
    dist = np.full(len(points), np.inf)
    for i, p in enumerate(points):
        proj.Perform(gp_Pnt(*map(float, p)))
        if proj.NbPoints():
            uv[i] = proj.LowerDistanceParameters()
            dist[i] = float(proj.LowerDistance())
    return uv, dist


def deviation(
    old_faces: Sequence[Any], new_face: Any, n: int = 8, enough: float = 0.0
) -> tuple[float, float]:
    """(old -> new, new -> old) largest distances between ``old_faces`` and ``new_face``,
    from ``n x n`` samples per face (``enough``: see :func:`max_distance`)."""
    old_pts = np.vstack([face_samples(f, n) for f in old_faces])
    new_pts = face_samples(new_face, n)
    return max_distance(old_pts, [new_face]), max_distance(new_pts, old_faces, enough)
