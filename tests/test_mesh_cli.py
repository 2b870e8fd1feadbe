"""``medax mesh`` and the mesh demo, in-process."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from medax.cli.main import main
from medax.geometry import sample_regions_path

REGIONS = str(sample_regions_path())


def test_mesh_vtu_report_plot(tmp_path, capsys):
    out, rep, png = tmp_path / "m.vtu", tmp_path / "q.json", tmp_path / "m.png"
    code = main(["mesh", REGIONS, "--region", "wavy", "--divisions", "7,12", "-o", str(out),
                 "--report", str(rep), "--plot", str(png)])  # fmt: skip
    assert code == 0
    m = meshio.read(out)
    assert len(m.points) == 8 * 13 and m.cells_dict["quad"].shape == (84, 4)
    r = json.loads(rep.read_text())
    assert r["n_nodes"] == 104 and r["n_quads"] == 84 and r["time_s"] > 0
    assert r["n_inverted"] == 0 and 0 < r["scaled_jacobian"]["min"] <= r["scaled_jacobian"]["p5"]
    assert {"mean", "p5", "min"} <= set(r["min_angle"])
    np.testing.assert_allclose(np.sort(m.cell_data["scaled_jacobian"][0])[0],
                               r["scaled_jacobian"]["min"])  # fmt: skip
    assert png.stat().st_size > 10_000
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("ext", [".msh", ".inp", ".bdf"])
def test_mesh_other_formats_and_size(tmp_path, ext):
    out = tmp_path / f"m{ext}"
    assert main(["mesh", REGIONS, "--region", "trapezoid", "--size", "1.0", "-o", str(out)]) == 0
    m = meshio.read(out)
    assert m.cells_dict["quad"].shape == (70, 4)  # 10 x 7: longest sides 10 and 6.5


def test_format_override(tmp_path):
    out = tmp_path / "mesh.dat"
    args = ["mesh", REGIONS, "--region", "arcs", "--divisions", "3", "-o", str(out)]
    assert main([*args, "--format", "nastran"]) == 0
    assert out.read_text().startswith("$ Nastran")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--size", "0"], "must be positive"),
        (["--size", "-2"], "must be positive"),
        (["--size", "1000"], "larger than region"),
        (["--divisions", "0,4"], "at least 1"),
        (["--divisions", "a,b"], "integers"),
        (["--divisions", "2,3,4"], "N1,N2"),
        (["--divisions", "4", "--format", "stl"], "unknown mesh format"),
        (["--divisions", "4", "--method", "paper", "--boundary", "ratio"], "not to paper"),
        (["--divisions", "4", "--tol=-1e-6"], "non-negative"),
        (["--divisions", "4", "--tol", "nan"], "--tol nan: must be a finite number"),
        (["--divisions", "4", "--tol", "inf"], "--tol inf: must be a finite number"),
        (["--divisions", "4", "--tol", "1e-15"], "below 1e-12"),
        (["--divisions", "4", "--method", "paper", "--tol", "0"], "--tol 0: must be positive"),
    ],
)
def test_bad_input(tmp_path, capsys, extra, message):
    out = tmp_path / "m.vtu"
    code = main(["mesh", REGIONS, "--region", "trapezoid", *extra, "-o", str(out)])
    assert code == 1
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_bad_paths(tmp_path, capsys):
    base = ["mesh", REGIONS, "--region", "trapezoid", "--divisions", "4"]
    assert main([*base, "-o", str(tmp_path / "m.stl")]) == 1
    assert "unknown mesh file extension" in capsys.readouterr().err
    assert main([*base, "-o", str(tmp_path / "no" / "m.vtu")]) == 1
    assert "does not exist" in capsys.readouterr().err
    assert main([*base, "-o", str(tmp_path / "m.vtu"), "--plot", str(tmp_path / "p.gif")]) == 1
    assert main(["mesh", REGIONS, "--region", "nope", "--divisions", "4", "-o",
                 str(tmp_path / "m.vtu")]) == 1  # fmt: skip
    assert "no region named 'nope'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_demo_mesh(tmp_path):
    from medax.cli.demo_mesh import demo

    written = demo(tmp_path)
    assert sorted(p.suffix for p in written) == [".png", ".png", ".vtu", ".vtu"]
    m = meshio.read(next(p for p in written if p.name.startswith("mesh-fig17")))
    assert m.cells[0].data.shape == (16 * 17, 4)
    assert np.all(m.cell_data["scaled_jacobian"][0] > 0)


def test_mesh_angle_method_on_the_annulus(tmp_path):
    """``--method angle`` runs and says so in the report; on the annulus sector it gives the
    same exact polar grid as the default."""
    out, rep = tmp_path / "a.vtu", tmp_path / "a.json"
    args = ["mesh", REGIONS, "--region", "annulus_sector", "--divisions", "5,7"]
    assert main([*args, "--method", "angle", "-o", str(out), "--report", str(rep)]) == 0
    assert json.loads(rep.read_text())["method"] == "angle"
    assert main([*args, "-o", str(tmp_path / "r.vtu")]) == 0
    a, r = meshio.read(out).points, meshio.read(tmp_path / "r.vtu").points
    np.testing.assert_allclose(a, r, atol=1e-9)


def test_mesh_boundary_rule(tmp_path):
    """--boundary ratio puts the boundary nodes at the ends of the constant-ratio curves:
    the mesh of mesh_region(boundary="ratio"), not the default (equal arc length)."""
    from medax.geometry import read_regions
    from medax.mesh.mesher import mesh_region

    region = read_regions(sample_regions_path())["wavy"]
    for rule in ("ratio", "arclength"):
        out = tmp_path / f"{rule}.vtu"
        args = ["mesh", REGIONS, "--region", "wavy", "--divisions", "6,5", "-o", str(out)]
        assert main([*args, "--boundary", rule]) == 0
        pts = meshio.read(out).points[:, :2]
        want = mesh_region(region, (6, 5), boundary=rule).points
        other = mesh_region(region, (6, 5), boundary="arclength" if rule == "ratio" else "ratio")
        np.testing.assert_allclose(pts, want, atol=1e-12)
        assert np.abs(pts - other.points).max() > 1e-3


def test_huge_divisions_refused_before_work(tmp_path, capsys, monkeypatch):
    """A division count whose estimated memory exceeds the limit is refused on one line that
    names the estimate, the limit and --force, before any meshing; nothing is written."""
    import medax.mesh.mesher as mesher

    def no_work(*args, **kwargs):
        raise AssertionError("meshed")

    monkeypatch.setattr(mesher, "mesh_region", no_work)
    out = tmp_path / "m.vtu"
    for extra, head in [
        (
            ["--divisions", "100000"],
            "--divisions 100000,100000: 1e+10 nodes, about 6e+03 GB and 27.8 h",
        ),
        (["--size", "1e-4"], "--size 0.0001 (100000x65000 quads): 6.5e+09 nodes, about"),
    ]:
        assert main(["mesh", REGIONS, "--region", "trapezoid", *extra, "-o", str(out)]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert head in err and "above the limit" in err and "--force" in err, err
    assert list(tmp_path.iterdir()) == []


def test_force_lifts_the_memory_limit(tmp_path, capsys, monkeypatch):
    """With the limit made tiny, a normal run is refused and --force runs it, saying the
    estimate on stderr first."""
    import medax.cli.limits as limits

    monkeypatch.setattr(limits, "MAX_BYTES", 1.0)
    out = tmp_path / "m.vtu"
    argv = ["mesh", REGIONS, "--region", "trapezoid", "--divisions", "4,3", "-o", str(out)]
    assert main(argv) == 1
    assert "--divisions 4,3: 20 nodes, about" in capsys.readouterr().err
    assert not out.exists()
    assert main([*argv, "--force"]) == 0
    assert "--divisions 4,3: estimated 20 nodes" in capsys.readouterr().err
    assert meshio.read(out).cells_dict["quad"].shape == (12, 4)


def test_large_run_says_its_estimate(tmp_path, capsys, monkeypatch):
    """Runs estimated above the note thresholds print the estimate on stderr and go on."""
    import medax.cli.limits as limits

    monkeypatch.setattr(limits, "NOTE_S", 0.0)
    out = tmp_path / "m.vtu"
    assert main(["mesh", REGIONS, "--region", "trapezoid", "--size", "2", "-o", str(out)]) == 0
    assert "--size 2 (5x4 quads): estimated 30 nodes, about" in capsys.readouterr().err


def test_available_memory(tmp_path, monkeypatch):
    """MemAvailable where /proc/meminfo has it, else the physical memory; the limit is the
    lower of half of it and the fixed cap."""
    import medax.cli.limits as limits

    avail = limits.available_memory()
    assert avail is not None and avail > 1e6
    limit, _ = limits.memory_limit()
    assert 0.0 < limit <= limits.MAX_BYTES and limit < avail
    monkeypatch.setattr(limits, "Path", lambda _: tmp_path / "no-meminfo")
    phys = limits.available_memory()
    assert phys is not None and phys >= avail * 0.5


@pytest.mark.parametrize("simplify", [[], ["--simplify"]])
def test_part_size_refused_before_work(tmp_path, capsys, monkeypatch, simplify):
    """``mesh PART --size H`` estimates its nodes from the part's surface area / H^2 and is
    refused above the limit before meshing or simplifying; nothing is written."""
    import medax.cad.part_mesh as part_mesh
    import medax.cad.simplify as cad_simplify
    from medax.samples import sample_path

    def no_work(*args, **kwargs):
        raise AssertionError("worked")

    monkeypatch.setattr(part_mesh, "mesh_part", no_work)
    monkeypatch.setattr(cad_simplify, "simplify", no_work)
    out = tmp_path / "p.msh"
    part = str(sample_path("l-bracket.step"))
    assert main(["mesh", part, "--size", "0.001", *simplify, "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert "--size 0.001: 4.53e+09 nodes, about" in err and "--force" in err, err
    assert list(tmp_path.iterdir()) == []
