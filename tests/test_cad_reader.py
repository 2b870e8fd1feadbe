"""Reading STEP / IGES / BRep files, healing, several solids, and bad input."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("OCP")

from OCP.BRep import BRep_Builder  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge  # noqa: E402
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox  # noqa: E402
from OCP.BRepTools import BRepTools  # noqa: E402
from OCP.gp import gp_Pnt  # noqa: E402
from OCP.IGESControl import IGESControl_Writer  # noqa: E402
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer  # noqa: E402
from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS, TopoDS_Compound, TopoDS_Shell  # noqa: E402

from medax.cad import parts, reader  # noqa: E402
from medax.cad.classify import classify_file, classify_solid  # noqa: E402
from medax.cad.reader import count, read_part  # noqa: E402
from medax.errors import CadError  # noqa: E402


def write_step(shape, path: Path) -> Path:
    w = STEPControl_Writer()
    w.Transfer(shape, STEPControl_AsIs)
    assert int(w.Write(str(path))) == 1  # IFSelect_RetDone
    return path


def test_step_round_trip_keeps_the_classification(tmp_path):
    built = parts.plate_with_boss()
    direct = classify_solid(built.shape).counts()
    path = write_step(built.shape, tmp_path / "boss.step")
    part = read_part(path)
    assert part.unit == "mm" and part.file_unit.startswith("milli")
    assert len(part.solids) == 1
    (c,) = classify_file(str(path))
    assert c.counts() == direct
    assert c.source == str(path)


def test_brep_and_iges_are_read(tmp_path):
    built = parts.pocket()
    brep = tmp_path / "pocket.brep"
    assert BRepTools.Write_s(built.shape, str(brep))
    assert classify_file(str(brep))[0].counts()["fillet"] == 4
    iges = tmp_path / "pocket.igs"
    w = IGESControl_Writer("MM", 1)
    w.AddShape(built.shape)
    w.ComputeModel()
    assert w.Write(str(iges))
    part = read_part(iges)
    assert len(part.solids) == 1
    assert count(part.solids[0], TopAbs_FACE) == count(built.shape, TopAbs_FACE)


def test_unify_same_domain_merges_split_faces(tmp_path):
    """Two boxes fused side by side: 11 split faces before, a single 6-face box after."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse

    a = BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape()
    b = BRepPrimAPI_MakeBox(gp_Pnt(10.0, 0.0, 0.0), 10.0, 10.0, 10.0).Shape()
    fused = BRepAlgoAPI_Fuse(a, b).Shape()
    assert count(fused, TopAbs_FACE) == 10
    path = write_step(fused, tmp_path / "fused.step")
    assert count(read_part(path).solids[0], TopAbs_FACE) == 6
    assert count(read_part(path, unify=False).solids[0], TopAbs_FACE) == 10


def _inside_out_box():
    """A 10 mm box with one face reversed in its shell: invalid to OCCT's analyzer, and
    ``ShapeFix_Shape`` mends it."""
    from OCP.TopoDS import TopoDS_Solid

    box = BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape()
    b = BRep_Builder()
    shell = TopoDS_Shell()
    b.MakeShell(shell)
    e = TopExp_Explorer(box, TopAbs_FACE)
    first = True
    while e.More():
        b.Add(shell, e.Current().Reversed() if first else e.Current())
        first = False
        e.Next()
    solid = TopoDS_Solid()
    b.MakeSolid(solid)
    b.Add(solid, shell)
    assert not BRepCheck_Analyzer(solid).IsValid()
    return solid


def test_healing_mends_an_invalid_solid():
    notes: list[str] = []
    healed = reader.heal(_inside_out_box(), notes=notes)
    assert BRepCheck_Analyzer(healed).IsValid() and notes == []


def test_a_merge_that_breaks_the_solid_is_left_out(monkeypatch):
    """Merging edges left a real part (MVE_100-3) with an invalid cone face: the faces are
    then merged without the edges. The broken merge is stood in for by a real invalid solid."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse

    a = BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape()
    b = BRepPrimAPI_MakeBox(gp_Pnt(10.0, 0.0, 0.0), 10.0, 10.0, 10.0).Shape()
    fused = TopoDS.Solid(TopExp_Explorer(BRepAlgoAPI_Fuse(a, b).Shape(), TopAbs_SOLID).Current())
    merge = reader._unify

    def broken(s, edges, keep=()):
        out, history = merge(s, edges, keep)
        return (_inside_out_box() if edges else out), history

    monkeypatch.setattr(reader, "_unify", broken)
    notes: list[str] = []
    healed = reader.heal(fused, notes=notes)
    assert BRepCheck_Analyzer(healed).IsValid()
    assert count(healed, TopAbs_FACE) == 6  # the faces merged all the same
    assert notes == ["edges on one curve left unmerged (merging them left the solid invalid)"]


def test_healing_that_breaks_a_valid_solid_is_not_kept(monkeypatch, tmp_path):
    """Seen on a written part: ``ShapeFix_Shape`` left three B-spline faces of a valid
    solid open in their parameters. The broken healing is stood in for by a real invalid
    solid; the file's own solid is read instead, and the part's notes say so."""
    built = parts.plate_with_boss()
    path = write_step(built.shape, tmp_path / "boss.step")
    monkeypatch.setattr(reader, "_fixed", lambda s, where: _inside_out_box())
    part = read_part(path)
    (solid,) = part.solids
    assert BRepCheck_Analyzer(solid).IsValid()
    assert count(solid, TopAbs_FACE) == count(built.shape, TopAbs_FACE)
    assert part.notes == ("read as in the file, not healed (healing left the valid solid invalid)",)


def test_several_solids_each_classified(tmp_path):
    comp = TopoDS_Compound()
    bld = BRep_Builder()
    bld.MakeCompound(comp)
    bld.Add(comp, parts.pocket().shape)
    bld.Add(comp, parts.stepped_shaft().shape)
    path = write_step(comp, tmp_path / "two.step")
    part = read_part(path)
    assert len(part.solids) == 2
    assert any("2 solids" in n for n in part.notes)
    cs = classify_file(str(path))
    assert sorted(c.counts()["fillet"] for c in cs) == [2, 4]
    assert [c.solid for c in cs] == [0, 1]


# ---- bad input ----------------------------------------------------------------------------
def _err(path: Path) -> str:
    with pytest.raises(CadError) as info:
        read_part(path)
    msg = str(info.value)
    assert "\n" not in msg and str(path) in msg
    return msg


def test_missing_file(tmp_path):
    assert "no such file" in _err(tmp_path / "nope.step")


def test_empty_file(tmp_path):
    p = tmp_path / "empty.step"
    p.write_bytes(b"")
    assert "empty" in _err(p)


def test_truncated_step(tmp_path):
    full = write_step(parts.pocket().shape, tmp_path / "full.step").read_bytes()
    for frac in (0.1, 0.5, 0.9):
        p = tmp_path / f"cut{frac}.step"
        p.write_bytes(full[: int(frac * len(full))])
        _err(p)


def test_garbage_with_step_extension(tmp_path):
    p = tmp_path / "junk.stp"
    p.write_text("this is not a STEP file\n")
    assert "not a STEP file (it does not start with ISO-10303-21;)" in _err(p)


def test_unknown_extension(tmp_path):
    p = tmp_path / "part.obj"
    p.write_text("v 0 0 0\n")
    assert "unknown extension" in _err(p)


def test_step_with_only_a_curve(tmp_path):
    edge = BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 2, 3)).Edge()
    p = write_step(edge, tmp_path / "curve.step")
    assert "no solid" in _err(p)


def test_open_shell(tmp_path):
    box = BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape()
    shell = TopoDS_Shell()
    bld = BRep_Builder()
    bld.MakeShell(shell)
    exp = TopExp_Explorer(box, TopAbs_FACE)
    for _ in range(5):  # five of six faces: an open box
        bld.Add(shell, TopoDS.Face(exp.Current()))
        exp.Next()
    p = tmp_path / "open.brep"
    assert BRepTools.Write_s(shell, str(p))
    assert "not closed" in _err(p)


def test_closed_shell_is_made_a_solid(tmp_path):
    box = BRepPrimAPI_MakeBox(10.0, 10.0, 10.0).Shape()
    exp = TopExp_Explorer(box, TopAbs_SHELL)
    p = tmp_path / "shell.brep"
    assert BRepTools.Write_s(exp.Current(), str(p))
    part = read_part(p)
    assert len(part.solids) == 1 and count(part.solids[0], TopAbs_FACE) == 6


def test_loose_faces_are_sewn_into_a_solid(tmp_path):
    """A closed set of faces without a shell (as IGES surface models are) is sewn."""
    comp = TopoDS_Compound()
    bld = BRep_Builder()
    bld.MakeCompound(comp)
    exp = TopExp_Explorer(parts.pocket().shape, TopAbs_FACE)
    while exp.More():
        bld.Add(comp, exp.Current())
        exp.Next()
    p = tmp_path / "faces.brep"
    assert BRepTools.Write_s(comp, str(p))
    part = read_part(p)
    assert part.unit == "model" and len(part.solids) == 1
    assert any("sewn" in n for n in part.notes)
    (c,) = classify_file(str(p))
    assert c.counts()["fillet"] == 4


def test_loose_open_faces_are_refused(tmp_path):
    comp = TopoDS_Compound()
    bld = BRep_Builder()
    bld.MakeCompound(comp)
    exp = TopExp_Explorer(BRepPrimAPI_MakeBox(5.0, 5.0, 5.0).Shape(), TopAbs_FACE)
    for _ in range(4):
        bld.Add(comp, exp.Current())
        exp.Next()
    p = tmp_path / "four.brep"
    assert BRepTools.Write_s(comp, str(p))
    assert "not closed" in _err(p)


def test_inch_file_is_converted_to_mm(tmp_path):
    """A file whose length unit is the inch reads back in mm (x 25.4); its unit is reported.

    The file is the mm file with its length unit entity replaced by a conversion-based inch.
    """
    import re

    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    box = BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape()
    text = write_step(box, tmp_path / "mm.step").read_text()
    mm = re.search(
        r"#(\d+) = \( LENGTH_UNIT\(\) NAMED_UNIT\(\*\) SI_UNIT\(\.MILLI\.,\.METRE\.\) \);", text
    )
    assert mm is not None
    k = mm.group(1)
    inch = (
        f"#{k} = ( CONVERSION_BASED_UNIT('INCH',#9001) LENGTH_UNIT() NAMED_UNIT(#9002) );\n"
        "#9000 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n"
        "#9001 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#9000);\n"
        "#9002 = DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);"
    )
    path = tmp_path / "inch.step"
    path.write_text(text.replace(mm.group(0), inch))
    part = read_part(path)
    assert part.unit == "mm" and part.file_unit == "inch"
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(part.solids[0], props)
    assert props.Mass() == pytest.approx(6000.0 * 25.4**3, rel=1e-9)
