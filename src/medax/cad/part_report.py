"""The quality report of a part mesh: per face and over the part (JSON-ready)."""

from __future__ import annotations

from typing import Any

import numpy as np

from medax.cad.part_mesh import PartMesh
from medax.geometry._types import FloatArray, IntArray
from medax.mesh.gmsh_quality import gmsh_scaled_jacobian
from medax.mesh.quality import quad_quality

SJ_DEFINITIONS = {
    "scaled_jacobian": "Verdict: min over the 4 corners of n . (L_{k-1} x L_k) / "
    "(|L_{k-1}| |L_k|), n the unit normal X1 x X2 of the quad (the sine of the corner angle)",
    "gmsh_scaled_jacobian": "gmsh's minSJ (getElementQualities), its own normalisation "
    "of the Jacobian determinant over the element (lower than Verdict's on "
    "non-parallelograms)",
}


#: histogram bins per metric: (low, high, bins); values outside are counted in the end bins
HISTOGRAM_BINS = {
    "scaled_jacobian": (-1.0, 1.0, 20),
    "min_angle": (0.0, 90.0, 18),
    "max_angle": (90.0, 180.0, 18),
}


def histograms(q: Any) -> dict[str, dict[str, list[float] | list[int]]]:
    """Per metric of :data:`HISTOGRAM_BINS`, ``edges`` (bins + 1) and ``counts`` (bins) of
    the quads' values (:class:`~medax.mesh.quality.QuadQuality`); a value outside the
    range counts in the nearest end bin, so the counts sum to the number of quads."""
    out: dict[str, dict[str, list[float] | list[int]]] = {}
    for name, (lo, hi, n) in HISTOGRAM_BINS.items():
        v = np.clip(getattr(q, name), lo, hi)
        counts, edges = np.histogram(v[np.isfinite(v)], bins=n, range=(lo, hi))
        out[name] = {"edges": [float(x) for x in edges], "counts": [int(c) for c in counts]}
    return out


def _stats(v: FloatArray) -> dict[str, float]:
    if v.size == 0:
        return {}
    p5 = float(np.percentile(v, 5.0))
    return {"min": float(v.min()), "p5": p5, "mean": float(v.mean()), "max": float(v.max())}


def edge_use(quads: IntArray) -> tuple[int, int]:
    """Mesh edges used by one quad only (open) and by more than two (non-manifold)."""
    e = np.sort(np.stack([quads, np.roll(quads, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return int(np.count_nonzero(counts == 1)), int(np.count_nonzero(counts > 2))


def part_report(mesh: PartMesh, source: str = "", size: float | None = None) -> dict[str, Any]:
    """Counts, times, conflicts, both scaled Jacobians, angles, per face and over the part."""
    q = quad_quality(mesh.points, mesh.quads)
    gsj = gmsh_scaled_jacobian(mesh.points, mesh.quads)
    open_edges, nonmanifold = edge_use(mesh.quads)
    faces = []
    for f in mesh.faces:
        s = slice(f.start, f.stop)
        faces.append(
            {
                "face": f.face,
                "kind": f.kind,
                "why_not_structured": f.why or None,
                "divisions": list(f.divisions) if f.divisions else None,
                "n_quads": f.stop - f.start,
                "time_s": round(f.time_s, 4),
                "scaled_jacobian": _stats(q.scaled_jacobian[s]),
                "gmsh_scaled_jacobian": _stats(gsj[s]),
                "min_angle": float(q.min_angle[s].min()) if f.stop > f.start else None,
                "max_angle": float(q.max_angle[s].max()) if f.stop > f.start else None,
            }
        )
    return {
        "input": source,
        "size": size,
        "n_faces": len(mesh.faces),
        "n_structured_faces": len(mesh.structured_faces),
        "n_gmsh_faces": len(mesh.gmsh_faces),
        "structured_faces": list(mesh.structured_faces),
        "conflicts": {str(k): v for k, v in sorted(mesh.conflicts.items())},
        "n_nodes": int(len(mesh.points)),
        "n_quads": int(len(mesh.quads)),
        "share_of_quads": 1.0,
        "open_mesh_edges": open_edges,
        "nonmanifold_mesh_edges": nonmanifold,
        "time_s": mesh.time_s,
        "definitions": SJ_DEFINITIONS,
        "scaled_jacobian": _stats(q.scaled_jacobian),
        "gmsh_scaled_jacobian": _stats(gsj),
        "min_angle": _stats(q.min_angle),
        "max_angle": _stats(q.max_angle),
        "n_inverted": int(np.count_nonzero(q.scaled_jacobian <= 0.0)),
        "histograms": histograms(q),
        "faces": faces,
    }
