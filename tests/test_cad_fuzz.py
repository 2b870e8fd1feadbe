"""Damaged and odd CAD files (issue 19): truncated, appended to, renamed, no solid, an open
shell. Each is one line, exit 1, and a pre-existing output stays as it was.

Run in process: the framing checks (``medax.cad.file_check``) keep these files away from
OCCT's readers, which crash the process on some of them (IGES cut at 90 %, BRep cut at 30 %)
or run for minutes (BRep cut at 50 %).
"""

from __future__ import annotations

import pytest
from OCP.BRep import BRep_Builder
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_Sewing,
)
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
from OCP.gp import gp_Pln, gp_Pnt
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer

from medax.cad.file_check import check_cad_file, sniff
from medax.cad.simplify import parts as P
from medax.cad.simplify.step_out import write_shape
from medax.cli.main import main
from medax.errors import CadError

FORMATS = {"step": ".step", "iges": ".igs", "brep": ".brep"}
KEEP = b"a previous output, to be kept\n"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cad")
    shape = P.box_vertical_fillets().shape
    return {fmt: write_shape(shape, d / f"box{ext}").read_bytes() for fmt, ext in FORMATS.items()}


def damaged(files) -> list[tuple[str, str, bytes, str]]:
    """(case, extension, content, expected message) for every damage."""
    out = []
    for fmt, ext in FORMATS.items():
        data = files[fmt]
        for frac in (0.05, 0.3, 0.5, 0.9, 0.99, 0.999):
            out.append((f"{fmt} cut at {frac}", ext, data[: int(len(data) * frac)], "not a whole"))
        out.append((f"{fmt} + text", ext, data + b"garbage ((( END-ISO-10303-21;\n" * 5, "whole"))
        out.append((f"{fmt} + bytes", ext, data + bytes(range(256)) * 4, "not a whole"))
        out.append((f"text + {fmt}", ext, b"hello\n" + data, "it does not start with"))
        out.append((f"{fmt} zeros", ext, b"\0" * 1000, "it does not start with"))
        for other, other_ext in FORMATS.items():
            if other != fmt:
                name = {"step": "STEP", "iges": "IGES", "brep": "BRep"}[fmt]
                out.append((f"{fmt} as {other_ext}", other_ext, data, f"holds {name} data"))
    return out


@pytest.mark.parametrize("command", ["simplify", "classify"])
def test_damaged_files_one_line_output_kept(files, tmp_path, capsys, command):
    cases = damaged(files)
    assert len(cases) == 36
    for k, (case, ext, data, message) in enumerate(cases):
        src = tmp_path / f"in{k}{ext}"
        src.write_bytes(data)
        out = tmp_path / ("out.step" if command == "simplify" else "out.json")
        out.write_bytes(KEEP)
        flag = "-o" if command == "simplify" else "--report"
        assert main([command, str(src), flag, str(out)]) == 1, case
        err = capsys.readouterr().err.strip()
        assert message in err and len(err.splitlines()) == 1, (case, err)
        assert out.read_bytes() == KEEP, case
        src.unlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


def test_whole_files_pass_the_framing_checks(files, tmp_path):
    for fmt, ext in FORMATS.items():
        p = tmp_path / f"ok{ext}"
        p.write_bytes(files[fmt])
        check_cad_file(p, fmt)
        assert sniff(files[fmt][:4096]) == fmt
        crlf = tmp_path / f"crlf{ext}"
        crlf.write_bytes(files[fmt].replace(b"\n", b"\r\n"))
        check_cad_file(crlf, fmt)
    with pytest.raises(CadError, match="holds STEP data, not BRep; rename it .step"):
        check_cad_file(tmp_path / "ok.step", "brep")


def _run(tmp_path, capsys, shape, fmt="step"):
    src = write_shape(shape, tmp_path / f"in{FORMATS[fmt]}")
    out = tmp_path / "out.step"
    out.write_bytes(KEEP)
    code = main(["simplify", str(src), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert out.read_bytes() == KEEP
    return code, err


@pytest.mark.parametrize("fmt", ["step", "brep"])
def test_no_solid(tmp_path, capsys, fmt):
    edge = BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 0, 0)).Edge()
    code, err = _run(tmp_path, capsys, edge, fmt)
    assert code == 1 and len(err) == 1 and "no solid in the file (only 1 curves)" in err[0], err


def test_single_face_is_no_solid(tmp_path, capsys):
    face = BRepBuilderAPI_MakeFace(gp_Pln(), 0.0, 1.0, 0.0, 1.0).Face()
    code, err = _run(tmp_path, capsys, face)
    assert code == 1 and len(err) == 1 and "is not closed" in err[0], err


def test_open_shell(tmp_path, capsys):
    box = BRepPrimAPI_MakeBox(10.0, 20.0, 5.0).Shape()
    sew = BRepBuilderAPI_Sewing(1e-6)
    exp = TopExp_Explorer(box, TopAbs_FACE)
    exp.Next()  # leave the first face out
    while exp.More():
        sew.Add(exp.Current())
        exp.Next()
    sew.Perform()
    code, err = _run(tmp_path, capsys, sew.SewedShape())
    assert code == 1 and len(err) == 1, err
    assert "shell 0 is not closed (4 free edges); need a solid" in err[0]


def test_two_solids_each_simplified(tmp_path, capsys):
    """Two solids are handled one by one (exit 0, per-solid lines)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.TopoDS import TopoDS_Compound

    t = gp_Trsf()
    t.SetTranslation(gp_Vec(100.0, 0.0, 0.0))
    comp = TopoDS_Compound()
    b = BRep_Builder()
    b.MakeCompound(comp)
    b.Add(comp, P.box_vertical_fillets().shape)
    b.Add(comp, BRepBuilderAPI_Transform(BRepPrimAPI_MakeBox(5.0, 5.0, 5.0).Shape(), t).Shape())
    src = write_shape(comp, tmp_path / "two.brep")
    out = tmp_path / "o.step"
    assert main(["simplify", str(src), "-o", str(out)]) == 0
    lines = capsys.readouterr().out
    assert "solid 0: faces 10 -> 6" in lines and "solid 1: faces 6 -> 6" in lines


def test_brep_with_a_trailing_integer_line_is_whole(files, tmp_path):
    """7 of the 34 BRep files of the Analysis Situs blend corpus end with one more integer
    line after the root shape ('+1 0 ', '0'); OCCT reads them, so must the framing check."""
    p = tmp_path / "box.brep"
    p.write_bytes(files["brep"].rstrip() + b"\n0\n\n")
    check_cad_file(p, "brep")
    p.write_bytes(files["brep"].rstrip() + b"\n0\n7\n")  # two lines: not a BRep ending
    with pytest.raises(CadError, match="root shape"):
        check_cad_file(p, "brep")
