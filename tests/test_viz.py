"""Plots fit notebooks: every plot function draws into a given axes (or figure) or a new one,
returns the figure, writes a file only when given a path, and never selects a backend."""

from __future__ import annotations

import ast
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

import medax
from medax.geometry.region_io import read_region
from medax.samples import sample_path
from medax.viz.axis_plot import plot_axes
from medax.viz.before_after import plot_before_after
from medax.viz.mesh_plot import plot_mesh
from medax.viz.part_plot import plot_part_mesh
from medax.viz.view3d import render_part

SRC = Path(medax.__file__).parent


@pytest.fixture(autouse=True)
def no_backend_switch(monkeypatch):
    """Selecting a backend (``matplotlib.use``, pyplot's ``switch_backend``) fails the test."""

    def refuse(*args, **kwargs):
        raise AssertionError("a plot function selected a matplotlib backend")

    monkeypatch.setattr(matplotlib, "use", refuse)
    try:
        import matplotlib.pyplot as plt

        monkeypatch.setattr(plt, "switch_backend", refuse)
    except ImportError:  # pragma: no cover
        pass


@pytest.fixture(scope="module")
def region():
    return read_region(sample_path("regions.json"), "wavy")


def _box_faces():
    """The six faces of a unit cube, each as triangles (2, 3, 3)."""
    c = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return c, np.array(quads), [c[[[a, b, e], [a, e, d]]] for a, b, e, d in quads]


def _plots(region):
    """(name, call(ax_or_fig, path)) for every plot function, and whether it takes ``fig``."""
    axis = medax.trace_axis(region, (0, 2))
    mesh = medax.mesh_region(region, divisions=(6, 6))
    pts, quads, tris = _box_faces()
    sj = np.linspace(0.5, 1.0, len(quads))
    faces = [("supporting", pts, np.array([[0, 1, 3], [0, 3, 2]]))]
    return [
        ("plot_axes", lambda ax, p: plot_axes(region, [axis], p, ax=ax), False),
        ("plot_mesh", lambda ax, p: plot_mesh(mesh, p, ax=ax), False),
        ("plot_part_mesh", lambda ax, p: plot_part_mesh(pts, quads, sj, p, "t", ax=ax), False),
        ("render_part", lambda ax, p: render_part(faces, p, title="t", ax=ax), False),
        (
            "plot_before_after",
            lambda fig, p: plot_before_after(tris, tris[:2], [-2] * 6, [0, 1], p, "t", fig=fig),
            True,
        ),
    ]


def test_every_plot_with_and_without_axes(region, tmp_path):
    for name, call, takes_fig in _plots(region):
        fig = call(None, None)
        assert isinstance(fig, Figure) and fig.axes, name
        assert not list(tmp_path.iterdir()), f"{name} wrote a file without a path"
        mine = Figure()
        target = mine if takes_fig else mine.add_subplot()
        assert call(target, None) is mine, name
        out = tmp_path / f"{name}.png"
        assert isinstance(call(None, out), Figure)
        assert out.read_bytes()[:4] == b"\x89PNG", name
        out.unlink()


def test_before_after_is_opaque(region):
    """The far faces of the cube are hidden: the picture of the whole cube equals the
    picture of its three near faces (a see-through view would differ)."""
    _, _, tris = _box_faces()
    whole = plot_before_after(tris, tris, [0] * 6, [0] * 6)
    img = np.asarray(whole.axes[0].images[0].get_array())
    assert img.shape[2] == 3 and np.isfinite(img).all()
    near = [k for k in range(6) if _faces_viewer(tris[k])]
    part = plot_before_after([tris[k] for k in near], tris, [0] * len(near), [0] * 6)
    img_near = np.asarray(part.axes[0].images[0].get_array())
    assert np.allclose(img, img_near)


def _faces_viewer(tri: np.ndarray) -> bool:
    """Whether the cube face ``tri`` (2, 3, 3) faces the default view (elevation 28,
    azimuth -58)."""
    elev, azim = np.radians(28.0), np.radians(-58.0)
    eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
    centre = tri.reshape(-1, 3).mean(axis=0) - 0.5
    return bool(centre @ eye > 0)


def test_library_never_selects_a_backend_nor_uses_pyplot():
    """``matplotlib.use`` and pyplot appear nowhere in the library (the CLI may select)."""
    for path in SRC.rglob("*.py"):
        if "cli" in path.relative_to(SRC).parts:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and node.attr == "use":
                assert getattr(node.value, "id", "") != "matplotlib", path
            if isinstance(node, ast.ImportFrom | ast.Import):
                names = [node.module or ""] if isinstance(node, ast.ImportFrom) else []
                names += [a.name for a in node.names]
                assert not any("pyplot" in n for n in names), path
