"""Read STEP / IGES / OCCT BRep files into healed solids.

Every OCCT failure is caught here and re-raised as a one-line
[CadError][medax.errors.CadError] naming the file. Healing: ``ShapeFix_Shape``, then
``ShapeUpgrade_UnifySameDomain`` merges faces (and edges) lying on the same surface so split
faces do not inflate counts; a step that would leave the solid invalid is left out
(``Part.notes`` says which). STEP and IGES shapes
are converted by OCCT to millimetres; ``Part.file_unit`` is the unit named in the file.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy, BRepBuilderAPI_MakeSolid
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepTools import BRepTools
from OCP.IFSelect import IFSelect_RetDone
from OCP.ShapeFix import ShapeFix_Shape, ShapeFix_Solid
from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID, TopAbs_VERTEX
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Shape

from medax.cad.file_check import check_cad_file
from medax.errors import CadError

log = logging.getLogger(__name__)

EXTENSIONS = {
    ".step": "step",
    ".stp": "step",
    ".iges": "iges",
    ".igs": "iges",
    ".brep": "brep",
    ".brp": "brep",
}
"""The file extensions understood (lower case), by format."""


@dataclass(frozen=True)
class Part:
    """The healed solids of one CAD file.

    Lengths are in ``unit``: ``"mm"`` for STEP and IGES (OCCT converts), ``"model"`` for
    BRep (which stores no unit).

    Attributes
    ----------
    source : str
        The file read.
    solids : tuple
        ``TopoDS_Solid`` objects, in file order.
    unit : str
        Length unit of the solids: ``"mm"`` or ``"model"``.
    file_unit : str
        The length unit the file declares (``""`` when it declares none, e.g. BRep).
    notes : tuple of str
        What healing did (shells made solids, loose faces sewn).
    """

    source: str
    solids: tuple[Any, ...]
    unit: str = "mm"
    file_unit: str = ""
    notes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        unit = f", file unit {self.file_unit}" if self.file_unit else ""
        return f"Part({self.source}: {len(self.solids)} solids, lengths in {self.unit}{unit})"


def read_part(path: str | Path, unify: bool = True) -> Part:
    """Read a STEP, IGES or BRep file into healed solids.

    The format comes from the extension (``EXTENSIONS``). Closed shells are made solids,
    loose faces are sewn; each solid is healed by [heal][medax.cad.reader.heal].

    Parameters
    ----------
    path : str or Path
        The file.
    unify : bool
        Merge faces and edges lying on the same surface (``ShapeUpgrade_UnifySameDomain``).

    Returns
    -------
    Part
        The solids, in mm for STEP and IGES ([Part][medax.cad.reader.Part]).

    Raises
    ------
    CadError
        One line naming the file: a missing, empty, unreadable, truncated or appended-to
        file, content of another format than the extension, an unknown extension, a file
        with no solid, or a shell that is not closed.
    """
    p = Path(path)
    fmt = EXTENSIONS.get(p.suffix.lower())
    if fmt is None:
        known = ", ".join(sorted(EXTENSIONS))
        raise CadError(f"{p}: unknown extension '{p.suffix}' (expected one of {known})")
    if p.is_dir():
        raise CadError(f"{p}: is a folder, not a file")
    if not p.is_file():
        raise CadError(f"{p}: no such file")
    if p.stat().st_size == 0:
        raise CadError(f"{p}: file is empty")
    check_cad_file(p, fmt)  # OCCT crashes or loops on some truncated files
    try:
        with quiet_occt():
            shape, file_unit = _READERS[fmt](p)
    except CadError:
        raise
    except Exception as err:  # OCCT raises Standard_Failure subclasses
        raise CadError(f"{p}: could not be read as {fmt.upper()} ({err})") from err
    if shape is None or shape.IsNull():
        raise CadError(f"{p}: no shape could be read (truncated or not a {fmt.upper()} file?)")
    notes: list[str] = []
    solids = _solids(shape, p, notes)
    healed = []
    for k, s in enumerate(solids):
        said: list[str] = []
        healed.append(heal(s, p, unify=unify, notes=said))
        notes += [f"solid {k + 1}: {n}" if len(solids) > 1 else n for n in said]
    if len(healed) > 1:
        notes.append(f"{len(healed)} solids; each is classified separately")
    for n in notes:
        log.info("%s: %s", p, n)
    unit = "mm" if fmt in ("step", "iges") else "model"
    return Part(str(p), tuple(healed), unit, file_unit, tuple(notes))


@contextmanager
def quiet_occt() -> Iterator[None]:
    """Silence OCCT's messages within the block.

    OCCT's parsers print to stdout; its default message printers are detached meanwhile and
    restored on exit.
    """
    from OCP.Message import Message

    messenger = Message.DefaultMessenger_s()
    printers = list(messenger.Printers())
    for pr in printers:
        messenger.RemovePrinter(pr)
    try:
        yield
    finally:
        for pr in printers:
            messenger.AddPrinter(pr)


def heal(
    solid: Any, where: str | Path = "shape", unify: bool = True, notes: list[str] | None = None
) -> Any:
    """Heal a solid with ``ShapeFix_Shape``, then merge same-surface faces and edges; never
    return an invalid solid where a valid one was at hand.

    Merging can leave a valid solid invalid (seen: one cone face of a real part), and so
    can healing (seen: B-spline faces sharing one surface, their wires left open in their
    parameters). The first valid of: the healed solid merged (faces and edges; where
    merging the edges breaks faces, the edges of the faces they came from left as they
    are; else faces only); the healed solid unmerged; the solid as given, merged when that
    stays valid. When none is valid (an invalid input healing does not mend), the healed
    and merged solid.

    Parameters
    ----------
    solid : TopoDS_Solid
        The solid (not modified).
    where : str or Path
        Names the source in error messages.
    unify : bool
        Merge faces and edges on the same surface (``ShapeUpgrade_UnifySameDomain``).
    notes : list of str, optional
        Receives a line for each fallback taken (which, and why).

    Returns
    -------
    TopoDS_Solid
        The healed solid.

    Raises
    ------
    CadError
        Healing failed or lost the solid.
    """
    try:
        fixed = _fixed(solid, where)
        said: list[str] = []
        merged = _merged(fixed, said) if unify else None
        if merged is not None:
            _note(notes, where, *said)
            return merged
        if _valid(fixed):
            if unify:
                _note(
                    notes,
                    where,
                    "faces on one surface left unmerged (merging them left the solid invalid)",
                )
            return fixed
        if not _valid(solid):
            return _unify(fixed, True)[0] if unify else fixed
        said = []
        plain = (_merged(_copy(solid), said) if unify else None) or solid
    except CadError:
        raise
    except Exception as err:
        raise CadError(f"{where}: healing failed ({err})") from err
    _note(
        notes,
        where,
        "read as in the file, not healed (healing left the valid solid invalid)",
        *said,
    )
    return plain


def _merged(solid: Any, notes: list[str]) -> Any | None:
    """``solid`` with its faces on one surface merged, and its edges on one curve, valid;
    None when no merge stays valid. Where merging the edges leaves faces invalid, the
    edges of the faces those came from stay as they are; else the edges all stay."""
    out, history = _unify(solid, True)
    if _valid(out):
        return out
    bad = [f for f in _all(out, TopAbs_FACE) if not _valid(f)]
    sources = [
        f
        for f in _all(solid, TopAbs_FACE)
        if any(f.IsSame(b) or any(m.IsSame(b) for m in history.Modified(f)) for b in bad)
    ]
    if sources:
        out, _ = _unify(solid, True, [v for f in sources for v in _all(f, TopAbs_VERTEX)])
        if _valid(out):
            notes.append(
                f"edges around {len(bad)} face{'s' * (len(bad) > 1)} left unmerged "
                "(merging them left the solid invalid)"
            )
            return out
    out, _ = _unify(solid, False)
    if _valid(out):
        notes.append("edges on one curve left unmerged (merging them left the solid invalid)")
        return out
    return None


def _fixed(solid: Any, where: str | Path) -> Any:
    """A copy of ``solid`` healed by ``ShapeFix_Shape`` (which changes the edges and curves
    it is given in place, shared with the solid: seen breaking a valid solid)."""
    fix = ShapeFix_Shape(_copy(solid))
    fix.Perform()
    return _solid_of(fix.Shape(), where)


def _copy(solid: Any) -> Any:
    """A copy of ``solid`` with its own geometry."""
    return BRepBuilderAPI_Copy(solid, True, False).Shape()


def _unify(solid: Any, edges: bool, keep: Sequence[Any] = ()) -> tuple[Any, Any]:
    """``solid`` with its faces on one surface merged, and its edges on one curve when
    ``edges`` but at the vertices ``keep``; and the merge's history."""
    u = ShapeUpgrade_UnifySameDomain(solid, edges, True, False)
    for v in keep:
        u.KeepShape(v)
    u.Build()
    return _solid_of(u.Shape(), ""), u.History()


def _solid_of(shape: Any, where: str | Path) -> Any:
    """The first solid of ``shape``."""
    out = _first(shape, TopAbs_SOLID)
    if out is None:
        raise CadError(f"{where}: healing lost the solid")
    return TopoDS.Solid(out)


def _valid(shape: Any) -> bool:
    """OCCT's validity check (``BRepCheck_Analyzer``)."""
    return bool(BRepCheck_Analyzer(shape).IsValid())


def _note(notes: list[str] | None, where: str | Path, *what: str) -> None:
    """Add the lines ``what`` to ``notes``, or log them when there are none."""
    for w in what:
        if notes is None:
            log.info("%s: %s", where, w)
        else:
            notes.append(w)


def count(shape: Any, kind: Any) -> int:
    """Count the distinct sub-shapes of one kind.

    Parameters
    ----------
    shape : TopoDS_Shape
        The shape.
    kind : TopAbs_ShapeEnum
        The kind, e.g. ``TopAbs_FACE``.

    Returns
    -------
    int
        Number of distinct sub-shapes of ``kind`` in ``shape``.
    """
    from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as IMap

    m = IMap()
    TopExp.MapShapes_s(shape, kind, m)
    return int(m.Extent())


# ---- format readers ----------------------------------------------------------------------
def _read_step(p: Path) -> tuple[TopoDS_Shape | None, str]:
    from OCP.collections import Sequence_TCollection_AsciiString as Seq
    from OCP.STEPControl import STEPControl_Reader

    reader = STEPControl_Reader()
    status = reader.ReadFile(str(p))
    if status != IFSelect_RetDone:
        raise CadError(f"{p}: not a readable STEP file (syntax error, truncated or not STEP)")
    lengths, angles, solid_angles = Seq(), Seq(), Seq()
    unit = ""
    try:
        reader.FileUnits(lengths, angles, solid_angles)
        if lengths.Length() > 0:
            unit = str(lengths.Value(1).ToCString()).lower()
    except Exception:  # units are informative only
        unit = ""
    if reader.NbRootsForTransfer() == 0:
        raise CadError(f"{p}: STEP file holds no shape (truncated or empty model?)")
    reader.TransferRoots()
    if reader.NbShapes() == 0:
        raise CadError(f"{p}: STEP file holds no transferable shape")
    return reader.OneShape(), unit


def _read_iges(p: Path) -> tuple[TopoDS_Shape | None, str]:
    from OCP.IGESControl import IGESControl_Reader

    reader = IGESControl_Reader()
    status = reader.ReadFile(str(p))
    if status != IFSelect_RetDone:
        raise CadError(f"{p}: not a readable IGES file (syntax error, truncated or not IGES)")
    reader.TransferRoots()
    if reader.NbShapes() == 0:
        raise CadError(f"{p}: IGES file holds no transferable shape")
    return reader.OneShape(), ""


def _read_brep(p: Path) -> tuple[TopoDS_Shape | None, str]:
    shape = TopoDS_Shape()
    ok = BRepTools.Read_s(shape, str(p), BRep_Builder())
    if not ok:
        raise CadError(f"{p}: not a readable BRep file")
    return shape, ""


_READERS = {"step": _read_step, "iges": _read_iges, "brep": _read_brep}


# ---- solids -------------------------------------------------------------------------------
def _first(shape: Any, kind: Any) -> Any:
    exp = TopExp_Explorer(shape, kind)
    return exp.Current() if exp.More() else None


def _all(shape: Any, kind: Any) -> list[Any]:
    out = []
    exp = TopExp_Explorer(shape, kind)
    while exp.More():
        out.append(exp.Current())
        exp.Next()
    return out


def _solids(shape: Any, p: Path, notes: list[str]) -> list[Any]:
    """The solids of ``shape``; closed shells are made solids, open shells refused."""
    solids = [TopoDS.Solid(s) for s in _all(shape, TopAbs_SOLID)]
    if solids:
        return solids
    shells = [TopoDS.Shell(s) for s in _all(shape, TopAbs_SHELL)]
    if not shells and count(shape, TopAbs_FACE) > 0:
        shells = _sew(shape, p)
        notes.append(f"{count(shape, TopAbs_FACE)} loose faces sewn into {len(shells)} shells")
    if not shells:
        nf, ne, nv = (count(shape, k) for k in (TopAbs_FACE, TopAbs_EDGE, TopAbs_VERTEX))
        what = f"{nf} faces" if nf else (f"{ne} curves" if ne else f"{nv} points")
        raise CadError(f"{p}: no solid in the file (only {what})")
    out = []
    for k, shell in enumerate(shells):
        free = _free_edges(shell)
        if free:
            raise CadError(f"{p}: shell {k} is not closed ({free} free edges); need a solid")
        mk = BRepBuilderAPI_MakeSolid(shell)
        fix = ShapeFix_Solid(mk.Solid())
        fix.Perform()
        solid = _first(fix.Solid(), TopAbs_SOLID)
        if solid is None or not BRepCheck_Analyzer(solid).IsValid():
            raise CadError(f"{p}: shell {k} could not be made a valid solid")
        out.append(TopoDS.Solid(solid))
        notes.append(f"shell {k} made a solid")
    return out


def _sew(shape: Any, p: Path) -> list[Any]:
    """Sew the loose faces of ``shape`` (e.g. an IGES surface model) into shells."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing

    sew = BRepBuilderAPI_Sewing(1e-6)
    for f in _all(shape, TopAbs_FACE):  # never called with no face: sewing nothing crashes
        sew.Add(f)
    try:
        sew.Perform()
        sewn = sew.SewedShape()
    except Exception as err:
        raise CadError(f"{p}: sewing its loose faces failed ({err})") from err
    return [TopoDS.Shell(s) for s in _all(sewn, TopAbs_SHELL)]


def _free_edges(shell: Any) -> int:
    """Number of edges of ``shell`` bounding only one face (seams excluded)."""
    from OCP.collections import (
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as EFMap,
    )

    m = EFMap()
    TopExp.MapShapesAndAncestors_s(shell, TopAbs_EDGE, TopAbs_FACE, m)
    free = 0
    for i in range(1, m.Extent() + 1):
        edge = TopoDS.Edge(m.FindKey(i))
        if BRep_Tool.Degenerated_s(edge):
            continue
        faces = m.FindFromIndex(i)
        if faces.Size() == 1 and not BRep_Tool.IsClosed_s(edge, TopoDS.Face(faces.First())):
            free += 1
    return free
