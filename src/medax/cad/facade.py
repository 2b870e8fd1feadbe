"""Notebook entry points that take what a user has at hand (a path, a part, a solid, a
classification) and pass it on to the library's functions. Lengths in the part's unit (mm
for STEP and IGES)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from medax import tolerances
from medax.cad.classify import classify_file, classify_solid
from medax.cad.model import Classification
from medax.cad.reader import Part
from medax.cad.simplify import pipeline
from medax.cad.simplify.specs import BlendInput, specs_from_classification


def classify(
    part: str | Path | Part | Any, angle_tol: float = tolerances.TANGENT_ANGLE
) -> list[Classification]:
    """Classify the faces and edges of each solid of ``part``: a file path (STEP, IGES,
    BRep), a :class:`~medax.cad.reader.Part` or one ``TopoDS_Solid``. ``angle_tol`` is the
    tangency tolerance (radians). One :class:`Classification` per solid, in file order."""
    if isinstance(part, str | Path):
        return classify_file(str(part), angle_tol)
    if isinstance(part, Part):
        return [
            classify_solid(s, angle_tol, source=part.source, unit=part.unit, index=k)
            for k, s in enumerate(part.solids)
        ]
    return [classify_solid(part, angle_tol)]


def simplify(
    part: Classification | Any,
    blends: BlendInput | None = None,
    tol: float = pipeline.DEVIATION_TOL,
    progress: Callable[[str], None] | None = None,
    time_budget: float = pipeline.ISOLATION_BUDGET,
) -> pipeline.SimplifyResult:
    """Remove the fillets of ``part``: a :class:`Classification` (its blends are used), or a
    ``TopoDS_Solid`` with ``blends`` (classified here when None). ``tol``: boundary deviation
    bound relative to the diagonal; ``time_budget`` (s) bounds the search for failing
    fillets. See :func:`medax.cad.simplify.simplify`."""
    if isinstance(part, Classification):
        shape, found = part.shape, part
    else:
        shape, found = part, None
    if blends is None:
        blends = specs_from_classification(found or classify_solid(shape))
    return pipeline.simplify(shape, blends, tol, progress, time_budget)
