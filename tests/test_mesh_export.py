"""Write-then-read round trips for every mesh format, with gmsh as the second reader."""

from __future__ import annotations

import os
from pathlib import Path

import meshio
import numpy as np
import pytest

from medax.errors import InputError
from medax.mesh.export import FORMATS, format_from_path, write_mesh
from medax.mesh.quality import quad_quality

gmsh = pytest.importorskip("gmsh")


def small_mesh(dim: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """A 3 x 2 grid of slightly sheared quads with negative, many-digit coordinates."""
    n1, n2 = 3, 2
    x, y = np.meshgrid(np.linspace(-1.2345678901234, 3.1, n1 + 1), np.linspace(-7.7, -0.3, n2 + 1))
    pts = np.column_stack(((x + 0.1 * y).ravel(), y.ravel()))
    if dim == 3:
        pts = np.column_stack((pts, -0.123456789012345 * pts[:, 0]))
    i, j = np.meshgrid(np.arange(n1), np.arange(n2))
    a = (j * (n1 + 1) + i).ravel()
    quads = np.column_stack((a, a + 1, a + n1 + 2, a + n1 + 1))
    return pts, quads


@pytest.fixture
def gmsh_session():
    started = not gmsh.isInitialized()
    if started:
        gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    yield gmsh
    gmsh.clear()
    if started:
        gmsh.finalize()


def gmsh_read(g, path: Path) -> tuple[np.ndarray, np.ndarray]:
    g.clear()
    g.open(str(path))
    tags, coords, _ = g.model.mesh.getNodes()
    order = np.argsort(tags)
    pts = coords.reshape(-1, 3)[order]
    types, _, nodes = g.model.mesh.getElements(2)
    assert list(types) == [3]  # gmsh element type 3 = 4-node quadrangle
    return pts, np.asarray(nodes[0], dtype=np.int64).reshape(-1, 4) - 1


@pytest.mark.parametrize("ext", [".msh", ".vtu", ".inp", ".bdf"])
@pytest.mark.parametrize("dim", [2, 3])
def test_round_trip_meshio(tmp_path, ext, dim):
    pts, quads = small_mesh(dim)
    q = quad_quality(pts, quads)
    path = write_mesh(tmp_path / f"m{ext}", pts, quads, q.as_dict())
    back = meshio.read(path)
    tol = 1e-9 if ext == ".bdf" else 1e-15  # Nastran fields hold 10 significant digits
    np.testing.assert_allclose(back.points[:, :dim], pts, rtol=tol, atol=tol)
    if back.points.shape[1] == 3 and dim == 2:
        assert np.all(back.points[:, 2] == 0.0)
    assert [c.type for c in back.cells] == ["quad"]
    np.testing.assert_array_equal(back.cells[0].data, quads)
    if ext in (".msh", ".vtu"):
        np.testing.assert_allclose(back.cell_data["scaled_jacobian"][0], q.scaled_jacobian)
    assert [p.name for p in tmp_path.iterdir()] == [f"m{ext}"]  # no temp file left


@pytest.mark.parametrize("ext", [".msh", ".bdf"])
def test_gmsh_reads_back(tmp_path, gmsh_session, ext):
    pts, quads = small_mesh(2)
    q = quad_quality(pts, quads)
    path = write_mesh(tmp_path / f"m{ext}", pts, quads, q.as_dict())
    gp, gq = gmsh_read(gmsh_session, path)
    tol = 1e-9 if ext == ".bdf" else 1e-15
    np.testing.assert_allclose(gp[:, :2], pts, rtol=tol, atol=tol)
    np.testing.assert_array_equal(gq, quads)
    if ext == ".msh":
        assert gmsh_session.model.getPhysicalGroups() == [(2, 1)]
        names = {}
        for v in gmsh_session.view.getTags():
            idx = gmsh_session.view.getIndex(v)
            names[gmsh_session.option.getString(f"View[{idx}].Name")] = v
        _, tags, values, *_ = gmsh_session.view.getModelData(names["scaled_jacobian"], 0)
        got = np.array([v[0] for v in values])[np.argsort(tags)]
        np.testing.assert_allclose(got, q.scaled_jacobian)


def test_abaqus_element_matches_gmsh_exporter(tmp_path, gmsh_session):
    """gmsh cannot read .inp; its own Abaqus exporter says which keyword a planar quad gets."""
    g = gmsh_session
    g.model.add("sq")
    g.model.occ.addRectangle(0, 0, 0, 1, 1)
    g.model.occ.synchronize()
    g.model.addPhysicalGroup(2, [1], 1)
    for c in range(1, 5):
        g.model.mesh.setTransfiniteCurve(c, 3)
    g.model.mesh.setTransfiniteSurface(1)
    g.model.mesh.setRecombine(2, 1)
    g.model.mesh.generate(2)
    g.write(str(tmp_path / "gmsh.inp"))
    gmsh_types = {
        line.split("type=")[1].split(",")[0].strip()
        for line in (tmp_path / "gmsh.inp").read_text().splitlines()
        if line.upper().startswith("*ELEMENT")
    }
    pts, quads = small_mesh(2)
    ours = write_mesh(tmp_path / "ours.inp", pts, quads).read_text().splitlines()
    elem = [line for line in ours if line.upper().startswith("*ELEMENT")]
    assert elem == ["*ELEMENT, TYPE=CPS4"]
    assert "CPS4" in gmsh_types
    assert "*ELSET, ELSET=MEDAX" in ours
    pts3, quads3 = small_mesh(3)
    text3 = write_mesh(tmp_path / "shell.inp", pts3, quads3).read_text()
    assert "*ELEMENT, TYPE=S4" in text3


def test_nastran_fields(tmp_path):
    pts, quads = small_mesh(3)
    lines = write_mesh(tmp_path / "m.bdf", pts, quads).read_text().splitlines()
    grids = [ln for ln in lines if ln.startswith(("GRID*", "*"))]
    assert all(len(ln) <= 72 for ln in grids)
    cq = [ln for ln in lines if ln.startswith("CQUAD4")]
    assert len(cq) == len(quads)
    assert all(ln[16:24].strip() == "1" for ln in cq)  # property id present


@pytest.mark.parametrize(
    ("name", "override", "want"),
    [
        ("a.msh", None, "msh"),
        ("a.VTU", None, "vtu"),
        ("a.inp", None, "abaqus"),
        ("a.nas", None, "nastran"),
        ("a.dat", "bdf", "nastran"),
        ("a.x", "abaqus", "abaqus"),
    ],
)
def test_format_from_path(name, override, want):
    assert format_from_path(name, override) == want
    assert want in FORMATS


def test_unknown_format(tmp_path):
    pts, quads = small_mesh()
    with pytest.raises(InputError, match="unknown mesh file extension '.stl'"):
        write_mesh(tmp_path / "m.stl", pts, quads)
    with pytest.raises(InputError, match="unknown mesh format 'foo'"):
        write_mesh(tmp_path / "m.msh", pts, quads, file_format="foo")
    assert list(tmp_path.iterdir()) == []


def test_unwritable_path(tmp_path):
    pts, quads = small_mesh()
    with pytest.raises(InputError, match="does not exist"):
        write_mesh(tmp_path / "nope" / "m.vtu", pts, quads)
    with pytest.raises(InputError, match="is a folder"):
        write_mesh(tmp_path, pts, quads, file_format="vtu")
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        try:
            with pytest.raises(InputError, match="cannot write"):
                write_mesh(ro / "m.vtu", pts, quads)
            assert list(ro.iterdir()) == []
        finally:
            ro.chmod(0o700)


def test_failed_write_keeps_old_file(tmp_path):
    pts, quads = small_mesh()
    target = tmp_path / "m.vtu"
    target.write_text("old")
    with pytest.raises(Exception):  # noqa: B017
        write_mesh(target, pts, quads, {"bad": np.zeros(1)})
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["m.vtu"]
