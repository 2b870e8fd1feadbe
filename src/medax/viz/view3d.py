"""The one 3D renderer of medax: opaque shaded faces, off-screen, into a matplotlib Axes.

Inputs are plain arrays (no OCP here): [Faces][medax.viz.view3d.Faces] (points, triangles,
colours), polylines
for edges and axes. Triangles are shaded by a fixed light (Lambert) and hidden surfaces and
lines removed with a small numpy z-buffer (an orthographic view), so the picture is opaque
and correct where matplotlib's painter's algorithm would sort badly; lines are drawn only
where they are visible. Cell outlines (quads of a mesh, faces of a part) are drawn where the
visible cell changes from one pixel to the next. [render_faces][medax.viz.view3d.render_faces]
is used by the classified part's view ([render_part][medax.viz.view3d.render_part]), the
before/after view and the part mesh plot. No backend is selected: figures are
``matplotlib.figure.Figure`` objects, not pyplot's.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from medax.geometry._types import FloatArray, IntArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: face colours by class (RGB, 0-1)
CLASS_COLOURS = {
    "fillet": (0.90, 0.35, 0.20),
    "corner_blend": (0.85, 0.15, 0.55),
    "supporting": (0.30, 0.55, 0.85),
    "protection": (0.78, 0.78, 0.75),
}
AXIS_COLOUR = (0.05, 0.05, 0.05)
EDGE_COLOUR = (0.1, 0.1, 0.1)


class Faces(NamedTuple):
    """Triangles to render, with their colours and cells.

    Attributes
    ----------
    points : ndarray
        Vertices (n, 3).
    triangles : ndarray
        Vertex indices (m, 3), int.
    colour : array_like
        RGB 0-1: one (3,) or one per triangle (m, 3).
    cells : ndarray or None
        Cell of each triangle (m,), int: outlines are drawn between triangles of different
        cells (None: one cell, outlined only against other ``Faces``).
    """

    points: FloatArray
    triangles: IntArray
    colour: Any
    cells: IntArray | None = None


def render_faces(
    faces: Sequence[Faces],
    ax: Axes | None = None,
    *,
    lines: Sequence[tuple[Sequence[FloatArray], tuple[float, float, float], float]] = (),
    outline: bool = False,
    view: tuple[float, float] = (28.0, -55.0),
    size: tuple[int, int] = (960, 720),
    dpi: int = 120,
    light: float = 0.7,
) -> Figure:
    """Render triangles opaquely, with hidden surfaces and lines removed.

    Parameters
    ----------
    faces : sequence of Faces
        The triangles to render ([Faces][medax.viz.view3d.Faces]).
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure of ``size`` pixels).
    lines : sequence of tuple
        Groups ``(polylines (k, 3), RGB, width)``, drawn where visible.
    outline : bool
        Darken the pixels where the visible cell changes.
    view : tuple of float
        ``(elevation, azimuth)`` of the orthographic camera, in degrees.
    size : tuple of int
        Image size in pixels ``(width, height)``.
    dpi : int
        Dots per inch of a new figure.
    light : float
        Share of the colour that depends on the light (0: flat colours).

    Returns
    -------
    Figure
        The figure drawn into.
    """
    from matplotlib.collections import LineCollection

    fig, ax = _figure_and_axes(ax, size, dpi)
    cam = _Camera(view, [f.points for f in faces], size)
    img, zbuf, ids = _rasterise(faces, cam, light)
    if outline:
        img[_cell_borders(ids)] *= 0.25
    ax.imshow(img, origin="upper", interpolation="bilinear")
    ax.set_xlim(-0.5, size[0] - 0.5)
    ax.set_ylim(size[1] - 0.5, -0.5)
    ax.set_axis_off()
    for polylines, rgb, width in lines:
        segs = _visible_segments(polylines, cam, zbuf)
        ax.add_collection(LineCollection(segs, colors=[rgb], lw=width))
    return fig


def render_part(
    faces: Sequence[tuple[str, FloatArray, IntArray]],
    path: str | Path | None = None,
    edges: Sequence[FloatArray] = (),
    axes: Sequence[FloatArray] = (),
    title: str = "",
    counts: dict[str, int] | None = None,
    view: tuple[float, float] = (28.0, -55.0),
    size: tuple[int, int] = (960, 720),
    dpi: int = 120,
    ax: Axes | None = None,
) -> Figure:
    """Render a classified part: faces coloured by class, visible edges and fillet axes.

    A legend gives the count per class.

    Parameters
    ----------
    faces : sequence of tuple
        Per face ``(class name, points (n, 3), triangles (m, 3) int)``.
    path : str or Path, optional
        Write the figure there (PNG, SVG or PDF by the extension).
    edges, axes : sequence of ndarray
        Polylines (k, 3) of the edges and of the fillets' medial axes.
    title : str
        The title.
    counts : dict of str to int, optional
        Faces per class, for the legend.
    view : tuple of float
        ``(elevation, azimuth)`` in degrees.
    size : tuple of int
        Image size in pixels ``(width, height)``.
    dpi : int
        Dots per inch of a new figure.
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).

    Returns
    -------
    Figure
        The figure drawn into.
    """
    from matplotlib.patches import Patch

    grey = (0.6, 0.6, 0.6)
    shaded = [Faces(p, t, CLASS_COLOURS.get(cls, grey)) for cls, p, t in faces]
    lines = [(edges, EDGE_COLOUR, 0.6), (axes, AXIS_COLOUR, 2.2)]
    fig = render_faces(shaded, ax, lines=lines, view=view, size=size, dpi=dpi)
    ax = ax or fig.axes[0]
    counts = counts or {}
    handles = [
        Patch(color=CLASS_COLOURS[k], label=f"{k.replace('_', ' ')} ({counts.get(k, 0)})")
        for k in CLASS_COLOURS
    ]
    handles.append(Patch(color=AXIS_COLOUR, label="medial axis"))
    ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False)
    if title:
        ax.text(0.5, 0.98, title, transform=ax.transAxes, ha="center", va="top", fontsize=10)
    save(fig, path)
    return fig


def save(fig: Figure, path: str | Path | None, **kwargs: Any) -> None:
    """Write a figure when given a path (format by extension, PNG when none).

    Parameters
    ----------
    fig : Figure
        The figure.
    path : str or Path or None
        Where to write it; None writes nothing.
    **kwargs
        Passed to ``Figure.savefig``.
    """
    if path is not None:
        out = Path(path)
        fig.savefig(out, format=out.suffix.lstrip(".").lower() or "png", **kwargs)


def new_figure(figsize: tuple[float, float], dpi: int = 100) -> Figure:
    """Create a figure not registered with pyplot.

    No backend is selected or switched, nothing needs closing, and a notebook displays it
    when it is returned.

    Parameters
    ----------
    figsize : tuple of float
        ``(width, height)`` in inches.
    dpi : int
        Dots per inch.

    Returns
    -------
    Figure
        The new figure.
    """
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, dpi=dpi)


def _figure_and_axes(ax: Axes | None, size: tuple[int, int], dpi: int) -> tuple[Figure, Axes]:
    if ax is not None:
        return ax.figure, ax  # type: ignore[return-value]
    fig = new_figure((size[0] / dpi, size[1] / dpi), dpi)
    return fig, fig.add_axes((0.0, 0.0, 1.0, 1.0))


class _Camera:
    """Orthographic camera looking at the part's centre from (elevation, azimuth)."""

    def __init__(
        self,
        view: tuple[float, float],
        points: Sequence[FloatArray],
        size: tuple[int, int],
    ) -> None:
        elev, azim = np.radians(view[0]), np.radians(view[1])
        self.eye = np.array(
            [np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)]
        )
        right = np.cross([0.0, 0.0, 1.0], self.eye)
        self.right = right / np.linalg.norm(right)
        self.up = np.cross(self.eye, self.right)
        allp = np.concatenate(points) if len(points) else np.zeros((1, 3))
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
    faces: Sequence[Faces], cam: _Camera, light: float = 0.7
) -> tuple[FloatArray, FloatArray, IntArray]:
    """Colour image (h, w, 3), depth buffer (h, w) (-inf where empty) and cell buffer (h, w)
    (-1 where empty; cells numbered over all ``faces``)."""
    img = np.ones((cam.h, cam.w, 3))
    zbuf = np.full((cam.h, cam.w), -np.inf)
    ids = np.full((cam.h, cam.w), -1, dtype=np.int64)
    towards = cam.eye + 0.5 * cam.up + 0.3 * cam.right
    towards /= np.linalg.norm(towards)
    first = 0
    for face in faces:
        pts, tris = np.asarray(face.points, dtype=np.float64), np.asarray(face.triangles)
        if len(tris) == 0:
            continue
        t = pts[tris]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        shade = (1.0 - light) + light * np.abs(n @ towards)
        rgb = np.broadcast_to(np.asarray(face.colour, dtype=np.float64), (len(tris), 3))
        rgb = shade[:, None] * rgb
        cells = np.zeros(len(tris), np.int64) if face.cells is None else np.asarray(face.cells)
        col, row, dep = cam.project(pts)
        for k, (a, b, c) in enumerate(tris.tolist()):
            idx = [a, b, c]
            _triangle(img, zbuf, ids, col[idx], row[idx], dep[idx], rgb[k], first + int(cells[k]))
        first += int(cells.max()) + 1
    return img, zbuf, ids


def _cell_borders(ids: IntArray) -> np.ndarray:
    """Pixels (h, w) bool of a cell next to another cell or to the background, one wide."""
    border = np.zeros(ids.shape, dtype=bool)
    dx, dy = ids[:, 1:] != ids[:, :-1], ids[1:, :] != ids[:-1, :]
    empty_x, empty_y = ids[:, 1:] < 0, ids[1:, :] < 0
    border[:, 1:] |= dx & ~empty_x  # one pixel wide: the right / lower cell's
    border[:, :-1] |= dx & empty_x  # against the background: the cell's own
    border[1:, :] |= dy & ~empty_y
    border[:-1, :] |= dy & empty_y
    return border


def _triangle(
    img: FloatArray,
    zbuf: FloatArray,
    ids: IntArray,
    x: FloatArray,
    y: FloatArray,
    z: FloatArray,
    rgb: FloatArray,
    cell: int,
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
    ids[y0 : y1 + 1, x0 : x1 + 1][win] = cell


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
