"""The z-buffer of the 3D view: nearer surfaces win, hidden lines are dropped."""

from __future__ import annotations

import numpy as np

from medax.viz.view3d import (
    CLASS_COLOURS,
    Faces,
    _Camera,
    _cell_borders,
    _rasterise,
    _visible_segments,
    render_part,
)


def square(z: float, half: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    pts = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    return pts, np.array([[0, 1, 2], [0, 2, 3]])


def shaded(cls: str, z: float, half: float) -> Faces:
    return Faces(*square(z, half), CLASS_COLOURS[cls])


def test_nearer_face_wins_whatever_the_drawing_order():
    top = shaded("fillet", 1.0, 0.5)
    bottom = shaded("protection", 0.0, 1.0)
    for faces in ([bottom, top], [top, bottom]):
        cam = _Camera((90.0 - 1e-6, 0.0), [f.points for f in faces], (200, 200))  # down -z
        img, zbuf, _ = _rasterise(faces, cam)
        centre = img[100, 100]
        # shaded fillet colour: a multiple of the base colour
        base = np.array(CLASS_COLOURS["fillet"])
        ratio = centre / base
        assert np.allclose(ratio, ratio[0], atol=1e-9)
        assert zbuf[100, 100] > zbuf[100, 30]  # the corner shows the lower square
        assert np.isfinite(zbuf[100, 30])


def test_hidden_line_is_dropped_visible_line_kept():
    faces = [shaded("protection", 1.0, 1.0)]
    cam = _Camera((90.0 - 1e-6, 0.0), [faces[0].points], (200, 200))
    _, zbuf, _ = _rasterise(faces, cam)
    below = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]])  # under the square: hidden
    above = np.array([[-0.5, 0.0, 2.0], [0.5, 0.0, 2.0]])  # over it: visible
    assert _visible_segments([below], cam, zbuf) == []
    (seg,) = _visible_segments([above], cam, zbuf)
    assert len(seg) > 50


def test_render_writes_png(tmp_path):
    render_part([("fillet",) + square(0.0)], tmp_path / "v.png", title="t")
    assert (tmp_path / "v.png").read_bytes()[:4] == b"\x89PNG"


def test_cell_outlines_one_pixel_wide_between_cells_and_at_the_silhouette():
    ids = np.full((5, 8), -1)
    ids[1:4, 1:4], ids[1:4, 4:7] = 0, 1
    border = _cell_borders(ids)
    assert border[2, 4] and not border[2, 3]  # between the cells: one pixel
    assert border[2, 1] and border[2, 6] and border[1, 2] and border[3, 2]  # silhouette
    assert not border[0].any() and not border[2, 2] and not border[2, 5]
