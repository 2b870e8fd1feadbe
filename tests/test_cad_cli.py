"""``medax classify`` end to end, in-process, on parts built with OCCT, and on bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer  # noqa: E402

from medax.cad import parts  # noqa: E402
from medax.cli.main import main  # noqa: E402


def write_step(shape, path):
    w = STEPControl_Writer()
    w.Transfer(shape, STEPControl_AsIs)
    assert int(w.Write(str(path))) == 1
    return path


def test_classify_writes_report_and_png(tmp_path, capsys):
    built = parts.plate_with_boss()
    step = write_step(built.shape, tmp_path / "boss.step")
    report, png = tmp_path / "classes.json", tmp_path / "view.png"
    assert main(["classify", str(step), "--report", str(report), "--png", str(png)]) == 0
    out = capsys.readouterr().out
    assert "2 fillet" in out
    data = json.loads(report.read_text())
    assert data["unit"] == "mm" and data["summary"]["fillet"] == 2
    assert data["summary"]["axes"] == 2 and data["summary"]["solids"] == 1
    solid = data["solids"][0]
    faces = {f["index"]: f for f in solid["faces"]}
    for f in solid["faces"]:
        assert {"index", "class", "surface", "area", "centroid", "neighbours"} <= set(f)
        if f["class"] == "supporting":
            assert set(f["edge_classes"].values()) <= {"smooth", "semi_smooth", "non_smooth"}
    for fr in solid["fillets"]:
        assert faces[fr["face"]]["class"] == "fillet"
        assert faces[fr["face"]]["surface"] == "torus"
        assert fr["radius"] == pytest.approx(built.radius)
        pts = np.array(fr["axis"]["points"])
        assert pts.shape[1] == 3 and len(pts) >= 3
        # the axis of a torus fillet around the boss is a circle about the boss axis
        rad = np.hypot(pts[:, 0] - 30.0, pts[:, 1] - 20.0)
        assert np.ptp(rad) < 1e-9 * built.radius and np.ptp(pts[:, 2]) < 1e-9 * built.radius
    assert png.stat().st_size > 10_000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".*"))  # no temporary files left


@pytest.mark.parametrize(
    "make, expect",
    [
        (lambda d: d / "missing.step", "no such file"),
        (lambda d: (d / "empty.step").write_bytes(b"") and None or d / "empty.step", "empty"),
        (lambda d: (d / "x.obj").write_text("v 1 2 3") and None or d / "x.obj", "extension"),
        (
            lambda d: (
                (d / "junk.step").write_text("ISO-10303-21;\nHEADER;\n") and None or d / "junk.step"
            ),
            "STEP",
        ),
    ],
)
def test_bad_input_one_line_no_report(tmp_path, capsys, make, expect):
    path = make(tmp_path)
    report, png = tmp_path / "classes.json", tmp_path / "view.png"
    code = main(["classify", str(path), "--report", str(report), "--png", str(png)])
    err = capsys.readouterr().err.strip()
    assert code == 1
    assert len(err.splitlines()) == 1 and expect in err and str(path) in err
    assert not report.exists() and not png.exists()


def test_unwritable_report_fails_before_work(tmp_path, capsys):
    step = write_step(parts.pocket().shape, tmp_path / "p.step")
    code = main(["classify", str(step), "--report", str(tmp_path / "no" / "such" / "r.json")])
    assert code == 1 and "does not exist" in capsys.readouterr().err
