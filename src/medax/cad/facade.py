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
    """Classify the faces and edges of each solid of a part.

    Fillets, chamfers and the faces they join are recognised per solid; lengths stay in the
    part's unit (mm for STEP and IGES).

    Parameters
    ----------
    part : str, Path, Part or TopoDS_Solid
        A file path (STEP, IGES, BRep), a [Part][medax.cad.reader.Part] or one solid.
    angle_tol : float
        Tangency tolerance (radians): two faces are tangent along an edge when their
        normals differ by less.

    Returns
    -------
    list of Classification
        One [Classification][medax.cad.model.Classification] per solid, in file order.

    Raises
    ------
    CadError
        The file cannot be read (see [read_part][medax.cad.reader.read_part]) or a solid
        cannot be classified.
    """
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
    strict_volume: bool = False,
) -> pipeline.SimplifyResult:
    """Remove the fillets of a classified part.

    Calls [medax.cad.simplify.pipeline.simplify][medax.cad.simplify.pipeline.simplify].
    Fillets that cannot be removed within the tolerances are kept, with the reason, in the
    result's report; the input solid is not modified.

    Parameters
    ----------
    part : Classification or TopoDS_Solid
        A [Classification][medax.cad.model.Classification] (its blends are used), or a solid
        with ``blends``.
    blends : BlendInput, optional
        The fillets to remove; classified here when None.
    tol : float
        Bound on the boundary deviation, relative to the part's diagonal.
    progress : callable, optional
        Called with one message per stage.
    time_budget : float
        Bound (s) on the search for the fillets that fail.
    strict_volume : bool
        Also keep the fillets whose merged faces OCCT's default mass properties (FreeCAD,
        CadQuery) would read as a volume change above 1e-6.

    Returns
    -------
    SimplifyResult
        The simplified solid and its report
        ([SimplifyResult][medax.cad.simplify.result.SimplifyResult]).

    Raises
    ------
    CadError
        A solid given without ``blends`` cannot be classified.
    """
    if isinstance(part, Classification):
        shape, found = part.shape, part
    else:
        shape, found = part, None
    if blends is None:
        blends = specs_from_classification(found or classify_solid(shape))
    return pipeline.simplify(shape, blends, tol, progress, time_budget, strict_volume)
