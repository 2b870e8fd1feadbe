"""How finely doubles resolve a region's coordinates, relative to its size."""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray


def coordinate_resolution(points: FloatArray, diagonal: float) -> float:
    """The spacing of doubles at the largest coordinate of ``points``, over ``diagonal``: no
    coordinate written there is more accurate than this (relative). About 1e-16 near the
    origin, 1e-5 for a 10-unit region at 1e12."""
    top = float(np.max(np.abs(np.asarray(points, dtype=np.float64))))
    return float(np.spacing(top)) / diagonal


def resolution_note(name: str, resolution: float, tol: float) -> str | None:
    """A warning when ``resolution`` is coarser than the tolerance ``tol`` promised."""
    if resolution <= tol:
        return None
    return (
        f"region '{name}': doubles resolve its coordinates only to {resolution:.1e} x diagonal "
        f"(far from the origin), above the {tol:g} tolerance; the written coordinates hold "
        "no better (move the region near the origin for full accuracy)"
    )
