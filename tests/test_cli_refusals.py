"""Wrong results are refused, not written with exit 0 (issue 19): inverted quads, NaN in
JSON, tolerances that are not finite, not positive or below what doubles reach."""

from __future__ import annotations

import json
import math

import pytest
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

from medax.cad.simplify.step_out import write_step
from medax.cli.main import main
from medax.errors import OutputError
from medax.geometry.region_io import sample_regions_path
from medax.io_utils import nonfinite_place, write_json

SAMPLE = str(sample_regions_path())
#: a 0.01-wide trapezoid far from the origin: its mesh came out with every quad inverted
FAR = {
    "corners": [
        [1e6, -2e6],
        [1e6 + 0.01, -2e6],
        [1e6 + 0.0075, -2e6 + 0.006],
        [1e6 + 0.0025, -2e6 + 0.006],
    ],  # fmt: skip
    "sides": [{"kind": "line"}] * 4,
}


def one_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    errors = [line for line in err.splitlines() if "error:" in line]
    assert len(errors) == 1 and "Traceback" not in err, err
    return errors[0]


@pytest.fixture(scope="module")
def box_step(tmp_path_factory):
    p = tmp_path_factory.mktemp("box") / "box.step"
    write_step(BRepPrimAPI_MakeBox(10.0, 20.0, 5.0).Shape(), p)
    return p


def test_inverted_mesh_refused_unless_allowed(tmp_path, capsys, monkeypatch):
    """A mesh with inverted quads is refused (exit 1, nothing written, an existing file kept);
    ``--allow-inverted`` writes it. The mesher's result is mirrored (every quad clockwise) so
    the test does not depend on which regions the mesher gets wrong."""
    import dataclasses

    import medax.mesh.mesher as mesher

    real = mesher.mesh_region

    def flipped(*args, **kwargs):
        m = real(*args, **kwargs)
        return dataclasses.replace(m, points=m.points * [-1.0, 1.0])

    monkeypatch.setattr(mesher, "mesh_region", flipped)
    out, rep = tmp_path / "m.vtu", tmp_path / "q.json"
    out.write_text("mine")
    argv = ["mesh", SAMPLE, "--region", "trapezoid", "--divisions", "4", "-o", str(out)]
    assert main([*argv, "--report", str(rep)]) == 1
    assert "16 of 16 quads are inverted" in one_error(capsys)
    assert out.read_text() == "mine" and not rep.exists()
    assert main([*argv, "--report", str(rep), "--allow-inverted"]) == 0
    assert json.loads(rep.read_text())["n_inverted"] == 16 and out.read_text() != "mine"


def test_far_region_mesh_not_written_inverted(tmp_path, capsys):
    """The region of the issue: whatever the mesher does with it, an inverted mesh is never
    written with exit 0."""
    src = tmp_path / "far.json"
    src.write_text(json.dumps({"far": FAR}))
    out = tmp_path / "m.vtu"
    code = main(["mesh", str(src), "--divisions", "16", "-o", str(out), "--report",
                 str(tmp_path / "q.json")])  # fmt: skip
    if code == 0:
        assert json.loads((tmp_path / "q.json").read_text())["n_inverted"] == 0
    else:
        assert "inverted" in one_error(capsys) and not out.exists()


def test_json_never_holds_nan(tmp_path):
    out = tmp_path / "a.json"
    out.write_text("old")
    data = {"points": [[0.0, 1.0], [2.0, math.nan]], "n": 2}
    with pytest.raises(OutputError, match=r"points\[1\]\[1\] is not a finite number"):
        write_json(out, data)
    assert out.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["a.json"]
    assert nonfinite_place({"a": [1.0, {"b": -math.inf}]}) == "a[1].b"
    assert nonfinite_place({"a": [1.0, 2]}) is None


def test_axis_with_nan_fails_with_the_reason(tmp_path, capsys, monkeypatch):
    import medax.axis.export as export

    real = export.axis_record

    def with_nan(axis):
        rec = real(axis)
        rec["max_curve_error"] = math.nan
        return rec

    monkeypatch.setattr(export, "axis_record", with_nan)
    out = tmp_path / "a.json"
    assert main(["axis", SAMPLE, "--region", "trapezoid", "-o", str(out)]) == 1
    assert "max_curve_error is not a finite number" in one_error(capsys)
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("tol", "message"),
    [
        ("nan", "--tol nan: must be a finite number"),
        ("inf", "--tol inf: must be a finite number"),
        ("-inf", "--tol -inf: must be a finite number"),
        ("0", "must be positive"),
        ("-1e-6", "must be "),
        ("1e-15", "below"),
        ("1e-300", "below"),
    ],
)
@pytest.mark.parametrize("command", ["axis", "mesh", "mesh-part", "classify", "simplify"])
def test_bad_tol_refused_before_work(box_step, tmp_path, capsys, command, tol, message):
    if command == "mesh" and tol == "0":
        return  # mesh: 0 solves every node (tested in test_mesh_cli)
    if command == "mesh-part":
        message = "--tol applies to regions, not to CAD parts"  # any value, nan and inf too
    out = tmp_path / "o"
    argv = {
        "axis": ["axis", SAMPLE, "--region", "wavy", "-o", f"{out}.json"],
        "mesh": ["mesh", SAMPLE, "--region", "wavy", "--size", "1", "-o", f"{out}.vtu"],
        "mesh-part": ["mesh", str(box_step), "--size", "5", "-o", f"{out}.msh"],
        "classify": ["classify", str(box_step), "--report", f"{out}.json"],
        "simplify": ["simplify", str(box_step), "-o", f"{out}.step"],
    }[command]
    assert main([*argv, f"--tol={tol}"]) == 1
    err = one_error(capsys)
    assert message in err, err
    assert list(tmp_path.iterdir()) == []
