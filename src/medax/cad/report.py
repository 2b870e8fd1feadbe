"""The ``classes.json`` report of a classified part, and tracing every fillet's axis.

Layout (all lengths in ``unit``)::

    {"source", "unit", "file_unit", "notes": [...],
     "summary": {"fillet": n, "corner_blend": n, "supporting": n, "protection": n,
                 "faces": n, "edges": n, "axes": n, "solids": n},
     "solids": [{"solid": k, "summary": {...},
                 "faces": [{"index", "class", "surface", "area", "centroid", "radius"?,
                            "neighbours", "edges", "edge_classes"? (supporting faces)}],
                 "edges": [{"index", "class", "faces", "curve", "length", "tangent",
                            "max_angle_deg"}],
                 "fillets": [{"face", "constraint_edges": [[...], [...]], "cross_edges",
                              "supporting", "radius", "closed",
                              "axis": {"points": [[x, y, z], ...], "max_point_error", ...}
                                      or null, "axis_error"?: "..."}],
                 "corner_blends": [{"face", "fillets", "supporting", "edges", "radius"}],
                 "doubts": [{"face", "reason"}]}]}
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from medax import tolerances
from medax._progress import log_progress
from medax.axis import MedialAxis
from medax.cad.model import Classification, FaceClass
from medax.errors import MedaxError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ClassifiedSolid:
    """A classification and the traced axes of its fillets (face index -> axis), and the
    one-line reasons for fillets whose axis could not be traced."""

    classification: Classification
    axes: dict[int, MedialAxis] = field(default_factory=dict)
    axis_errors: dict[int, str] = field(default_factory=dict)


def trace_fillet_axes(c: Classification, tol: float = tolerances.CURVE_TOL) -> ClassifiedSolid:
    """Trace the medial axis of every edge fillet of ``c``; failures are recorded, not
    raised (a part with one odd fillet still gets a report)."""
    from medax.cad.face_region import fillet_axis

    axes: dict[int, MedialAxis] = {}
    errors: dict[int, str] = {}
    for k, rec in enumerate(c.fillets):
        log_progress(log, "fillet axes traced", k + 1, len(c.fillets))
        try:
            axes[rec.face] = fillet_axis(c, rec, tol=tol)
        except MedaxError as err:
            errors[rec.face] = str(err)
            log.warning("fillet face %d: no axis (%s)", rec.face, err)
    return ClassifiedSolid(c, axes, errors)


def _r(x: float) -> float:
    return float(f"{x:.12g}")


def _axis_json(a: MedialAxis) -> dict[str, Any]:
    return {
        "points": [[_r(v) for v in p] for p in a.space_points.tolist()],
        "uv": [[_r(v) for v in p] for p in a.points.tolist()],
        "max_point_error": float(a.max_point_error),
        "max_curve_error": float(a.max_curve_error),
        "n_points": a.n_points,
    }


def solid_report(cs: ClassifiedSolid) -> dict[str, Any]:
    """The JSON-ready report of one classified solid."""
    c = cs.classification
    faces = []
    for f in c.faces:
        item: dict[str, Any] = {
            "index": f.index,
            "class": f.cls.value,
            "surface": f.surface,
            "area": _r(f.area),
            "centroid": [_r(v) for v in f.centroid],
        }
        if f.radius is not None:
            item["radius"] = _r(f.radius)
        item["neighbours"] = list(f.neighbours)
        item["edges"] = list(f.edges)
        if f.cls is FaceClass.SUPPORTING:
            item["edge_classes"] = {str(j): k.value for j, k in c.edge_classes(f.index).items()}
        faces.append(item)
    fillets = []
    for rec in c.fillets:
        fr: dict[str, Any] = {
            "face": rec.face,
            "constraint_edges": [list(rec.smooth_edges[0]), list(rec.smooth_edges[1])],
            "cross_edges": list(rec.cross_edges),
            "supporting": list(rec.supporting),
            "radius": None if rec.radius is None else _r(rec.radius),
            "closed": rec.closed,
            "axis": _axis_json(cs.axes[rec.face]) if rec.face in cs.axes else None,
        }
        if rec.face in cs.axis_errors:
            fr["axis_error"] = cs.axis_errors[rec.face]
        fillets.append(fr)
    corners = [
        {
            "face": r.face,
            "fillets": list(r.fillets),
            "supporting": list(r.supporting),
            "edges": list(r.edges),
            "radius": None if r.radius is None else _r(r.radius),
        }
        for r in c.corners
    ]
    edges = [
        {
            "index": e.index,
            "class": e.cls.value,
            "faces": list(e.faces),
            "curve": e.curve,
            "length": _r(e.length),
            "tangent": e.tangent,
            "max_angle_deg": _r(float(np.degrees(e.max_angle))),
        }
        for e in c.edges
    ]
    summary = c.counts()
    summary["axes"] = len(cs.axes)
    return {
        "solid": c.solid,
        "summary": summary,
        "faces": faces,
        "edges": edges,
        "fillets": fillets,
        "corner_blends": corners,
        "doubts": [{"face": d.face, "reason": d.reason} for d in c.doubts],
        "tangent_angle": c.tangent_angle,
    }


def part_report(
    solids: list[ClassifiedSolid],
    source: str,
    unit: str,
    file_unit: str = "",
    notes: tuple[str, ...] = (),
) -> dict[str, Any]:
    """The whole ``classes.json`` document for the solids of one file."""
    reports = [solid_report(s) for s in solids]
    keys = [k.value for k in FaceClass] + ["faces", "edges", "axes"]
    summary = {k: sum(r["summary"][k] for r in reports) for k in keys}
    summary["solids"] = len(reports)
    return {
        "source": source,
        "unit": unit,
        "file_unit": file_unit,
        "notes": list(notes),
        "summary": summary,
        "solids": reports,
    }
