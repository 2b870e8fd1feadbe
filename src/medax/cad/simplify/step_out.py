"""Write a shape to STEP (AP214) atomically: temporary file beside the target, then rename."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from OCP.IFSelect import IFSelect_RetDone
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

from medax.errors import CadError
from medax.io_utils import atomic_path


def write_step(shape: Any, path: str | Path) -> Path:
    """Write ``shape`` to ``path``; raises :class:`CadError` when OCCT fails (no file left)."""
    from medax.cad.reader import quiet_occt

    with atomic_path(path) as tmp, quiet_occt():
        writer = STEPControl_Writer()
        if writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone:
            raise CadError(f"{path}: the shape could not be transferred to STEP")
        if writer.Write(str(tmp)) != IFSelect_RetDone:
            raise CadError(f"{path}: writing the STEP file failed")
    return Path(path)
