"""Read a written solid back and compare it with the solid that was validated.

A STEP or IGES file stores each edge's 3D curve and pcurves separately; a reader may rebuild
one from the other, so an input whose edges carry large tolerances (the 3D curve and the
pcurve apart by up to that much) can come back moved within them: the corpus's pulley changes
three faces' areas by up to 1.6e-3 (volume 8.0e-6) through a STEP round trip of the input
alone. The simplifier validates the solid in memory; this check makes the same promise about
the file: as read by OCCT's plain reader (no healing, as a CAD system reads it), it holds as
many solids and faces, is valid, and no face, inside or along its boundary, moves by more than
the allowed distance ``max(deviation tolerance, 2 x the largest edge or vertex tolerance of
the solid)``. An edge's two pcurves may each lie up to its tolerance from its 3D curve, so a
reader that rebuilds one from the others can move a boundary by twice that; a file cannot be
held to less than the tolerance its own geometry carries.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve2d, BRepAdaptor_Surface
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.TopAbs import TopAbs_EDGE, TopAbs_SOLID, TopAbs_VERTEX
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from scipy.spatial import cKDTree

from medax._progress import log_progress
from medax.cad.simplify.occ import Array, count, edges_of, faces_of, xyz
from medax.cad.simplify.validate import default_volume, face_samples, max_distance
from medax.errors import CadError

log = logging.getLogger(__name__)

#: samples per face (n x n UV grid, kept inside the face)
SAMPLES = 5
#: boundary points per edge (each face's boundary polyline)
BOUNDARY_DENSE = 49
#: every STRIDE-th boundary point is measured against the other face's polyline
STRIDE = 4


@dataclass(frozen=True)
class ReadBack:
    """What the written file holds against the validated solid.

    ``max_deviation`` and ``allowed`` in the model's length unit; ``volume_rel_change``
    relative to the validated solid's, both by OCCT's default integrator (what FreeCAD and
    CadQuery show; for information: the distances decide).
    """

    solids: int
    faces: int
    valid: bool
    max_deviation: float
    allowed: float
    volume_rel_change: float

    def report(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "solids": self.solids,
            "faces": self.faces,
            "valid": self.valid,
            "max_deviation": self.max_deviation,
            "allowed_deviation": self.allowed,
            "default_integrator_volume_rel_change": self.volume_rel_change,
        }


def shape_tolerance(shape: Any) -> float:
    """The largest edge or vertex tolerance of ``shape`` (length unit)."""
    worst = 0.0
    for kind, cast, tol in (
        (TopAbs_EDGE, TopoDS.Edge, BRep_Tool.Tolerance_s),
        (TopAbs_VERTEX, TopoDS.Vertex, BRep_Tool.Tolerance_s),
    ):
        exp = TopExp_Explorer(shape, kind)
        while exp.More():
            worst = max(worst, float(tol(cast(exp.Current()))))
            exp.Next()
    return worst


def read_back(
    path: str | Path, fmt: str, shape: Any, tol_length: float, name: str | Path | None = None
) -> ReadBack:
    """Read ``path`` (``fmt``: 'step', 'iges' or 'brep') and compare it with ``shape``.

    ``tol_length``: the deviation tolerance (length unit); ``name``: the file's name in
    messages (default ``path``: a staged file goes by its target's). CadError naming it and what
    differs when the file holds another number of solids or faces, is not valid, or moves a
    face (inside or along its boundary) by more than the allowed distance.
    """
    from medax.cad.reader import _READERS, quiet_occt

    p = Path(path)
    label = p if name is None else name
    with quiet_occt():
        try:
            back, _unit = _READERS[fmt](p)
        except CadError as err:
            why = str(err).removeprefix(f"{p}: ")
            raise CadError(f"{label}: the written file does not read back ({why})") from None
    if back is None:
        raise CadError(f"{label}: the written file holds no shape")
    allowed = max(tol_length, 2.0 * shape_tolerance(shape))
    n_solids = count(back, TopAbs_SOLID)
    want_solids = count(shape, TopAbs_SOLID)
    if n_solids != want_solids:
        raise CadError(f"{label}: the written file holds {n_solids} solids, not {want_solids}")
    old, new = list(faces_of(shape)), list(faces_of(back))
    if len(new) != len(old):
        raise CadError(f"{label}: the written file holds {len(new)} faces, not {len(old)}")
    valid = bool(BRepCheck_Analyzer(back).IsValid())
    if not valid:
        raise CadError(f"{label}: the written file does not read back as a valid solid")
    dev = 0.0
    for k, (a, b) in enumerate(zip(old, new, strict=True)):
        log_progress(log, f"{label}: faces read back and sampled", k + 1, len(old))
        d = _face_deviation(a, b, old, allowed)
        if d > allowed:
            raise CadError(
                f"{label}: face {k} moves by {d:.3g} through the file (allowed {allowed:.3g})"
            )
        dev = max(dev, d)
    v0, v1 = default_volume(shape), default_volume(back)
    dv = (v1 - v0) / v0
    return ReadBack(n_solids, len(new), valid, dev, allowed, dv)


def _face_deviation(old: Any, new: Any, all_old: list[Any], allowed: float) -> float:
    """Largest distance between ``old`` and ``new`` (the face in the same place in the
    file): samples inside each from the other face, and the boundary as each face's pcurves
    place it, from the other's (:func:`boundary_shift`). A face written in another order is
    measured against every face of the solid."""
    pts_new = face_samples(new, SAMPLES)
    d = max(
        max_distance(pts_new, [old]),
        max_distance(face_samples(old, SAMPLES), [new]),
        boundary_shift(old, new),
    )
    if d <= allowed:
        return d
    return max_distance(pts_new, all_old)


def boundary_shift(old: Any, new: Any) -> float:
    """Largest distance (length unit) of ``new``'s boundary points from ``old``'s boundary
    polyline, and back; both as the faces' pcurves place them on their surfaces."""
    a, b = boundary_samples(old, BOUNDARY_DENSE), boundary_samples(new, BOUNDARY_DENSE)
    return max(_to_polylines(b[:, ::STRIDE], a), _to_polylines(a[:, ::STRIDE], b))


def _to_polylines(points: Array, lines: Array) -> float:
    """Largest distance of ``points`` (e, k, 3) from the nearest segment of ``lines``
    (e', m, 3): one polyline per edge.

    Exact, on the segments that can be nearest only: a point's distance to the nearest
    polyline vertex bounds its answer, so only segments whose midpoint lies within that
    bound plus the longest half-segment are measured (a k-d tree finds them; all pairs
    took 15 s of a 700-face part's read-back)."""
    p = points.reshape(-1, 3)
    if p.size == 0 or lines.size == 0:
        return 0.0
    a, b = lines[:, :-1].reshape(-1, 3), lines[:, 1:].reshape(-1, 3)
    bound = cKDTree(lines.reshape(-1, 3)).query(p)[0]
    half = 0.5 * float(np.sqrt(((b - a) ** 2).sum(1)).max())
    near = cKDTree(0.5 * (a + b)).query_ball_point(p, bound * (1 + 1e-9) + half)
    rows = np.repeat(np.arange(len(p)), [len(c) for c in near])
    cols = np.fromiter((j for c in near for j in c), dtype=np.intp, count=len(rows))
    ab, ap = b[cols] - a[cols], p[rows] - a[cols]
    t = np.clip((ap * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
    d = np.linalg.norm(ap - t[:, None] * ab, axis=1)
    best = bound.copy()  # the nearest vertex, an end of some segment
    np.minimum.at(best, rows, d)
    return float(best.max())


def boundary_samples(face: Any, n: int) -> Array:
    """Points (e, n, 3) on ``face``'s e edges (degenerate ones left out) as its pcurves
    place them on the surface: where the integrators and the face classifier see them."""
    surf = BRepAdaptor_Surface(face)
    out = []
    for edge in edges_of(face):
        if BRep_Tool.Degenerated_s(edge):
            continue
        c2 = BRepAdaptor_Curve2d(edge, face)
        ts = np.linspace(c2.FirstParameter(), c2.LastParameter(), n).tolist()
        uvs = [c2.Value(t) for t in ts]  # OCCT evaluations, n per edge
        out.append([xyz(surf.Value(uv.X(), uv.Y())) for uv in uvs])
    return np.array(out, dtype=np.float64).reshape(-1, n, 3)
