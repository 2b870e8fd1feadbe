"""Write a shape as STEP (AP214), IGES (5.3, B-rep faces) or OCCT BRep, atomically.

The format comes from the extension (``SHAPE_SUFFIXES``); each writer writes to a
temporary file beside the target (``medax.io_utils.atomic_path``), then renames it.
STEP faces can carry colours and names ([medax.cad.xcaf][medax.cad.xcaf]).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from OCP.BRepTools import BRepTools
from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Writer
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

from medax.cad.reader import EXTENSIONS
from medax.cad.xcaf import FaceStyle, write_styled_step
from medax.errors import CadError, InputError
from medax.io_utils import atomic_path

#: output extension -> format name: the extensions the reader takes
SHAPE_SUFFIXES = EXTENSIONS


def shape_format(path: str | Path) -> str:
    """'step', 'iges' or 'brep' by the extension of ``path``; InputError for any other."""
    suffix = Path(path).suffix.lower()
    fmt = SHAPE_SUFFIXES.get(suffix)
    if fmt is None:
        got = f"'{suffix}'" if suffix else "no extension"
        raise InputError(
            f"{path}: cannot write a solid with {got} (use {', '.join(SHAPE_SUFFIXES)})"
        )
    return fmt


def write_shape(
    shape: Any,
    path: str | Path,
    fmt: str | None = None,
    styles: Sequence[FaceStyle] = (),
    name: str = "",
    label: str | Path | None = None,
) -> Path:
    """Write ``shape`` as ``fmt`` (default: by ``path``'s extension); CadError when OCCT
    fails (the target is then untouched). ``styles``: colours and names of faces, written
    to STEP only (XCAF, :mod:`medax.cad.xcaf`; IGES and BRep get the plain shape);
    ``name``: the STEP product's name; ``label``: the file's name in messages."""
    from medax.cad.reader import quiet_occt

    writer = _WRITERS[fmt or shape_format(path)]
    with atomic_path(path) as tmp, quiet_occt():
        writer(shape, tmp, path if label is None else label, styles, name)
    return Path(path)


def write_step(shape: Any, path: str | Path) -> Path:
    """Write ``shape`` to ``path`` as STEP (AP214), whatever its extension, atomically.

    Parameters
    ----------
    shape : TopoDS_Shape
        The shape to write.
    path : str or Path
        The target; written through a temporary file beside it, then renamed.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    CadError
        OCCT failed to write (the target is then untouched).
    """
    from medax.cad.reader import quiet_occt

    with atomic_path(path) as tmp, quiet_occt():
        _step(shape, tmp, path)
    return Path(path)


def _step(
    shape: Any, tmp: Path, path: str | Path, styles: Sequence[FaceStyle] = (), name: str = ""
) -> None:
    if styles:
        write_styled_step(shape, tmp, styles, name, path)
        return
    writer = STEPControl_Writer()
    if writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone:
        raise CadError(f"{path}: the shape could not be transferred to STEP")
    if writer.Write(str(tmp)) != IFSelect_RetDone:
        raise CadError(f"{path}: writing the STEP file failed")


def _iges(shape: Any, tmp: Path, path: str | Path, *_: Any) -> None:
    writer = IGESControl_Writer("MM", 1)  # mode 1: faces as B-rep entities (type 186)
    if not writer.AddShape(shape):
        raise CadError(f"{path}: the shape could not be transferred to IGES")
    writer.ComputeModel()
    if not writer.Write(str(tmp)):
        raise CadError(f"{path}: writing the IGES file failed")


def _brep(shape: Any, tmp: Path, path: str | Path, *_: Any) -> None:
    if not BRepTools.Write_s(shape, str(tmp)):
        raise CadError(f"{path}: writing the BRep file failed")


#: format -> writer(shape, temporary, name in messages, face styles, product name)
_WRITERS: dict[str, Callable[[Any, Path, str | Path, Sequence[FaceStyle], str], None]] = {
    "step": _step,
    "iges": _iges,
    "brep": _brep,
}
