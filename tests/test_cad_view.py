"""The z-buffer of the 3D view: nearer surfaces win, hidden lines are dropped."""

from __future__ import annotations

import numpy as np

from medax.viz.view3d import CLASS_COLOURS, _Camera, _rasterise, _visible_segments, render_part


def square(z: float, half: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    pts = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    return pts, np.array([[0, 1, 2], [0, 2, 3]])


def test_nearer_face_wins_whatever_the_drawing_order():
    top = ("fillet",) + square(1.0, 0.5)
    bottom = ("protection",) + square(0.0, 1.0)
    for faces in ([bottom, top], [top, bottom]):
        cam = _Camera((90.0 - 1e-6, 0.0), faces, (200, 200))  # looking down -z
        img, zbuf = _rasterise(faces, cam)
        centre = img[100, 100]
        # shaded fillet colour: a multiple of the base colour
        base = np.array(CLASS_COLOURS["fillet"])
        ratio = centre / base
        assert np.allclose(ratio, ratio[0], atol=1e-9)
        assert zbuf[100, 100] > zbuf[100, 30]  # the corner shows the lower square
        assert np.isfinite(zbuf[100, 30])


def test_hidden_line_is_dropped_visible_line_kept():
    faces = [("protection",) + square(1.0, 1.0)]
    cam = _Camera((90.0 - 1e-6, 0.0), faces, (200, 200))
    _, zbuf = _rasterise(faces, cam)
    below = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]])  # under the square: hidden
    above = np.array([[-0.5, 0.0, 2.0], [0.5, 0.0, 2.0]])  # over it: visible
    assert _visible_segments([below], cam, zbuf) == []
    (seg,) = _visible_segments([above], cam, zbuf)
    assert len(seg) > 50


def test_render_writes_png(tmp_path):
    out = render_part([("fillet",) + square(0.0)], tmp_path / "v.png", title="t")
    assert out.read_bytes()[:4] == b"\x89PNG"
