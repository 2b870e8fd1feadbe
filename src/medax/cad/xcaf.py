"""STEP files with a colour and a name per face (XCAF), so that a CAD viewer shows what medax
did: faces coloured by class (``medax classify --step``) or by merged group (``medax
simplify``).

The shape goes into an XCAF document (``XCAFDoc_ShapeTool``); each face becomes a sub-shape
label with a surface colour (``XCAFDoc_ColorTool``, ``XCAFDoc_ColorSurf``) and a
``TDataStd_Name``; ``STEPCAFControl_Writer`` writes the colours as ``STYLED_ITEM`` entities and
the names as the names of the ``ADVANCED_FACE`` entities (OCCT's
``write.stepcaf.subshapes.name``, switched on for the call only). Colours are the pictures'
0-1 sRGB values; OCCT keeps colours linear inside and writes sRGB, so they are handed over
and read back as ``Quantity_TOC_sRGB``: the file holds the pictures' numbers.
The geometry written is that of the plain writer; a reader that ignores styles gets the same
solid.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.Quantity import Quantity_Color, Quantity_TOC_sRGB
from OCP.STEPCAFControl import STEPCAFControl_Reader, STEPCAFControl_Writer
from OCP.STEPControl import STEPControl_AsIs
from OCP.TCollection import TCollection_ExtendedString
from OCP.TDataStd import TDataStd_Name
from OCP.TDF import TDF_AttributeIterator, TDF_ChildIterator
from OCP.TDocStd import TDocStd_Document
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.XCAFApp import XCAFApp_Application
from OCP.XCAFDoc import XCAFDoc_ColorSurf, XCAFDoc_ColorTool, XCAFDoc_DocumentTool

from medax.cad.simplify.occ import shape_map
from medax.errors import CadError

RGB = tuple[float, float, float]
#: OCCT's switches for face (sub-shape) names in STEP, off by default
_WRITE_NAMES = "write.stepcaf.subshapes.name"
_READ_NAMES = "read.stepcaf.subshapes.name"


@dataclass(frozen=True)
class FaceStyle:
    """A face of the shape to write, with its colour and name.

    Attributes
    ----------
    face : TopoDS_Face
        The face.
    rgb : tuple of float
        Its colour, sRGB components in 0-1.
    name : str
        Its name in the STEP file.
    """

    face: Any
    rgb: RGB
    name: str


@dataclass(frozen=True)
class StyledFace:
    """A face read from a STEP file, with its colour and name.

    Attributes
    ----------
    face : TopoDS_Face
        The face.
    rgb : tuple of float or None
        Its colour, sRGB components in 0-1 (None: none).
    name : str or None
        Its name (None: none).
    """

    face: Any
    rgb: RGB | None
    name: str | None


def _new_document() -> Any:
    doc = TDocStd_Document(TCollection_ExtendedString("MDTV-XCAF"))
    XCAFApp_Application.GetApplication_s().InitDocument(doc)
    return doc


@contextlib.contextmanager
def _static(name: str, value: int) -> Iterator[None]:
    """Set OCCT's integer parameter ``name`` for the block, then restore it."""
    old = Interface_Static.IVal_s(name)
    Interface_Static.SetIVal_s(name, value)
    try:
        yield
    finally:
        Interface_Static.SetIVal_s(name, old)


def write_styled_step(
    shape: Any, path: str | Path, styles: Sequence[FaceStyle], name: str = "", label: Any = None
) -> None:
    """Write a shape as STEP (AP214) with a colour and a name per face.

    Faces not in ``styles`` get no colour. A shape placed by locations (a located solid, as
    readers return some parts, or a compound of them) is written as an assembly: each placed
    piece once, unplaced, as a part whose faces carry the styles, and placed by its
    component's location (styled directly, OCCT's writer loses the names of most located
    faces).

    Parameters
    ----------
    shape : TopoDS_Shape
        The shape to write.
    path : str or Path
        The STEP file.
    styles : sequence of FaceStyle
        The faces' colours and names ([FaceStyle][medax.cad.xcaf.FaceStyle]).
    name : str
        The product's name.
    label : str, optional
        The file's name in messages (default ``path``).

    Raises
    ------
    CadError
        OCCT fails to transfer or write the shape.
    """
    where = path if label is None else label
    doc = _new_document()
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    colours = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())

    def style(part: Any, s: FaceStyle, face: Any) -> None:
        sub = shapes.AddSubShape(part, face)
        if sub.IsNull():
            raise CadError(f"{where}: a styled face is not a face of the shape written")
        r, g, b = (min(max(float(v), 0.0), 1.0) for v in s.rgb)
        colours.SetColor(sub, Quantity_Color(r, g, b, Quantity_TOC_sRGB), XCAFDoc_ColorSurf)
        TDataStd_Name.Set_s(sub, TCollection_ExtendedString(s.name))

    pieces = _placed_pieces(shape)
    if pieces is None:
        top = shapes.AddShape(shape, False)
        for s in styles:
            style(top, s, s.face)
    else:
        top = shapes.NewShape()
        maps = [shape_map(piece, TopAbs_FACE) for piece, _ in pieces]
        protos = []
        for k, (piece, loc) in enumerate(pieces):
            proto = shapes.AddShape(piece.Located(TopLoc_Location()), False)
            TDataStd_Name.Set_s(proto, TCollection_ExtendedString(f"{name or 'part'} {k}"))
            shapes.AddComponent(top, proto, loc)
            protos.append(proto)
        for s in styles:
            owner = next((k for k, m in enumerate(maps) if m.FindIndex(s.face) > 0), None)
            if owner is None:
                raise CadError(f"{where}: a styled face is not a face of the shape written")
            # the face as in the unplaced piece: the piece's location taken off
            rel = pieces[owner][1].Inverted().Multiplied(s.face.Location())
            style(protos[owner], s, s.face.Located(rel))
        shapes.UpdateAssemblies()
    if name:
        TDataStd_Name.Set_s(top, TCollection_ExtendedString(name))
    writer = STEPCAFControl_Writer()  # defines the STEP parameters (Interface_Static)
    writer.SetColorMode(True)
    writer.SetNameMode(True)
    with _static(_WRITE_NAMES, 1):
        if not writer.Transfer(doc, STEPControl_AsIs):
            raise CadError(f"{where}: the shape could not be transferred to STEP")
    if writer.Write(str(path)) != IFSelect_RetDone:
        raise CadError(f"{where}: writing the STEP file failed")


def _placed_pieces(shape: Any) -> list[tuple[Any, Any]] | None:
    """None when no face of ``shape`` is placed by a location; else its pieces (``shape``
    itself, or a compound's children) with their locations."""
    from OCP.TopAbs import TopAbs_COMPOUND
    from OCP.TopoDS import TopoDS_Iterator

    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More() and exp.Current().Location().IsIdentity():
        exp.Next()
    if not exp.More():
        return None
    if shape.ShapeType() != TopAbs_COMPOUND:
        return [(shape, shape.Location())]
    out = []
    it = TopoDS_Iterator(shape)  # children with the compound's location composed
    while it.More():
        out.append((it.Value(), it.Value().Location()))
        it.Next()
    return out


def read_styled_step(path: str | Path) -> tuple[Any, list[StyledFace]]:
    """Read a STEP file's first shape with its faces' colours and names.

    Colours and names are those OCCT's XCAF reader finds: on the face, or on the face of
    the part an assembly places.

    Parameters
    ----------
    path : str or Path
        The STEP file.

    Returns
    -------
    shape : TopoDS_Shape
        The first shape of the file.
    faces : list of StyledFace
        Its faces in explorer order, with colours and names
        ([StyledFace][medax.cad.xcaf.StyledFace]).

    Raises
    ------
    CadError
        The file cannot be read.
    """
    reader = STEPCAFControl_Reader()
    reader.SetColorMode(True)
    reader.SetNameMode(True)
    doc = _new_document()
    with _static(_READ_NAMES, 1):
        if reader.ReadFile(str(path)) != IFSelect_RetDone or not reader.Transfer(doc):
            raise CadError(f"{path}: cannot be read as STEP")
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    colours = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())
    # the shape tool's children are the shapes, the first the part or its assembly (a
    # sequence of labels from GetFreeShapes crashes OCP 8's binding: the labels are walked)
    labels = _children(shapes.Label())
    if not labels:
        raise CadError(f"{path}: holds no shape")
    shape = shapes.GetShape_s(labels[0])
    # every styled sub-shape label of every part: its face (unplaced), colour and name
    styled = []
    for part in labels:
        for sub in _children(part):
            face = shapes.GetShape_s(sub)
            if face.IsNull() or face.ShapeType() != TopAbs_FACE:
                continue
            colour = Quantity_Color()
            rgb = None
            if XCAFDoc_ColorTool.GetColor_s(sub, XCAFDoc_ColorSurf, colour):
                rgb = _srgb(colour)
            styled.append((face, rgb, _name(sub)))
    out = []
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        face = exp.Current()
        # the same face in the part (placed or not): the same underlying TShape
        match = next((m for m in styled if m[0].IsPartner(face)), None)
        colour = Quantity_Color()
        rgb = match[1] if match else None
        if rgb is None and colours.GetColor(face, XCAFDoc_ColorSurf, colour):
            rgb = _srgb(colour)
        out.append(StyledFace(face, rgb, match[2] if match else None))
        exp.Next()
    return shape, out


def _children(label: Any) -> list[Any]:
    it = TDF_ChildIterator(label, False)
    out = []
    while it.More():
        out.append(it.Value())
        it.Next()
    return out


def _srgb(colour: Any) -> RGB:
    r, g, b = colour.Values(Quantity_TOC_sRGB)
    return (float(r), float(g), float(b))


def _name(label: Any) -> str | None:
    """The ``TDataStd_Name`` of ``label``, if any (``FindAttribute`` with a name crashes
    OCP 8's binding: the attributes are walked)."""
    it = TDF_AttributeIterator(label)
    while it.More():
        attr = it.Value()
        if isinstance(attr, TDataStd_Name):
            return str(attr.Get().ToExtString())
        it.Next()
    return None


def _solid_prefix(k: int, n: int) -> str:
    return f"solid {k} " if n > 1 else ""


def class_styles(classifications: Sequence[Any]) -> list[FaceStyle]:
    """Give each face of classified solids its class's colour and a name.

    Parameters
    ----------
    classifications : sequence of Classification
        The solids' classifications ([Classification][medax.cad.model.Classification]).

    Returns
    -------
    list of FaceStyle
        Per face: the class's colour of the pictures and a name such as ``fillet 12 r=2.5``
        (``solid k`` in front when there are several solids).
    """
    from medax.viz.view3d import CLASS_COLOURS

    out = []
    for k, c in enumerate(classifications):
        pre = _solid_prefix(k, len(classifications))
        for f in c.faces:
            cls = f.cls.value
            radius = "" if f.radius is None else f" r={f.radius:.6g}"
            name = f"{pre}{cls.replace('_', ' ')} {f.index}{radius}"
            out.append(FaceStyle(c.face(f.index), CLASS_COLOURS[cls], name))
    return out


def group_styles(shapes: Sequence[Any], reports: Sequence[dict[str, Any]]) -> list[FaceStyle]:
    """Give each face of simplified solids its merged group's colour and a name.

    Parameters
    ----------
    shapes : sequence of TopoDS_Shape
        The simplified solids.
    reports : sequence of dict
        Their simplify reports (``face_groups``, ``blends_kept``), in the same order.

    Returns
    -------
    list of FaceStyle
        Per face: a merged face in its group's colour of the before/after picture, named
        ``merged from faces 3,7,9 (fillet halves 7,9)``; a kept blend black, named
        ``kept blend 12 r=2.5: REASON``; an untouched face grey, named ``face 5`` (its
        index in the input).
    """
    from OCP.TopoDS import TopoDS

    from medax.cad.simplify.occ import shape_map
    from medax.viz.before_after import KEPT, group_colour

    out = []
    key = 0  # the groups are numbered over all solids, as in the picture of one solid
    for k, (shape, rep) in enumerate(zip(shapes, reports, strict=True)):
        pre = _solid_prefix(k, len(shapes))
        fmap = shape_map(shape, TopAbs_FACE)
        kept = {b["face"]: b for b in rep["blends_kept"]}
        for g in rep["face_groups"]:
            face = TopoDS.Face(fmap.FindKey(g["new_face"] + 1))
            whole, halves = g["original_faces"], g["fillet_halves"]
            if halves:
                faces = ",".join(str(i) for i in sorted({*whole, *halves}))
                name = f"{pre}merged from faces {faces} (fillet halves "
                name += ",".join(str(i) for i in halves) + ")"
                out.append(FaceStyle(face, group_colour(key), name))
                key += 1
                continue
            blend = next((kept[i] for i in whole if i in kept), None)
            if blend is not None:
                r = blend.get("radius")
                radius = "" if r is None else f" r={r:.6g}"
                name = f"{pre}kept blend {blend['face']}{radius}: {blend['reason']}"
                out.append(FaceStyle(face, KEPT, name))
            else:
                faces = ",".join(str(i) for i in whole)
                out.append(FaceStyle(face, group_colour(-1), f"{pre}face {faces}"))
    return out
