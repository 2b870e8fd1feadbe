"""Every subcommand's outputs: checked before any work, never an input, never a special file,
all written or none, mode from the umask (issue 19, data loss and clobbering)."""

from __future__ import annotations

import json
import os
import stat

import pytest
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

from medax.cad.simplify.step_out import write_step
from medax.cli.main import main
from medax.geometry.region_io import sample_regions_path

SAMPLE = sample_regions_path().read_text()


@pytest.fixture()
def regions(tmp_path):
    p = tmp_path / "r.json"
    p.write_text(SAMPLE)
    return p


@pytest.fixture(scope="module")
def box_step(tmp_path_factory):
    p = tmp_path_factory.mktemp("box") / "box.step"
    write_step(BRepPrimAPI_MakeBox(10.0, 20.0, 5.0).Shape(), p)
    return p


def axis(src, *extra):
    return ["axis", str(src), "--region", "trapezoid", *map(str, extra)]


def mesh(src, *extra):
    return ["mesh", str(src), "--region", "trapezoid", "--divisions", "4", *map(str, extra)]


def refused(argv, capsys, message):
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 1, err
    errors = [line for line in err.splitlines() if "error:" in line]
    assert len(errors) == 1 and errors[0] == err.splitlines()[-1], err
    assert message in errors[0], err
    assert "Traceback" not in err


def listing(folder):
    return sorted(p.name for p in folder.iterdir())


# ---- an output naming an input ------------------------------------------------------------
@pytest.mark.parametrize("link", ["same", "symlink", "hardlink", "dotted"])
@pytest.mark.parametrize("command", ["axis", "mesh"])
def test_output_is_the_regions_file(regions, tmp_path, capsys, link, command):
    before = regions.read_bytes()
    out = {
        "same": regions,
        "symlink": tmp_path / "link.json",
        "hardlink": tmp_path / "hard.json",
        "dotted": tmp_path / "." / "r.json",
    }[link]
    if link == "symlink":
        out.symlink_to(regions)
    elif link == "hardlink":
        os.link(regions, out)
    argv = axis(regions, "-o", out) if command == "axis" else mesh(regions, "--format", "vtu")
    if command == "mesh":
        argv += ["-o", str(out)]
    refused(argv, capsys, "is the regions file")
    assert regions.read_bytes() == before
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())


def test_mesh_report_over_mesh_refused(regions, tmp_path, capsys):
    out = tmp_path / "same.json"
    refused(
        mesh(regions, "--format", "vtu", "-o", out, "--report", out), capsys, "name the same file"
    )
    assert not out.exists()
    refused(mesh(regions, "-o", "same.vtu", "--report", "same.vtu"), capsys, "--report")


def test_outputs_linked_to_each_other_refused(regions, tmp_path, capsys):
    rep = tmp_path / "q.json"
    rep.write_text("keep")
    os.link(rep, tmp_path / "m.json")
    argv = mesh(regions, "--format", "vtu", "-o", tmp_path / "m.json", "--report", rep)
    refused(argv, capsys, "name the same file")
    assert rep.read_text() == "keep"


@pytest.mark.parametrize("command", ["simplify", "classify"])
def test_cad_output_is_the_part(box_step, tmp_path, capsys, command):
    src = tmp_path / "part.step"
    src.write_bytes(box_step.read_bytes())
    before = src.read_bytes()
    if command == "simplify":
        refused(["simplify", str(src), "-o", str(src)], capsys, "is the input part")
        (tmp_path / "p.json").symlink_to(src)
        refused(
            ["simplify", str(src), "-o", str(tmp_path / "o.step"), "--report",
             str(tmp_path / "p.json")], capsys, "is the input part",
        )  # fmt: skip
    else:
        (tmp_path / "p.json").symlink_to(src)
        refused(["classify", str(src), "--report", str(tmp_path / "p.json")], capsys, "input part")
    assert src.read_bytes() == before
    assert listing(tmp_path) == ["p.json", "part.step"]


# ---- the output path itself ---------------------------------------------------------------
@pytest.mark.parametrize(
    ("path", "message"),
    [
        ("", "empty file name"),
        ("newdir/", "names a folder"),
        ("sub", "is a folder"),
        ("sub/", "names a folder"),
        ("missing/a.json", "folder missing does not exist"),
    ],
)
def test_bad_output_paths(regions, tmp_path, capsys, monkeypatch, path, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    refused(axis(regions, "-o", path), capsys, message)
    refused(mesh(regions, "--format", "vtu", "-o", path), capsys, message)
    refused(mesh(regions, "-o", "m.vtu", "--report", path), capsys, message)
    assert listing(tmp_path) == ["r.json", "sub"] and listing(tmp_path / "sub") == []


def test_bad_output_paths_cad(box_step, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    refused(["simplify", str(box_step), "-o", ""], capsys, "empty file name")
    refused(["simplify", str(box_step), "-o", "d/"], capsys, "names a folder")
    refused(["simplify", str(box_step), "-o", "o.step", "--png", ""], capsys, "empty file name")
    refused(["classify", str(box_step), "--report", "x/"], capsys, "names a folder")
    assert listing(tmp_path) == []


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["simplify", "{box}", "-o", "o.stl"], "-o 'o.stl': '.stl' is not a known extension"),
        (["simplify", "{box}", "-o", "o"], "no extension"),
        (["simplify", "{box}", "-o", "o.step", "--png", "out.xyz"], "--png 'out.xyz': '.xyz'"),
        (["simplify", "{box}", "-o", "o.step", "--report", "r.txt"], "--report 'r.txt'"),
        (["classify", "{box}", "--png", "v.xyz"], "--png 'v.xyz': '.xyz'"),
        (["axis", "{regions}", "--region", "trapezoid", "-o", "a.vtu"], "-o 'a.vtu': '.vtu'"),
        (["axis", "{regions}", "--region", "wavy", "--plot", "p.xyz"], "--plot 'p.xyz'"),
        (["mesh", "{regions}", "--region", "wavy", "--size", "1", "-o", "m.xyz"], "'.xyz'"),
        (
            [
                "mesh",
                "{regions}",
                "--region",
                "wavy",
                "--size",
                "1",
                "-o",
                "m.vtu",
                "--plot",
                "p.gif",
            ],
            "--plot 'p.gif'",
        ),  # fmt: skip
    ],
)
def test_unknown_extensions_refused_up_front(
    regions, box_step, tmp_path, capsys, monkeypatch, argv, message
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "o.step").write_text("mine")
    argv = [a.format(box=box_step, regions=regions) for a in argv]
    refused(argv, capsys, message)
    assert listing(tmp_path) == ["o.step", "r.json"]
    assert (tmp_path / "o.step").read_text() == "mine"


# ---- special files ------------------------------------------------------------------------
def _char_device(tmp_path):
    """A character device to aim at: a /dev/null twin in ``tmp_path`` when we may create
    one; /dev/null itself only when we cannot replace it (not root). Never /dev/null as
    root: a regression here would replace the machine's /dev/null."""
    node = tmp_path / "null.json"
    try:
        os.mknod(node, stat.S_IFCHR | 0o666, os.makedev(1, 3))
        return node
    except (PermissionError, OSError):
        if os.geteuid() == 0:
            pytest.skip("cannot create a device node and will not risk /dev/null as root")
        return "/dev/null"


def test_char_device_and_fifo_not_replaced(regions, tmp_path, capsys):
    dev = _char_device(tmp_path)
    rdev = os.stat(dev).st_rdev
    refused(axis(regions, "-o", dev), capsys, "is a character device")
    refused(mesh(regions, "--format", "vtu", "-o", dev), capsys, "character device")
    assert stat.S_ISCHR(os.stat(dev).st_mode) and os.stat(dev).st_rdev == rdev
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    refused(axis(regions, "-o", fifo), capsys, "is a FIFO")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())


def test_read_only_output_not_replaced(regions, tmp_path, capsys):
    if os.geteuid() == 0:
        pytest.skip("root may write anything")
    out = tmp_path / "ro.json"
    out.write_text("keep")
    out.chmod(0o444)
    refused(axis(regions, "-o", out), capsys, "read-only")
    assert out.read_text() == "keep"


# ---- what is written ----------------------------------------------------------------------
@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_mode_follows_the_umask(regions, tmp_path, mask):
    old = os.umask(mask)
    try:
        outs = [tmp_path / n for n in ("a.json", "a.png", "m.vtu", "m.bdf", "q.json")]
        assert main(axis(regions, "-o", outs[0], "--plot", outs[1])) == 0
        assert main(mesh(regions, "-o", outs[2], "--report", outs[4])) == 0
        assert main(mesh(regions, "-o", outs[3])) == 0
    finally:
        os.umask(old)
    for p in outs:
        assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~mask, p


def test_long_name_and_existing_output_replaced(regions, tmp_path):
    out = tmp_path / ("x" * 245 + ".json")
    out.write_text("old")
    assert main(axis(regions, "-o", out)) == 0
    assert json.loads(out.read_text())["region"] == "trapezoid"
    mesh_out = tmp_path / ("m" * 246 + ".vtu")
    assert main(mesh(regions, "-o", mesh_out)) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["r.json", out.name, mesh_out.name])


def test_symlinked_output_writes_the_linked_file(regions, tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert main(axis(regions, "-o", link)) == 0
    assert link.is_symlink() and json.loads(real.read_text())["region"] == "trapezoid"


def test_failing_plot_leaves_no_output(regions, tmp_path, capsys, monkeypatch):
    """Outputs are all written or none: a plot that fails after the JSON was staged leaves
    the previous JSON in place and no temporary."""
    from medax.errors import MedaxError

    def boom(*_args, **_kw):
        raise MedaxError("plot failed")

    monkeypatch.setattr("medax.viz.axis_plot.plot_axes", boom)
    out = tmp_path / "a.json"
    out.write_text("old")
    refused(axis(regions, "-o", out, "--plot", tmp_path / "a.png"), capsys, "plot failed")
    assert out.read_text() == "old"
    assert listing(tmp_path) == ["a.json", "r.json"]


def test_simplify_failing_png_writes_nothing(box_step, tmp_path, capsys, monkeypatch):
    from medax.errors import MedaxError

    def boom(*_args, **_kw):
        raise MedaxError("picture failed")

    monkeypatch.setattr("medax.cli.simplify._png", boom)
    out = tmp_path / "o.step"
    out.write_text("mine")
    argv = ["simplify", str(box_step), "-o", str(out), "--report", str(tmp_path / "r.json")]
    refused([*argv, "--png", str(tmp_path / "p.png")], capsys, "picture failed")
    assert out.read_text() == "mine" and listing(tmp_path) == ["o.step"]


@pytest.mark.parametrize(("suffix", "head"), [(".brep", b"DBRep_DrawableShape"), (".igs", None)])
def test_simplify_writes_the_asked_format(box_step, tmp_path, suffix, head):
    from OCP.TopAbs import TopAbs_FACE

    from medax.cad.reader import count, read_part

    out = tmp_path / f"o{suffix}"
    assert main(["simplify", str(box_step), "-o", str(out)]) == 0
    data = out.read_bytes()
    if head is not None:
        assert data.startswith(head)
    else:  # IGES: 80-column records, the first in the start section
        assert data.split(b"\n", 1)[0].rstrip()[72:73] == b"S"
        assert b"ISO-10303" not in data
    part = read_part(out)
    assert len(part.solids) == 1 and count(part.solids[0], TopAbs_FACE) == 6
