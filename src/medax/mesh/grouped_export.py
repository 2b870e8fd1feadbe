"""Quad meshes with named groups: a surface group per set of quads (a CAD face, a region)
and a curve group per set of line segments (a CAD edge, a region side).

- ``msh`` (Gmsh 4.1 ASCII, written by gmsh itself from a discrete model): one surface
  entity and physical surface per quad group, one curve entity and physical curve (with
  line elements) per line group, all named in ``$PhysicalNames``; the cell data as
  ``$ElementData`` on the quads.
- ``vtu``: quads and lines, cell data ``surface_group`` / ``curve_group`` (the group ids,
  -1 on the other kind of cell) and the quad fields (NaN on lines); the names are not stored.
- ``inp`` (Abaqus): ``S4`` (``CPS4`` for planar points) elements in one ``*ELSET`` per
  surface group, the nodes of each curve group as an ``*NSET``; no cell data.
- ``bdf`` (Nastran): ``GRID*`` and ``CQUAD4`` with property id = surface group id + 1, a
  ``SET1`` of grid ids per curve group (id = curve group id + 1), the names in comments.

Group names must be Abaqus-safe (letters, digits, ``_``); ids are non-negative integers.
Written atomically like :func:`medax.mesh.export.write_mesh`.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np

from medax.errors import MeshError, OutputError
from medax.geometry._types import FloatArray, IntArray
from medax.io_utils import atomic_path
from medax.mesh.export import (
    ABAQUS_PLANE_QUAD,
    ABAQUS_SHELL_QUAD,
    _pad3,
    checked_mesh,
    format_from_path,
    nastran_real,
)
from medax.mesh.gmsh_session import gmsh_session
from medax.mesh.grid import boundary_indices

log = logging.getLogger(__name__)
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class MeshGroups:
    """``quad_group`` (m,) the group id of each quad, ``quad_names`` id -> name;
    ``lines`` (k, 2) node pairs, ``line_group`` (k,) their group id, ``line_names``."""

    quad_group: IntArray
    quad_names: Mapping[int, str]
    lines: IntArray
    line_group: IntArray
    line_names: Mapping[int, str]

    def check(self, n_points: int, n_quads: int) -> None:
        """:class:`MeshError` for shapes, ids or names that do not fit."""
        if self.quad_group.shape != (n_quads,):
            raise MeshError(f"export: quad groups have shape {self.quad_group.shape}")
        if (
            self.lines.ndim != 2
            or self.lines.shape[1] != 2
            or self.line_group.shape != (len(self.lines),)
        ):
            raise MeshError("export: lines must be (k, 2) with one group id each")
        if self.lines.size and (self.lines.min() < 0 or self.lines.max() >= n_points):
            raise MeshError("export: a line refers to a node that does not exist")
        for ids, names in ((self.quad_group, self.quad_names), (self.line_group, self.line_names)):
            missing = set(np.unique(ids).tolist()) - set(names)
            if missing:
                raise MeshError(f"export: group id {min(missing)} has no name")
            if any(i < 0 for i in names):
                raise MeshError("export: group ids must be non-negative")
            bad = [n for n in names.values() if not _NAME.match(n)]
            if bad:
                raise MeshError(f"export: group name '{bad[0]}' is not letters, digits and _")


def region_groups(n1: int, n2: int, name: str = "MEDAX") -> MeshGroups:
    """Groups of a structured region mesh (:mod:`medax.mesh.grid` numbering): all quads in
    ``name``, the boundary segments of side ``k`` in ``S<k>`` (in the side's direction)."""
    sides = boundary_indices(n1, n2)
    lines = np.concatenate([np.column_stack((s[:-1], s[1:])) for s in sides])
    line_group = np.repeat(np.arange(4), [len(s) - 1 for s in sides])
    return MeshGroups(
        np.zeros(n1 * n2, dtype=np.int64),
        {0: name},
        lines,
        line_group,
        {k: f"S{k}" for k in range(4)},
    )


def write_grouped_mesh(
    path: str | Path,
    points: FloatArray,
    quads: IntArray,
    groups: MeshGroups,
    cell_data: Mapping[str, FloatArray] | None = None,
    file_format: str | None = None,
) -> Path:
    """Write ``quads`` (m, 4) over ``points`` (n, 2|3) with ``groups`` to ``path``."""
    fmt = format_from_path(path, file_format)
    pts, q, data = checked_mesh(points, quads, cell_data)
    groups.check(len(pts), len(q))
    target = Path(path)
    writer = {
        "msh": _msh,
        "vtu": _vtu,
        "abaqus": _abaqus,
        "nastran": _nastran,
    }[fmt]
    try:
        with atomic_path(target) as tmp:
            writer(tmp, pts, q, groups, data)
    except OSError as err:
        raise OutputError(f"{target}: cannot write ({err.strerror or err})") from None
    log.info("wrote %s (%s, %d nodes, %d quads, groups)", target, fmt, len(pts), len(q))
    return target


def _msh(
    path: Path, pts: FloatArray, quads: IntArray, g: MeshGroups, data: dict[str, FloatArray]
) -> None:
    p3 = _pad3(pts)
    n, m = len(p3), len(quads)
    # each node on one entity: a curve's if a line uses it, else a surface's
    entity = np.zeros((n, 2), dtype=np.int64)  # (dim, tag)
    for k in range(4):
        entity[quads[:, k]] = np.column_stack((np.full(m, 2), g.quad_group + 1))
    for k in range(2):
        entity[g.lines[:, k]] = np.column_stack((np.full(len(g.lines), 1), g.line_group + 1))
    with gmsh_session() as gmsh:
        gmsh.model.add("medax-export")
        try:
            for dim, ids in ((2, g.quad_names), (1, g.line_names)):
                for i in sorted(ids):
                    gmsh.model.addDiscreteEntity(dim, i + 1)
            tags = np.arange(1, n + 1)
            for dim, tag in np.unique(entity, axis=0).tolist():
                rows = np.flatnonzero((entity[:, 0] == dim) & (entity[:, 1] == tag))
                gmsh.model.mesh.addNodes(dim, tag, tags[rows].tolist(), p3[rows].ravel().tolist())
            # element tags in the order gmsh writes them (curves, then surfaces, each by
            # group): lines 1..k, quads k + 1..k + m
            k = len(g.lines)
            line_order = np.argsort(g.line_group, kind="stable")
            quad_order = np.argsort(g.quad_group, kind="stable")
            line_tag = np.empty(k, dtype=np.int64)
            line_tag[line_order] = np.arange(1, k + 1)
            quad_tag = np.empty(m, dtype=np.int64)
            quad_tag[quad_order] = np.arange(k + 1, k + m + 1)
            for i, name in sorted(g.line_names.items()):
                rows = np.flatnonzero(g.line_group == i)
                gmsh.model.mesh.addElementsByType(
                    i + 1, 1, line_tag[rows].tolist(), (g.lines[rows] + 1).ravel().tolist()
                )
                gmsh.model.addPhysicalGroup(1, [i + 1], i + 1, name)
            for i, name in sorted(g.quad_names.items()):
                rows = np.flatnonzero(g.quad_group == i)
                gmsh.model.mesh.addElementsByType(
                    i + 1, 3, quad_tag[rows].tolist(), (quads[rows] + 1).ravel().tolist()
                )
                gmsh.model.addPhysicalGroup(2, [i + 1], i + 1, name)
            gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
            gmsh.option.setNumber("Mesh.Binary", 0)
            gmsh.option.setNumber("Mesh.SaveAll", 0)
            gmsh.write(str(path))
        finally:
            gmsh.model.remove()
    if data:
        # every element gets a value (meshio reads only complete data): nan on the lines
        values = np.full(k + m, np.nan)
        with open(path, "a", encoding="ascii") as f:
            for name, v in data.items():
                values[quad_tag - 1] = v
                _element_data(f, name, values)


def _element_data(f: IO[str], name: str, v: FloatArray) -> None:
    f.write(f'$ElementData\n1\n"{name}"\n1\n0\n3\n0\n1\n{len(v)}\n')
    f.writelines(f"{k + 1} {x!r}\n" for k, x in enumerate(v.tolist()))
    f.write("$EndElementData\n")


def _vtu(
    path: Path, pts: FloatArray, quads: IntArray, g: MeshGroups, data: dict[str, FloatArray]
) -> None:
    import meshio  # noqa: PLC0415

    m, k = len(quads), len(g.lines)
    cells = [("quad", quads), ("line", g.lines)]
    cd: dict[str, list[np.ndarray]] = {
        "surface_group": [g.quad_group.astype(np.int64), np.full(k, -1, dtype=np.int64)],
        "curve_group": [np.full(m, -1, dtype=np.int64), g.line_group.astype(np.int64)],
    }
    for name, v in data.items():
        cd[name] = [v, np.full(k, np.nan)]
    meshio.write(str(path), meshio.Mesh(_pad3(pts), cells, cell_data=cd), file_format="vtu")


def _abaqus(
    path: Path, pts: FloatArray, quads: IntArray, g: MeshGroups, data: dict[str, FloatArray]
) -> None:
    kind = ABAQUS_PLANE_QUAD if pts.shape[1] == 2 else ABAQUS_SHELL_QUAD
    with open(path, "w", encoding="ascii") as f:
        f.write("*HEADING\nmedax quad mesh with groups\n*NODE\n")
        f.writelines(
            f"{k + 1}, " + ", ".join(repr(x) for x in row) + "\n"
            for k, row in enumerate(pts.tolist())
        )
        for i, name in sorted(g.quad_names.items()):
            rows = np.flatnonzero(g.quad_group == i)
            f.write(f"*ELEMENT, TYPE={kind}, ELSET={name}\n")
            q1 = quads[rows] + 1
            f.writelines(
                f"{e + 1}, {a}, {b}, {c}, {d}\n"
                for e, (a, b, c, d) in zip(rows.tolist(), q1.tolist(), strict=True)
            )
        for i, name in sorted(g.line_names.items()):
            ids = np.unique(g.lines[g.line_group == i]) + 1
            f.write(f"*NSET, NSET={name}\n")
            _rows_of(f, ids.tolist(), 16, ", ")


def _rows_of(f: IO[str], values: list[int], per: int, sep: str) -> None:
    for k in range(0, len(values), per):
        f.write(sep.join(str(v) for v in values[k : k + per]) + "\n")


def _nastran(
    path: Path, pts: FloatArray, quads: IntArray, g: MeshGroups, data: dict[str, FloatArray]
) -> None:
    p3 = _pad3(pts)
    if max(len(p3), len(quads)) > 99_999_999:
        raise MeshError("export: Nastran ids are limited to 8 digits")
    xyz = np.array(nastran_real(p3.ravel())).reshape(-1, 3)
    with open(path, "w", encoding="ascii") as f:
        f.write("$ Nastran bulk data written by medax: GRID* + CQUAD4, one PID per face group\n")
        for i, name in sorted(g.quad_names.items()):
            f.write(f"$ PID {i + 1}: {name}\n")
        for i, name in sorted(g.line_names.items()):
            f.write(f"$ SET1 {i + 1}: {name}\n")
        f.write("BEGIN BULK\n")
        f.writelines(
            f"GRID*   {k + 1:<16d}{'':16s}{x}{y}\n*       {z}\n"
            for k, (x, y, z) in enumerate(xyz.tolist())
        )
        q1 = quads + 1
        pid = g.quad_group + 1
        f.writelines(
            f"CQUAD4  {e + 1:<8d}{p:<8d}{a:<8d}{b:<8d}{c:<8d}{d:<8d}\n"
            for e, (p, (a, b, c, d)) in enumerate(zip(pid.tolist(), q1.tolist(), strict=True))
        )
        for i in sorted(g.line_names):
            ids = (np.unique(g.lines[g.line_group == i]) + 1).tolist()
            _set1(f, i + 1, ids)
        f.write("ENDDATA\n")


def _set1(f: IO[str], sid: int, ids: list[int]) -> None:
    """A small-field SET1 card: SID then 7 grid ids on the first line, 8 per continuation."""
    head, rest = ids[:7], ids[7:]
    f.write(f"SET1    {sid:<8d}" + "".join(f"{v:<8d}" for v in head) + "\n")
    for k in range(0, len(rest), 8):
        f.write("        " + "".join(f"{v:<8d}" for v in rest[k : k + 8]) + "\n")
