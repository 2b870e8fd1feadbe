"""Which of many points in a face's parameters lie in the face, decided in numpy.

OCCT's ``IntTools_FClass2d`` answers one point per call; the validation asks it about the
feet of thousands of sample points per face (the gap measure, the deviations), a Python
loop of OCCT calls. Here each wire of the face is sampled into a polygon in ``(u, v)``
(its edges' pcurves, in the wire's order and orientation) and the points are tested
against the polygons at once (crossing number, ``matplotlib.path.Path``, even-odd over
the wires). The polygon stands for the boundary up to its chords' sag and the tolerance
(OCCT's classifier counts a point within the edges' tolerance as on the face): the points
nearer the polygon than twice the sag plus the tolerance in parameters are asked to
``IntTools_FClass2d`` one by one, as before; so are all points of a face whose polygon
does not close. The answers are OCCT's wherever the polygon could differ from it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.path import Path
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve2d, BRepAdaptor_Surface
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.GeomAbs import GeomAbs_BSplineCurve
from OCP.gp import gp_Pnt2d
from OCP.IntTools import IntTools_FClass2d
from OCP.TopAbs import TopAbs_OUT, TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from scipy.spatial import cKDTree

from medax.cad.simplify.occ import Array, uv_bounds
from medax.cad.topology import edge_uv

#: Chords per edge of the boundary polygons (more on B-splines of many spans, at most
#: ``MAX_CHORDS``).
CHORDS, MAX_CHORDS = 48, 4096
#: Samples of the boundary polygons over the diagonal of their box: a point nearer than
#: half that spacing plus the band to a sample is asked to OCCT.
SAMPLES_PER_BOX = 1000


class FaceClassifier:
    """Points ``(u, v)`` of ``face``'s surface in the face (IN or ON, as
    ``IntTools_FClass2d(face, tol)`` says; ``tol``: length), many at a time."""

    def __init__(self, face: Any, tol: float) -> None:
        self.face = face
        self.occ = IntTools_FClass2d(face, tol)
        surf = BRepAdaptor_Surface(face)
        u0, u1, v0, v1 = uv_bounds(face)
        self.start = np.array([u0, v0])
        self.period = np.array(
            [
                surf.UPeriod() if surf.IsUPeriodic() else 0.0,
                surf.VPeriod() if surf.IsVPeriodic() else 0.0,
            ]
        )
        tol_uv = max(surf.UResolution(tol), surf.VResolution(tol))
        # wider than a period: which copy of a point OCCT takes is its own affair
        wide = np.any((self.period > 0.0) & (np.array([u1 - u0, v1 - v0]) > self.period - 1e-9))
        self.loops, sag = (None, 0.0) if wide else _wire_polygons(face)
        if self.loops is not None:
            self.paths = [Path(loop, closed=True) for loop in self.loops]
            chords = np.vstack([np.stack([p[:-1], p[1:]], axis=1) for p in self.loops])
            samples, spacing = _chord_samples(chords)
            self.tree = cKDTree(samples)
            # a point within this of a sample may be within the band of a chord
            self.reach = 0.5 * spacing + 2.0 * sag + 2.0 * tol_uv

    def inside(self, uv: Array) -> NDArray[np.bool_]:
        """``uv`` (n, 2) -> (n,) True where the point is in the face or on its boundary."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        if self.loops is None:
            return self._asked(uv)
        q = self._unwrapped(uv)
        out = np.zeros(len(q), dtype=bool)
        for path in self.paths:
            out ^= path.contains_points(q, radius=0.0)
        dist, _ = self.tree.query(q, k=1, distance_upper_bound=self.reach)
        near = np.flatnonzero(np.isfinite(dist))
        if near.size:
            out[near] = self._asked(uv[near])
        return out

    def _asked(self, uv: Array) -> NDArray[np.bool_]:
        """OCCT's answer for each point of ``uv`` (n, 2), one at a time."""
        perform = self.occ.Perform
        return np.array([perform(gp_Pnt2d(u, v)) != TopAbs_OUT for u, v in uv.tolist()], bool)

    def _unwrapped(self, uv: Array) -> Array:
        """``uv`` moved by whole periods into the face's window (as OCCT's classifier
        does on periodic surfaces)."""
        out = uv.copy()
        for k in (0, 1):
            p = self.period[k]
            if p > 0.0:
                out[:, k] = self.start[k] + np.mod(out[:, k] - self.start[k], p)
        return out


def _wire_polygons(face: Any) -> tuple[list[Array] | None, float]:
    """Each wire of ``face`` as a closed polygon (m, 2) in its parameters and the largest
    sag of a chord (parameter units), or (None, 0) when a wire's pcurves do not chain (a
    gap between consecutive edges wider than a hundredth of the face's parameter box)."""
    u0, u1, v0, v1 = uv_bounds(face)
    gap_limit = 1e-2 * max(u1 - u0, v1 - v0)
    loops: list[Array] = []
    sag = 0.0
    exp = TopExp_Explorer(face, TopAbs_WIRE)
    while exp.More():
        pts: list[Array] = []
        walk = BRepTools_WireExplorer(TopoDS.Wire(exp.Current()), face)
        while walk.More():
            edge = walk.Current()
            if BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0) is None:
                return None, 0.0
            curve = BRepAdaptor_Curve2d(edge, face)
            t = np.linspace(curve.FirstParameter(), curve.LastParameter(), 2 * _chords(curve) + 1)
            if edge.Orientation() == TopAbs_REVERSED:
                t = t[::-1]
            p, _ = edge_uv(edge, face, t)
            ends, mids = p[::2], p[1::2]
            sag = max(sag, float(np.max(_point_chord(mids, ends[:-1], ends[1:]))))
            if pts and np.linalg.norm(ends[0] - pts[-1][-1]) > gap_limit:
                return None, 0.0
            pts.append(ends)
            walk.Next()
        if pts:
            loop = np.vstack(pts)
            if np.linalg.norm(loop[0] - loop[-1]) > gap_limit:
                return None, 0.0
            loops.append(np.vstack([loop, loop[:1]]))
        exp.Next()
    return (loops or None), sag


def _chords(curve: Any) -> int:
    """Chords for pcurve ``curve``: ``CHORDS``, or four per knot span of a B-spline with
    more spans (a chord's sag is measured at its middle: within one or two spans the curve
    does not turn back between), at most ``MAX_CHORDS``."""
    if curve.GetType() == GeomAbs_BSplineCurve:
        return int(min(max(CHORDS, 4 * (curve.NbKnots() - 1)), MAX_CHORDS))
    return CHORDS


def _point_chord(p: Array, a: Array, b: Array) -> Array:
    """Distances (n,) of points ``p`` (n, 2) from the segments ``a`` - ``b`` (n, 2) each."""
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.where(dd > 0.0, dd, 1.0), 0.0, 1.0)
    return np.asarray(np.linalg.norm(p - (a + t[:, None] * d), axis=1))


def _chord_samples(chords: Array) -> tuple[Array, float]:
    """Points along ``chords`` (m, 2, 2) at most a spacing apart (the diagonal of their box
    over ``SAMPLES_PER_BOX``; each chord's pieces by their midpoints) and that spacing: a
    point within ``b`` of a chord is within ``b`` plus half the spacing of a sample."""
    a, d = chords[:, 0], chords[:, 1] - chords[:, 0]
    length = np.sqrt(np.einsum("ij,ij->i", d, d))
    lo, hi = chords.reshape(-1, 2).min(axis=0), chords.reshape(-1, 2).max(axis=0)
    spacing = max(float(np.hypot(*(hi - lo))) / SAMPLES_PER_BOX, 1e-300)
    n = np.maximum(1, np.ceil(length / spacing)).astype(np.intp)
    which = np.repeat(np.arange(len(chords)), n)
    frac = (np.arange(len(which)) - np.repeat(np.cumsum(n) - n, n) + 0.5) / n[which]
    return a[which] + frac[:, None] * d[which], spacing
