"""Off-screen shaded 3D view of a classified part (matplotlib, Agg; no display needed).

Inputs are plain arrays (no OCP here): per face its triangles and class, the edges as
polylines, the fillet axes as polylines. Faces are coloured by class and shaded by a fixed
light (Lambert). Hidden surfaces and lines are removed with a small numpy z-buffer (an
orthographic view), so the picture is correct where matplotlib's painter's algorithm
would sort badly; edges and axes are drawn only where they are visible.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from medax.geometry._types import FloatArray

#: face colours by class (RGB, 0-1)
CLASS_COLOURS = {
    "fillet": (0.90, 0.35, 0.20),
    "corner_blend": (0.85, 0.15, 0.55),
    "supporting": (0.30, 0.55, 0.85),
    "protection": (0.78, 0.78, 0.75),
}
AXIS_COLOUR = (0.05, 0.05, 0.05)


def render_part(
    faces: Sequence[tuple[str, FloatArray, np.ndarray]],
    path: str | Path,
    edges: Sequence[FloatArray] = (),
    axes: Sequence[FloatArray] = (),
    title: str = "",
    counts: dict[str, int] | None = None,
    view: tuple[float, float] = (28.0, -55.0),
    size: tuple[int, int] = (960, 720),
    dpi: int = 120,
) -> Path:
    """Render to ``path`` (PNG or SVG by extension).

    ``faces``: ``(class name, points (n, 3), triangles (m, 3) int)`` per face; ``edges``
    and ``axes``: polylines (k, 3). ``view`` = (elevation, azimuth) in degrees; ``size``
    in pixels.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    cam = _Camera(view, faces, size)
    img, zbuf = _rasterise(faces, cam)

    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.imshow(img, origin="upper", interpolation="bilinear")
    ax.set_xlim(-0.5, size[0] - 0.5)
    ax.set_ylim(size[1] - 0.5, -0.5)
    ax.set_axis_off()
    ax.add_collection(
        LineCollection(_visible_segments(edges, cam, zbuf), colors=[(0.1, 0.1, 0.1)], lw=0.6)
    )
    ax.add_collection(
        LineCollection(_visible_segments(axes, cam, zbuf), colors=[AXIS_COLOUR], lw=2.2)
    )
    counts = counts or {}
    handles = [
        Patch(color=CLASS_COLOURS[k], label=f"{k.replace('_', ' ')} ({counts.get(k, 0)})")
        for k in CLASS_COLOURS
    ]
    handles.append(Patch(color=AXIS_COLOUR, label="medial axis"))
    ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False)
    if title:
        ax.text(0.5, 0.98, title, transform=ax.transAxes, ha="center", va="top", fontsize=10)
    out = Path(path)
    fig.savefig(out, format=out.suffix.lstrip(".").lower() or "png")
    return out


class _Camera:
    """Orthographic camera looking at the part's centre from (elevation, azimuth)."""

    def __init__(
        self,
        view: tuple[float, float],
        faces: Sequence[tuple[str, FloatArray, np.ndarray]],
        size: tuple[int, int],
    ) -> None:
        elev, azim = np.radians(view[0]), np.radians(view[1])
        self.eye = np.array(
            [np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)]
        )
        right = np.cross([0.0, 0.0, 1.0], self.eye)
        self.right = right / np.linalg.norm(right)
        self.up = np.cross(self.eye, self.right)
        pts = [p for _, p, t in faces if len(t)]
        allp = np.concatenate(pts) if pts else np.zeros((1, 3))
        self.w, self.h = size
        sx, sy = allp @ self.right, allp @ self.up
        self.cx, self.cy = 0.5 * (sx.min() + sx.max()), 0.5 * (sy.min() + sy.max())
        span = max(float(np.ptp(sx)) / (0.9 * self.w), float(np.ptp(sy)) / (0.8 * self.h), 1e-300)
        self.scale = 1.0 / span
        depth = allp @ self.eye
        self.bias = 5e-3 * max(float(np.ptp(depth)), 1e-300)

    def project(self, p: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Pixel column, row and depth (larger = nearer) of points ``p`` (n, 3)."""
        col = (p @ self.right - self.cx) * self.scale + 0.5 * self.w
        row = -(p @ self.up - self.cy) * self.scale + 0.52 * self.h
        return col, row, p @ self.eye


def _rasterise(
    faces: Sequence[tuple[str, FloatArray, np.ndarray]], cam: _Camera
) -> tuple[FloatArray, FloatArray]:
    """Colour image (h, w, 3) and depth buffer (h, w) (-inf where empty)."""
    img = np.ones((cam.h, cam.w, 3))
    zbuf = np.full((cam.h, cam.w), -np.inf)
    light = cam.eye + 0.5 * cam.up + 0.3 * cam.right
    light /= np.linalg.norm(light)
    for cls, pts, tris in faces:
        if len(tris) == 0:
            continue
        t = pts[tris]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        shade = 0.3 + 0.7 * np.abs(n @ light)
        base = np.array(CLASS_COLOURS.get(cls, (0.6, 0.6, 0.6)))
        col, row, dep = cam.project(pts)
        for k, (a, b, c) in enumerate(tris):
            _triangle(img, zbuf, col[[a, b, c]], row[[a, b, c]], dep[[a, b, c]], shade[k] * base)
    return img, zbuf


def _triangle(
    img: FloatArray, zbuf: FloatArray, x: FloatArray, y: FloatArray, z: FloatArray, rgb: FloatArray
) -> None:
    h, w = zbuf.shape
    x0, x1 = max(int(np.floor(x.min())), 0), min(int(np.ceil(x.max())), w - 1)
    y0, y1 = max(int(np.floor(y.min())), 0), min(int(np.ceil(y.max())), h - 1)
    if x0 > x1 or y0 > y1:
        return
    det = (y[1] - y[2]) * (x[0] - x[2]) + (x[2] - x[1]) * (y[0] - y[2])
    if abs(det) < 1e-12:
        return
    gx, gy = np.meshgrid(np.arange(x0, x1 + 1), np.arange(y0, y1 + 1))
    l0 = ((y[1] - y[2]) * (gx - x[2]) + (x[2] - x[1]) * (gy - y[2])) / det
    l1 = ((y[2] - y[0]) * (gx - x[2]) + (x[0] - x[2]) * (gy - y[2])) / det
    l2 = 1.0 - l0 - l1
    eps = -1e-9
    inside = (l0 >= eps) & (l1 >= eps) & (l2 >= eps)
    if not inside.any():
        return
    depth = l0 * z[0] + l1 * z[1] + l2 * z[2]
    sub = zbuf[y0 : y1 + 1, x0 : x1 + 1]
    win = inside & (depth > sub)
    sub[win] = depth[win]
    img[y0 : y1 + 1, x0 : x1 + 1][win] = rgb


def _visible_segments(
    lines: Sequence[FloatArray], cam: _Camera, zbuf: FloatArray
) -> list[FloatArray]:
    """Pieces (k, 2) in pixels of the polylines that are not hidden by a surface."""
    out: list[FloatArray] = []
    h, w = zbuf.shape
    for line in lines:
        if len(line) < 2:
            continue
        col, row, dep = cam.project(np.asarray(line, dtype=np.float64))
        # resample to about one point per pixel
        seg = np.hypot(np.diff(col), np.diff(row))
        n = np.maximum(np.ceil(seg).astype(int), 1)
        s = np.concatenate([np.arange(k) / k for k in n])
        i = np.repeat(np.arange(len(n)), n)
        c = np.append(col[i] + s * (col[i + 1] - col[i]), col[-1])
        r = np.append(row[i] + s * (row[i + 1] - row[i]), row[-1])
        d = np.append(dep[i] + s * (dep[i + 1] - dep[i]), dep[-1])
        ci = np.clip(np.rint(c).astype(int), 0, w - 1)
        ri = np.clip(np.rint(r).astype(int), 0, h - 1)
        # compare with the nearest surface in a 3x3 neighbourhood (edges lie on two faces)
        near = np.full(len(c), -np.inf)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr = np.clip(ri + dr, 0, h - 1)
                cc = np.clip(ci + dc, 0, w - 1)
                near = np.maximum(near, zbuf[rr, cc])
        vis = d >= near - cam.bias
        pts = np.column_stack((c, r))
        edges_vis = np.flatnonzero(np.diff(np.concatenate(([0], vis.astype(int), [0]))))
        for a, b in zip(edges_vis[::2], edges_vis[1::2], strict=True):
            if b - a >= 2:
                out.append(pts[a:b])
    return out
