"""What a fillet simplification returns: the simplified solid, what was removed and kept,
the measures of its validation, and their JSON report."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from medax.cad.simplify.reasons import reason_counts

#: The deviation check samples an n x n UV grid on every old and new face (kept inside).
DEVIATION_SAMPLES = 8


@dataclass(frozen=True)
class FaceGroup:
    """A face of the result and what it came from.

    Attributes
    ----------
    new_face : int
        Index (0-based) of the face in the result.
    whole : tuple of int
        Original faces it contains whole.
    halves : tuple of int
        Fillet faces of which it absorbed a half.
    surface : str
        ``extrusion``, ``revolution`` (new exact surfaces), ``fitted`` or ``original``.
    """

    new_face: int
    whole: tuple[int, ...]
    halves: tuple[int, ...]
    surface: str


@dataclass
class SimplifyResult:
    """Outcome of [simplify][medax.cad.simplify.pipeline.simplify]; its JSON form is
    [report][medax.cad.simplify.result.SimplifyResult.report].

    Attributes
    ----------
    shape : TopoDS_Shape
        The simplified solid (the input itself when nothing was removed).
    faces_before, faces_after : int
        Face counts of the input and the result.
    blends_removed : list of int
        Original indices of the fillets and corner blends removed.
    blends_kept : list of (int, str)
        Original index and reason of every blend kept.
    valid : bool
        ``BRepCheck_Analyzer`` validity of the result.
    volume_before, volume_after : float
        Volumes (length unit cubed) by two integrators that agree; when no rebuild was
        measured both are OCCT's default integrator's, and equal.
    max_deviation, diagonal : float
        Largest two-sided distance between old and new faces, and the part's diagonal
        (length unit).
    face_groups : list of FaceGroup
        What each face of the result came from.
    time_s : float
        Wall time of the run, s.
    cpu_s : float
        CPU time of the run (this process, all threads), s: what the budgets count.
    """

    shape: Any
    faces_before: int
    faces_after: int
    blends_removed: list[int]
    blends_kept: list[tuple[int, str]]
    valid: bool
    volume_before: float
    volume_after: float
    max_deviation: float
    diagonal: float
    face_groups: list[FaceGroup]
    time_s: float
    cpu_s: float = 0.0
    medial_error: float = 0.0
    fit_error: float = 0.0
    fit_volume_rel_change: float = 0.0
    area_rel_change: float = 0.0
    default_volume_rel_change: float = 0.0
    notes: list[str] = field(default_factory=list)
    radii: dict[int, float | None] = field(default_factory=dict)

    @property
    def volume_rel_change(self) -> float:
        """(after - before) / before."""
        return (self.volume_after - self.volume_before) / self.volume_before

    def __repr__(self) -> str:
        return (
            f"SimplifyResult(faces {self.faces_before} -> {self.faces_after}, "
            f"{len(self.blends_removed)} blends removed, {len(self.blends_kept)} kept, "
            f"valid {self.valid}, volume change {self.volume_rel_change:.1e}, "
            f"deviation {self.max_deviation / self.diagonal:.1e} x diagonal, {self.time_s:.2f} s)"
        )

    def report(self) -> dict[str, Any]:
        """The JSON-ready report.

        Returns
        -------
        dict
            Face and blend counts, kept blends with radius and reason, the reasons grouped,
            validity, volume, area, deviation and fit measures, face groups and time (the
            ``simplify-report`` schema's body).
        """
        return {
            "faces_before": self.faces_before,
            "faces_after": self.faces_after,
            "blends_removed": sorted(self.blends_removed),
            "blends_found": len(self.blends_removed) + len(self.blends_kept),
            "blends_kept": [
                {"face": f, "radius": self.radii.get(f), "reason": r}
                for f, r in sorted(self.blends_kept)
            ],
            "kept_reasons": reason_counts(r for _, r in self.blends_kept),
            "valid": self.valid,
            "volume_before": self.volume_before,
            "volume_after": self.volume_after,
            "volume_rel_change": self.volume_rel_change,
            "area_rel_change": self.area_rel_change,
            # what FreeCAD and CadQuery would report: OCCT's default (fixed-order) integrator
            "default_integrator_volume_rel_change": self.default_volume_rel_change,
            "max_deviation": {
                "absolute": self.max_deviation,
                "relative_to_diagonal": self.max_deviation / self.diagonal,
            },
            "diagonal": self.diagonal,
            "medial_equidistance_error": self.medial_error,
            # null where a fitted face's side of the solid could not be told (no estimate)
            "fit_volume_rel_change": (
                self.fit_volume_rel_change if math.isfinite(self.fit_volume_rel_change) else None
            ),
            "max_fit_error": {
                "absolute": self.fit_error,
                "relative_to_diagonal": self.fit_error / self.diagonal,
            },
            "deviation_samples_per_face": DEVIATION_SAMPLES**2,
            "face_groups": [
                {
                    "new_face": g.new_face,
                    "original_faces": list(g.whole),
                    "fillet_halves": list(g.halves),
                    "surface": g.surface,
                }
                for g in self.face_groups
            ],
            "notes": self.notes,
            "time_s": self.time_s,
            "cpu_s": self.cpu_s,
        }
