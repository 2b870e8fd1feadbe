"""Hostile regions files: one typed line naming the region and side, never a traceback
(issue 19); and orientation far from the origin."""

from __future__ import annotations

import json

import numpy as np
import pytest

from medax.cli.main import main
from medax.errors import InputError
from medax.geometry.region_io import read_region, region_from_dict

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]
LINES = [{"kind": "line"}] * 4
BIG = "1" + "0" * 400  # an integer no float holds


def region_text(corners=SQUARE, side0=None) -> str:
    sides = [side0 or LINES[0], *LINES[1:]]
    return json.dumps({"r": {"corners": corners, "sides": sides}})


def bspline(degree) -> dict:
    pts = [[0, 0], [0.3, -0.1], [0.7, 0.1], [1, 0]]
    return {"kind": "bspline", "degree": degree, "points": pts}


CASES = [
    ("[" * 100_000 + "]" * 100_000, "JSON nested too deeply"),
    ('{"r": ' + "[" * 100_000 + "]" * 100_000 + "}", "JSON nested too deeply"),
    ('{"r": {"corners": [[0, 0], [1, 1' + "0" * 5000 + "]]}}", "malformed JSON"),
    (region_text().replace("[1, 0]", f"[{BIG}, 0]", 1), "corners: a number is too large"),
    (
        region_text(side0={"kind": "polyline", "points": [[0, 0], [0.5, 7], [1, 0]]}).replace(
            "7", BIG
        ),
        "side 0: 'points': a number is too large",
    ),
    (region_text(side0={"kind": "arc", "sagitta": 7}).replace("7", BIG), "side 0: sagitta is"),
    (
        region_text(side0={"kind": "arc", "center": [0.5, -1], "radius": 7}).replace("7", BIG),
        "side 0: radius is too large",
    ),
    (region_text(side0=bspline(7)).replace(": 7", ": Infinity"), "side 0: degree must be"),
    (region_text(side0=bspline(7)).replace(": 7", ": NaN"), "side 0: degree must be"),
    (region_text(side0=bspline(2.5)), "side 0: degree must be an integer from 1 to 3"),
    (region_text(side0=bspline("3")), 'from 1 to 3 (4 points), got "3"'),
    (region_text(side0=bspline(7)).replace(": 7", ": " + BIG), "side 0: degree must be"),
    (
        region_text(side0={"kind": "polyline", "points": [[0, 0], [0.5, 7], [1, 0]]}).replace(
            "7", "NaN"
        ),
        "side 0: 'points' must be finite",
    ),
    (region_text(side0={"kind": "polyline", "points": [[0, 0], [1], [1, 0]]}), "side 0: 'points'"),
    (region_text(side0={"kind": "arc", "center": "ab", "radius": 1}), "side 0: center must be"),
    (region_text(side0={"kind": "arc", "sagitta": "1"}), "side 0: sagitta must be a number"),
    (region_text(corners=[[0, 0], [1, 0], [2, 0], [3, 0]]), "sides 2 and 3 fold onto each other"),
    (region_text(corners=[[0, 0], [1, 1], [2, 2], [3, 3]]), "sides 2 and 3 fold onto each other"),
    (region_text(corners=[[0, 0], [2, 0], [1, 0], [3, 0]]), "sides 0 and 1 fold onto each other"),
    (region_text(corners=[[0, 0], [1e308, 0], [1e308, 1e308], [0, 1e308]]), "too large"),
]


@pytest.mark.parametrize(("text", "message"), CASES)
def test_hostile_regions_one_line(tmp_path, capsys, text, message):
    src = tmp_path / "r.json"
    src.write_text(text)
    with pytest.raises(InputError, match=None) as info:
        read_region(src, "r")
    assert message in str(info.value)
    out = tmp_path / "a.json"
    for argv in (
        ["axis", str(src), "--region", "r", "-o", str(out)],
        ["mesh", str(src), "--region", "r", "--divisions", "4", "-o", str(tmp_path / "m.vtu")],
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err.strip()
        assert message in err and len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.json"]


def poly(*pts) -> dict:
    return {"kind": "polyline", "points": [list(p) for p in pts]}


RECT = [[0, 0], [2, 0], [2, 1], [0, 1]]
SIMPLE = "the four sides must form one simple closed curve"


@pytest.mark.parametrize(
    ("corners", "sides", "message"),
    [
        (
            RECT,
            [poly((0, 0), (1, 0), (2, 0)), *LINES[1:2], poly((2, 1), (1, 0), (0, 1)), LINES[3]],
            "side 0 touches side 2 at (1, 0)",
        ),  # fmt: skip
        (
            RECT,
            [*LINES[:2], {"kind": "arc", "sagitta": -1.0}, LINES[3]],
            "side 0 touches side 2 at (1, 0)",
        ),  # fmt: skip
        (
            SQUARE,
            [poly((0, 0), (0.6, 0), (0.3, 0), (1, 0)), *LINES[1:]],
            "side 0 doubles back at (0.6, 0)",
        ),  # fmt: skip
        (SQUARE, [poly((0, 0), (0.6, 0), (0.59, 0), (1, 0)), *LINES[1:]], "side 0 doubles back"),
        (
            SQUARE,
            [poly((0, 0), (1, 0), (1, 0.5), (1, 0)), *LINES[1:]],
            "side 0 doubles back at (1, 0.5)",
        ),  # fmt: skip
        (
            [[0, 0], [1, 0], [1, 0], [0, 1]],
            [LINES[0], poly((1, 0), (1.5, 0.5), (1, 1), (1, 0)), *LINES[2:]],
            "corners 1 and 2 coincide at (1, 0)",
        ),  # fmt: skip
        (
            SQUARE,
            [poly((0, 0), (0.5, 0), (0.5, 0.5), (0.5, 0.999_999_99), (0.6, 0), (1, 0)), *LINES[1:]],
            "side 0 touches side 2",
        ),  # fmt: skip
    ],
)
def test_degenerate_regions_refused(corners, sides, message):
    """Pinched (also by an arc's apex, between samples), doubling back, running up a
    neighbour and back, a side that is a loop, a spike nearly touching the far side."""
    with pytest.raises(InputError) as info:
        region_from_dict({"corners": corners, "sides": sides}, "r")
    assert message in str(info.value) and SIMPLE in str(info.value), str(info.value)


@pytest.mark.parametrize(
    ("corners", "sides"),
    [
        (
            [[0, 0], [10, 0], [10, 10], [0, 10]],
            [poly((0, 0), (4.8, 0), (5, 9), (5.2, 0), (10, 0)), *LINES[1:]],
        ),  # fmt: skip
        ([[0, 0], [20, 0], [20, 1e-3], [0, 1e-3]], LINES),
        (SQUARE, [{"kind": "arc", "sagitta": 0.2}, *LINES[1:]]),
        (RECT, [*LINES[:2], {"kind": "arc", "sagitta": -0.99}, LINES[3]]),
    ],
)
def test_narrow_but_simple_regions_accepted(corners, sides):
    """A thin spike, a 1:20000 strip, arcs; an arc passing 0.01 from the opposite side."""
    region_from_dict({"corners": corners, "sides": sides}, "ok")


def test_sample_regions_still_accepted():
    from medax.geometry.region_io import read_regions, sample_regions_path

    assert set(read_regions(sample_regions_path())) == {
        "trapezoid",
        "arcs",
        "wavy",
        "annulus_sector",
    }


@pytest.mark.parametrize(
    ("offset", "width"), [((1e6, -2e6), 0.01), ((1e9, 1e9), 10.0), ((1e12, 1e12), 10.0)]
)
def test_orientation_far_from_the_origin(offset, width):
    """A counter-clockwise trapezoid stays counter-clockwise far away (the signed area is
    summed relative to a corner; it cancelled in absolute coordinates at 1e6 and 1e9)."""
    x0, y0 = offset
    w, h = width, 0.6 * width
    corners = [[x0, y0], [x0 + w, y0], [x0 + 0.75 * w, y0 + h], [x0 + 0.25 * w, y0 + h]]
    reg = region_from_dict({"corners": corners, "sides": LINES}, "far")
    assert not reg.reoriented
    cw = region_from_dict({"corners": corners[::-1], "sides": LINES}, "far")
    assert cw.reoriented
    assert reg.signed_area() == pytest.approx(0.75 * w * h, rel=1e-3)


def test_far_region_states_its_coordinate_bound(tmp_path, caplog):
    """At 1e12 doubles hold a 10-unit region to 1e-5 x diagonal: axis and mesh succeed and
    say so (a warning and the JSON), instead of claiming 1e-10; near the origin, silent."""
    w, h, x0 = 10.0, 6.0, 1e12
    far = [[x0, x0], [x0 + w, x0], [x0 + 0.75 * w, x0 + h], [x0 + 0.25 * w, x0 + h]]
    near = [[x - x0 for x in c] for c in far]
    regions = {n: {"corners": c, "sides": LINES} for n, c in (("far", far), ("near", near))}
    src = tmp_path / "r.json"
    src.write_text(json.dumps(regions))
    for name in ("far", "near"):
        caplog.clear()
        out, rep = tmp_path / f"{name}.json", tmp_path / f"{name}-q.json"
        assert main(["axis", str(src), "--region", name, "-o", str(out)]) == 0
        assert main(["mesh", str(src), "--region", name, "--divisions", "8", "-o",
                     str(tmp_path / f"{name}.vtu"), "--report", str(rep)]) == 0  # fmt: skip
        res = json.loads(out.read_text())["coordinate_resolution_rel"]
        res_mesh = json.loads(rep.read_text())["coordinate_resolution_rel"]
        if name == "far":
            assert 0.5e-5 < res < 2e-5 and 0.5e-5 < res_mesh < 2e-5
            assert caplog.text.count("resolve its coordinates only to 1.0e-05 x diagonal") == 2
        else:
            assert res < 1e-15 and res_mesh < 1e-15 and "resolve" not in caplog.text


@pytest.mark.parametrize("size", [1e-3, 1e-4])
def test_corners_meet_to_what_doubles_resolve(size):
    """A 1e-3 region of arcs at 1.1e6: its arcs' computed end points miss the corners by a
    few units in the last place there (4.7e-10, above 1e-7 x diagonal); not an open corner."""
    off = np.array([1102191.6626334107, -1148783.277913306])
    corners = off + size * np.array([[0, 0], [1, 0.1], [0.9, 1], [-0.1, 0.8]])
    sides = [{"kind": "arc", "sagitta": s * size} for s in (0.1, -0.1, 0.1, -0.1)]
    region = region_from_dict({"corners": corners.tolist(), "sides": sides}, "far")
    assert not region.reoriented
    end = (corners[1] + [0.0, 1e-3 * size]).tolist()  # a real gap, 1e-3 of the size
    spec = {"corners": corners.tolist(), "sides": [{"kind": "line"}] * 4}
    spec["sides"][0] = {"kind": "polyline", "points": [corners[0].tolist(), end]}
    with pytest.raises(InputError, match="corner 1 open by"):
        region_from_dict(spec, "open")
