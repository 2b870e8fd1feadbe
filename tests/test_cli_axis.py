"""``medax axis`` in-process: outputs and every bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from medax.cli.main import main
from medax.geometry.region_io import sample_regions_path
from medax.schemas import validation_errors

SAMPLE = str(sample_regions_path())


def test_axis_json_and_plot(tmp_path, capsys):
    out, png = tmp_path / "axis.json", tmp_path / "axis.png"
    assert (
        main(
            [
                "axis",
                SAMPLE,
                "--region",
                "wavy",
                "--pair",
                "0,2",
                "-o",
                str(out),
                "--plot",
                str(png),
            ]
        )
        == 0
    )
    rec = json.loads(out.read_text())
    for key in (
        "region",
        "pair",
        "points",
        "spline",
        "max_point_error",
        "max_curve_error",
        "diagonal",
        "n_points",
    ):
        assert key in rec
    assert rec["region"] == "wavy" and rec["pair"] == [0, 2]
    assert len(rec["points"]) == rec["n_points"]
    sp = rec["spline"]
    assert len(sp["knots"]) == len(sp["control_points"]) + sp["degree"] + 1
    assert rec["max_curve_error"] <= 1e-6 * rec["diagonal"]
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_axis_both_pairs_svg(tmp_path):
    out, svg = tmp_path / "a.json", tmp_path / "a.svg"
    assert (
        main(
            [
                "axis",
                SAMPLE,
                "--region",
                "annulus_sector",
                "--pair",
                "both",
                "-o",
                str(out),
                "--plot",
                str(svg),
            ]
        )
        == 0
    )
    recs = json.loads(out.read_text())
    assert [r["pair"] for r in recs] == [[0, 2], [1, 3]]
    pts = np.array(recs[1]["points"])
    assert np.allclose(np.linalg.norm(pts, axis=1), 7.0, atol=1e-9)
    assert svg.read_text().lstrip().startswith("<?xml")


def _bad(tmp_path, spec) -> str:
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({"r": spec}) if not isinstance(spec, str) else spec)
    return str(p)


SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]
LINES = [{"kind": "line"}] * 4


@pytest.mark.parametrize(
    ("make", "args", "message"),
    [
        (lambda t: str(t / "missing.json"), ["--region", "r"], "no such file"),
        (lambda t: _bad(t, "{not json"), ["--region", "r"], "malformed JSON"),
        (
            lambda t: _bad(t, {"corners": SQUARE, "sides": LINES}),
            ["--region", "nope"],
            "no region named 'nope'",
        ),
        (
            lambda t: _bad(
                t,
                {
                    "corners": SQUARE,
                    "sides": [
                        {"kind": "line"},
                        {"kind": "spiral"},
                        {"kind": "line"},
                        {"kind": "line"},
                    ],
                },
            ),
            ["--region", "r"],
            "side 1: unknown side kind 'spiral'",
        ),
        (
            lambda t: _bad(
                t,
                {
                    "corners": SQUARE,
                    "sides": [
                        {"kind": "line"},
                        {"kind": "polyline", "points": [[1, 0], [1.2, 0.5], [1, 0.9]]},
                        {"kind": "line"},
                        {"kind": "line"},
                    ],
                },
            ),
            ["--region", "r"],
            "side 1: last point [1.0, 0.9] is not corner [1.0, 1.0]",
        ),
        (
            lambda t: _bad(
                t,
                {
                    "corners": SQUARE,
                    "sides": [{"kind": "arc", "center": [0.5, 0.5], "radius": 0.3}, *LINES[1:]],
                },
            ),
            ["--region", "r"],
            "side 0: arc start point",
        ),
        (
            lambda t: _bad(t, {"corners": [[0, 0], [1, 0], [1, 0], [0, 1]], "sides": LINES}),
            ["--region", "r"],
            "side 1 has zero length",
        ),
        (
            lambda t: _bad(t, {"corners": [[0, 0], [1, 1], [1, 0], [0, 1]], "sides": LINES}),
            ["--region", "r"],
            "crosses",
        ),
        (lambda t: SAMPLE, ["--region", "wavy", "--pair", "0,1"], "--pair must be"),
        (lambda t: SAMPLE, ["--region", "wavy", "--tol", "-1"], "--tol -1: must be positive"),
        (lambda t: SAMPLE, ["--region", "wavy", "--plot", "x.gif"], "(use .png, .svg)"),
    ],
)
def test_bad_input_one_line_error_no_output(tmp_path, capsys, make, args, message):
    src = make(tmp_path)
    out = tmp_path / "out.json"
    code = main(["axis", src, *args, "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code != 0
    assert message in err, err
    assert len(err.splitlines()) == 1
    assert not out.exists()
    assert not any(p.name.startswith(".out.json") for p in tmp_path.iterdir())


def test_unwritable_output_fails_before_work(tmp_path, capsys):
    code = main(["axis", SAMPLE, "--region", "wavy", "-o", str(tmp_path / "no" / "dir" / "a.json")])
    assert code != 0 and "does not exist" in capsys.readouterr().err


def test_demo_writes_axis_files(tmp_path, capsys):
    from medax.cli.demo_axis import demo

    written = demo(tmp_path)
    names = {p.name for p in written}
    assert {"axis-wavy.json", "axis-wavy.png", "axis-annulus_sector.json"} <= names
    recs = json.loads((tmp_path / "axis-wavy.json").read_text())
    assert [r["pair"] for r in recs] == [[0, 2], [1, 3]]
    assert validation_errors(recs, "axis") == []


@pytest.mark.parametrize("pair", ["0,2", "1,3"])
def test_clockwise_region_reports_the_files_side_numbers(tmp_path, pair):
    """A clockwise region is reversed inside; axis.json names sides as the file does: the
    first point lies on the file's start_side, the last on its end_side."""
    from medax.geometry.region_io import read_region

    corners = [[0, 0], [0, 6], [10, 4], [10, 0]]  # clockwise; side k from corner k to k+1
    spec = {"corners": corners, "sides": [{"kind": "line"}] * 4}
    src, out = tmp_path / "cw.json", tmp_path / "a.json"
    src.write_text(json.dumps({"cw": spec}))
    assert read_region(src, "cw").reoriented
    assert main(["axis", str(src), "--region", "cw", "--pair", pair, "-o", str(out)]) == 0
    rec = json.loads(out.read_text())
    c = np.array(corners, dtype=float)

    def gap(p, k):  # distance from p to the file's side k (a segment)
        a, b = c[k], c[(k + 1) % 4]
        t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0, 1)
        return np.linalg.norm(p - (a + t * (b - a)))

    first, last = np.array(rec["points"][0]), np.array(rec["points"][-1])
    assert gap(first, rec["start_side"]) <= 1e-9 and gap(last, rec["end_side"]) <= 1e-9
    assert sorted(rec["constraints"]) == sorted(int(x) for x in pair.split(","))
