"""``medax simplify`` end to end on STEP files written from OCCT-built parts."""

from __future__ import annotations

import json

import pytest
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

from medax.cad.simplify import parts as P
from medax.cad.simplify.step_out import write_step
from medax.cli.main import main
from medax.schemas import validation_errors

KEYS = {
    "faces_before",
    "faces_after",
    "blends_removed",
    "blends_kept",
    "valid",
    "volume_rel_change",
    "max_deviation",
    "face_groups",
    "time_s",
}


@pytest.fixture(scope="module")
def box_step(tmp_path_factory):
    path = tmp_path_factory.mktemp("in") / "box4.step"
    write_step(P.box_vertical_fillets().shape, path)
    return path


@pytest.mark.slow
def test_cli_simplify_box(box_step, tmp_path, capsys):
    out, rep, png = tmp_path / "s.step", tmp_path / "r.json", tmp_path / "ba.png"
    code = main(
        ["simplify", str(box_step), "-o", str(out), "--report", str(rep), "--png", str(png)]
    )
    assert code == 0
    report = json.loads(rep.read_text())
    assert KEYS <= set(report)
    assert (report["faces_before"], report["faces_after"]) == (10, 6)
    assert report["valid"] and abs(report["volume_rel_change"]) <= 1e-6
    assert report["max_deviation"]["relative_to_diagonal"] <= 1e-7
    assert png.stat().st_size > 10_000
    written = report["written_file"]  # the file read back against the validated solid
    assert written["faces"] == 6 and written["valid"]
    assert written["max_deviation"] <= 1e-9 * report["diagonal"]
    assert abs(written["default_integrator_volume_rel_change"]) <= 1e-9
    # exact merged faces: OCCT's default integrator agrees, no note about it
    assert "default mass properties" not in capsys.readouterr().out
    # the written STEP reads back as a 6-face solid without fillets
    assert (
        main(
            [
                "simplify",
                str(out),
                "-o",
                str(tmp_path / "again.step"),
                "--report",
                str(tmp_path / "r2.json"),
            ]
        )
        == 0
    )
    again = json.loads((tmp_path / "r2.json").read_text())
    assert again["faces_before"] == 6 and again["faces_after"] == 6
    assert not again["blends_removed"] and again["valid"]
    assert "no fillet" in " ".join(again["notes"])
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "again.step",
        "ba.png",
        "r.json",
        "r2.json",
        "s.step",
    ]


@pytest.mark.slow
def test_cli_notes_the_default_integrator_on_fitted_faces(tmp_path, capsys):
    """On fitted merged faces (the 12-fillet box: sphere corners) OCCT's default integrator
    misreads the written file's volume (issue 18, open): the CLI says by how much, and the
    number is what that integrator gives on the file against the input's exact volume."""
    import math

    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from medax.cad.reader import read_part

    a, b, h, r = 40.0, 30.0, 20.0, 4.0
    src, out = tmp_path / "box12.step", tmp_path / "o.step"
    write_step(P.box_all_fillets(a, b, h, r).shape, src)
    assert main(["simplify", str(src), "-o", str(out)]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if "default mass properties" in ln]
    assert len(line) == 1
    said = float(line[0].split("volume change of ")[1].split(" ")[0].rstrip(":"))
    x, y, z = a - 2 * r, b - 2 * r, h - 2 * r
    exact = x * y * z + 2 * r * (x * y + y * z + z * x) + math.pi * r**2 * (x + y + z)
    exact += 4 / 3 * math.pi * r**3
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(read_part(out, unify=False).solids[0], props)
    on_file = props.Mass() / exact - 1.0
    assert abs(on_file) > 1e-6  # the open part of issue 18: the note has something to say
    assert abs(on_file) < 2e-5  # 61 Gauss points on each face (reader_spans); 1e-4 at 16
    assert abs(said - on_file) <= 0.05 * abs(on_file)  # printed to two digits


@pytest.mark.slow
def test_cli_strict_volume_keeps_what_the_default_integrator_misreads(box_step, tmp_path):
    """With ``--strict-volume`` the written file measures right by OCCT's default mass
    properties too: on the 12-fillet box (fitted faces, misread by 1e-5 and more without it,
    see above) against the exact volume, with the fillets kept saying why; on the 4-fillet
    box (exact merged faces, read right) the same 4 fillets still go."""
    import math

    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from medax.cad.reader import read_part

    a, b, h, r = 40.0, 30.0, 20.0, 4.0
    src, out, rep = tmp_path / "box12.step", tmp_path / "o.step", tmp_path / "r.json"
    write_step(P.box_all_fillets(a, b, h, r).shape, src)
    assert (
        main(["simplify", str(src), "-o", str(out), "--report", str(rep), "--strict-volume"]) == 0
    )
    x, y, z = a - 2 * r, b - 2 * r, h - 2 * r
    exact = x * y * z + 2 * r * (x * y + y * z + z * x) + math.pi * r**2 * (x + y + z)
    exact += 4 / 3 * math.pi * r**3
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(read_part(out, unify=False).solids[0], props)
    assert abs(props.Mass() / exact - 1.0) <= 1e-6
    report = json.loads(rep.read_text())
    assert abs(report["default_integrator_volume_rel_change"]) <= 1e-6
    assert any("default mass properties" in k for k in report["kept_reasons"])
    assert report["strict_volume"] is True
    assert not validation_errors(report, "simplify-report")
    out4, rep4 = tmp_path / "o4.step", tmp_path / "r4.json"
    assert (
        main(["simplify", str(box_step), "-o", str(out4), "--report", str(rep4), "--strict-volume"])
        == 0
    )
    report4 = json.loads(rep4.read_text())
    assert (report4["faces_before"], report4["faces_after"]) == (10, 6)


def test_cli_no_fillets_written_unchanged(tmp_path):
    src = tmp_path / "plain.step"
    write_step(BRepPrimAPI_MakeBox(10.0, 20.0, 5.0).Shape(), src)
    out, rep = tmp_path / "o.step", tmp_path / "r.json"
    assert main(["simplify", str(src), "-o", str(out), "--report", str(rep)]) == 0
    report = json.loads(rep.read_text())
    assert report["faces_before"] == report["faces_after"] == 6
    assert report["notes"] == ["no fillets found: output equals input"]
    assert out.exists()


def test_cli_bad_output_fails_before_work(box_step, tmp_path, capsys):
    out = tmp_path / "missing" / "o.step"
    assert main(["simplify", str(box_step), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "does not exist" in err and err.count("\n") == 1
    assert not out.parent.exists()


def test_cli_missing_input(tmp_path, capsys):
    out = tmp_path / "o.step"
    assert main(["simplify", str(tmp_path / "nope.step"), "-o", str(out)]) == 1
    assert "nope.step" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_cli_truncated_step(box_step, tmp_path):
    bad = tmp_path / "cut.step"
    bad.write_text(box_step.read_text()[:500])
    out = tmp_path / "o.step"
    assert main(["simplify", str(bad), "-o", str(out)]) == 1
    assert not out.exists()


def test_cli_two_solids(tmp_path):
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.TopoDS import TopoDS_Compound

    t = gp_Trsf()
    t.SetTranslation(gp_Vec(200.0, 0.0, 0.0))
    far = BRepBuilderAPI_Transform(P.plate_with_boss().shape, t, True).Shape()
    comp = TopoDS_Compound()
    b = BRep_Builder()
    b.MakeCompound(comp)
    b.Add(comp, P.box_vertical_fillets().shape)
    b.Add(comp, far)
    src, out, rep = tmp_path / "two.step", tmp_path / "o.step", tmp_path / "r.json"
    write_step(comp, src)
    assert main(["simplify", str(src), "-o", str(out), "--report", str(rep)]) == 0
    report = json.loads(rep.read_text())
    assert [(s["faces_before"], s["faces_after"]) for s in report["solids"]] == [(10, 6), (10, 9)]
    assert (report["faces_before"], report["faces_after"]) == (20, 15) and report["valid"]
    assert validation_errors(report, "simplify-report") == []


def test_cli_refuses_a_file_that_reads_back_moved(box_step, tmp_path, monkeypatch, capsys):
    """A writer whose file holds another shape than the one validated (here: the solid moved
    by 1e-4 of its size) is caught by reading the file back; the user's file survives."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf, gp_Vec

    from medax.cad.simplify import step_out

    honest = step_out._WRITERS["step"]

    def moved(shape, tmp, path, *_styles_and_name):  # the moved copy has other faces
        t = gp_Trsf()
        t.SetTranslation(gp_Vec(0.0, 0.0, 5e-3))
        honest(BRepBuilderAPI_Transform(shape, t, True).Shape(), tmp, path)

    monkeypatch.setitem(step_out._WRITERS, "step", moved)
    out = tmp_path / "s.step"
    out.write_text("the user's earlier result")
    code = main(["simplify", str(box_step), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1
    assert "s.step: face" in err and "moves by 0.005" in err
    assert out.read_text() == "the user's earlier result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.step"]


def test_boundary_shift_polyline_distance_is_exact():
    """The read-back's point-to-polyline distance (k-d tree pruned) equals the distance
    over all point-segment pairs, on bent polylines at scales 1e-3 to 1e3."""
    import numpy as np

    from medax.cad.simplify.readback import _to_polylines

    rng = np.random.default_rng(18)
    t = np.linspace(0.0, 1.0, 49)[None, :, None]
    for scale in (1e-3, 1.0, 1e3):
        for noise in (0.0, 1e-6, 0.3):
            s = rng.normal(size=(12, 1, 3)) * scale
            lines = s + t * rng.normal(size=(12, 1, 3)) * scale
            lines += t * (1 - t) * rng.normal(size=(12, 1, 3)) * 0.3 * scale
            pts = lines[:, ::4] + rng.normal(size=lines[:, ::4].shape) * noise * scale
            p = pts.reshape(-1, 3)
            a, b = lines[:, :-1].reshape(-1, 3), lines[:, 1:].reshape(-1, 3)
            ab, ap = b - a, p[:, None] - a[None]
            u = np.clip((ap * ab).sum(2) / (ab * ab).sum(1), 0.0, 1.0)
            want = np.linalg.norm(ap - u[..., None] * ab, axis=2).min(axis=1).max()
            assert abs(_to_polylines(pts, lines) - want) <= 1e-12 * scale
