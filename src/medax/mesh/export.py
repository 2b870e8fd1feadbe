"""Write quad meshes to Gmsh ``.msh`` 4.1, VTK ``.vtu``, Abaqus ``.inp`` and Nastran ``.bdf``.

Every file is written through :func:`medax.io_utils.atomic_path` (a temporary file beside
the target, renamed onto it), so a failure never leaves a partial file. The format comes
from the extension unless ``file_format`` overrides it.

What each format gets, and the meshio 5.3.5 defects worked around:

- ``msh`` (Gmsh 4.1, ASCII): one surface entity and physical group 1 holding every quad, the
  quality fields as ``$ElementData`` views. meshio writes ASCII element data with ``repr``,
  which under numpy 2 gives ``np.float64(1.0)`` and an unreadable file; we write with numpy's
  1.25 printing rules. Without ``gmsh:dim_tags`` meshio writes no ``$Entities`` and gmsh
  refuses the physical tags; we supply them.
- ``vtu``: points padded to 3-D; the quality fields as cell data.
- ``inp`` (Abaqus): meshio names quads ``CAX4P`` (axisymmetric pore pressure). We write
  ``CPS4`` (plane stress, 2-D coordinates; what gmsh's own Abaqus exporter writes) for a planar
  mesh and ``S4`` (shell) for a mesh in space, all elements in ``*ELSET, ELSET=MEDAX``.
  Abaqus has no cell data: the quality fields are not written.
- ``bdf`` (Nastran bulk data): meshio's large-field writer asserts on negative coordinates
  with 12 significant digits (17 characters in a 16-character field) and leaves the CQUAD4
  property id blank, which gmsh misreads. We write ``GRID*`` large-field cards with 10
  significant digits and ``CQUAD4`` cards with property id 1 (define ``PSHELL 1`` in the
  solver deck). No cell data.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO

import numpy as np

from medax.errors import InputError, MeshError, OutputError
from medax.geometry._types import FloatArray, IntArray
from medax.io_utils import atomic_path

log = logging.getLogger(__name__)

#: format name -> file extensions (the first is the canonical one)
FORMATS: dict[str, tuple[str, ...]] = {
    "msh": (".msh",),
    "vtu": (".vtu",),
    "abaqus": (".inp",),
    "nastran": (".bdf", ".nas"),
}
#: Abaqus element keyword for a planar and for a spatial 4-node quad
ABAQUS_PLANE_QUAD = "CPS4"
ABAQUS_SHELL_QUAD = "S4"
#: the element set / physical group every quad belongs to
ELSET = "MEDAX"


def format_from_path(path: str | Path, file_format: str | None = None) -> str:
    """The format name for ``path``: ``file_format`` if given, else from the extension."""
    if file_format is not None:
        name = file_format.lower().lstrip(".")
        for fmt, exts in FORMATS.items():
            if name == fmt or f".{name}" in exts:
                return fmt
        raise InputError(f"unknown mesh format '{file_format}' (known: {', '.join(FORMATS)})")
    ext = Path(path).suffix.lower()
    for fmt, exts in FORMATS.items():
        if ext in exts:
            return fmt
    known = ", ".join(e for exts in FORMATS.values() for e in exts)
    raise InputError(f"{path}: unknown mesh file extension '{ext}' (known: {known})")


def write_mesh(
    path: str | Path,
    points: FloatArray,
    quads: IntArray,
    cell_data: Mapping[str, FloatArray] | None = None,
    file_format: str | None = None,
) -> Path:
    """Write ``quads`` (m, 4) over ``points`` (n, 2|3) to ``path``; returns the path.

    ``cell_data`` maps names to (m,) arrays (e.g. the quality metrics), written where the
    format can hold them. Raises :class:`InputError` for an unknown format or a path that
    cannot be written; nothing is left behind on failure.
    """
    fmt = format_from_path(path, file_format)
    pts, q, data = checked_mesh(points, quads, cell_data)
    target = Path(path)
    writer = _WRITERS[fmt]
    try:
        with atomic_path(target) as tmp:
            writer(tmp, pts, q, data)
    except OSError as err:
        raise OutputError(f"{target}: cannot write ({err.strerror or err})") from None
    log.info("wrote %s (%s, %d nodes, %d quads)", target, fmt, len(pts), len(q))
    return target


def checked_mesh(
    points: FloatArray, quads: IntArray, cell_data: Mapping[str, FloatArray] | None
) -> tuple[FloatArray, IntArray, dict[str, FloatArray]]:
    """``points`` (n, 2|3) finite, ``quads`` (m, 4) indices into them and each cell data
    array (m,), as float / int arrays; :class:`MeshError` naming what is wrong."""
    pts = np.asarray(points, dtype=np.float64)
    q = np.asarray(quads, dtype=np.int64)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or not np.all(np.isfinite(pts)):
        raise MeshError(f"export: points must be finite (n, 2|3), got shape {pts.shape}")
    if q.ndim != 2 or q.shape[1] != 4 or (q.size and (q.min() < 0 or q.max() >= len(pts))):
        raise MeshError(f"export: quads must be (m, 4) indices into {len(pts)} points")
    data = {k: np.asarray(v, dtype=np.float64) for k, v in (cell_data or {}).items()}
    for k, v in data.items():
        if v.shape != (q.shape[0],):
            raise MeshError(f"export: cell data '{k}' has shape {v.shape}, want ({q.shape[0]},)")
    return pts, q, data


def _pad3(points: FloatArray) -> FloatArray:
    if points.shape[1] == 3:
        return points
    return np.column_stack((points, np.zeros(len(points))))


def _write_msh(
    path: Path, points: FloatArray, quads: IntArray, data: dict[str, FloatArray]
) -> None:
    import meshio  # noqa: PLC0415

    m = len(quads)
    ones = np.ones(m, dtype=np.int64)
    cell_data: dict[str, list[np.ndarray]] = {k: [v] for k, v in data.items()}
    cell_data["gmsh:physical"] = [ones]
    cell_data["gmsh:geometrical"] = [ones]
    mesh = meshio.Mesh(
        _pad3(points),
        [("quad", quads)],
        point_data={"gmsh:dim_tags": np.tile(np.array([2, 1]), (len(points), 1))},
        cell_data=cell_data,
    )
    with np.printoptions(legacy="1.25"):  # meshio writes ASCII data with repr()
        meshio.write(str(path), mesh, file_format="gmsh", binary=False)


def _write_vtu(
    path: Path, points: FloatArray, quads: IntArray, data: dict[str, FloatArray]
) -> None:
    import meshio  # noqa: PLC0415

    cell_data = {k: [v] for k, v in data.items()}
    mesh = meshio.Mesh(_pad3(points), [("quad", quads)], cell_data=cell_data)
    meshio.write(str(path), mesh, file_format="vtu")


def _write_abaqus(
    path: Path, points: FloatArray, quads: IntArray, data: dict[str, FloatArray]
) -> None:
    import meshio  # noqa: PLC0415

    mesh = meshio.Mesh(points, [("quad", quads)], cell_sets={ELSET: [np.arange(len(quads))]})
    # meshio maps "quad" to CAX4P; name the element ourselves
    mesh.cells[0].type = ABAQUS_PLANE_QUAD if points.shape[1] == 2 else ABAQUS_SHELL_QUAD
    meshio.abaqus.write(str(path), mesh, translate_cell_names=False)


def nastran_real(values: FloatArray) -> list[str]:
    """Nastran reals for 16-character large fields (10 significant digits, ``E`` exponent)."""
    v = np.asarray(values, dtype=np.float64)
    v = np.where(np.abs(v) < 1e-99, 0.0, v)
    if np.any(np.abs(v) >= 1e99):
        raise MeshError("export: a coordinate is too large for a Nastran field (>= 1e99)")
    return [f"{x:16.9E}" for x in v.tolist()]


def _write_nastran(
    path: Path, points: FloatArray, quads: IntArray, data: dict[str, FloatArray]
) -> None:
    pts = _pad3(points)
    n, m = len(pts), len(quads)
    if max(n, m) > 99_999_999:
        raise MeshError("export: Nastran ids are limited to 8 digits")
    xyz = np.array(nastran_real(pts.ravel())).reshape(-1, 3)
    with open(path, "w", encoding="ascii") as f:
        _nastran_body(f, xyz, quads)


def _nastran_body(f: IO[str], xyz: np.ndarray, quads: IntArray) -> None:
    f.write("$ Nastran bulk data written by medax: GRID* + CQUAD4 (PID 1: supply PSHELL 1)\n")
    f.write("BEGIN BULK\n")
    f.writelines(
        f"GRID*   {i + 1:<16d}{'':16s}{x}{y}\n*       {z}\n"
        for i, (x, y, z) in enumerate(xyz.tolist())
    )
    q1 = quads + 1
    f.writelines(
        f"CQUAD4  {e + 1:<8d}{1:<8d}{a:<8d}{b:<8d}{c:<8d}{d:<8d}\n"
        for e, (a, b, c, d) in enumerate(q1.tolist())
    )
    f.write("ENDDATA\n")


_WRITERS: dict[str, Callable[[Path, FloatArray, IntArray, dict[str, FloatArray]], None]] = {
    "msh": _write_msh,
    "vtu": _write_vtu,
    "abaqus": _write_abaqus,
    "nastran": _write_nastran,
}
