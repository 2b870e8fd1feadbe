"""Off-screen shaded 3D view of a classified part (matplotlib, Agg; no display needed).

Inputs are plain arrays (no OCP here): per face its triangles and class, the edges as
polylines, the fillet axes as polylines. Faces are coloured by class and shaded by a fixed
light (Lambert); axes are drawn on top of the fillets.
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
    size: tuple[float, float] = (8.0, 6.5),
    dpi: int = 120,
) -> Path:
    """Render to ``path`` (PNG or SVG by extension).

    ``faces``: ``(class name, points (n, 3), triangles (m, 3) int)`` per face; ``edges``
    and ``axes``: polylines (k, 3). ``view`` = (elevation, azimuth) in degrees.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    fig = Figure(figsize=size, dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(111, projection="3d")
    elev, azim = np.radians(view[0]), np.radians(view[1])
    eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
    light = eye + np.array([0.3, 0.2, 0.6])
    light /= np.linalg.norm(light)

    tris_all, cols_all = [], []
    for cls, pts, tris in faces:
        if len(tris) == 0:
            continue
        t = pts[tris]  # (m, 3, 3)
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        shade = 0.35 + 0.65 * np.abs(n @ light)
        base = np.array(CLASS_COLOURS.get(cls, (0.6, 0.6, 0.6)))
        tris_all.append(t)
        cols_all.append(np.clip(shade[:, None] * base[None, :], 0.0, 1.0))
    if tris_all:
        tri = np.concatenate(tris_all)
        col = np.concatenate(cols_all)
        poly = Poly3DCollection(tri, facecolors=col, edgecolors="none", linewidths=0.0)
        ax.add_collection3d(poly)
        allpts = tri.reshape(-1, 3)
    else:
        allpts = np.zeros((1, 3))
    if edges:
        ax.add_collection3d(
            Line3DCollection(list(edges), colors=[(0.15, 0.15, 0.15)], linewidths=0.5)
        )
    for a in axes:
        ax.plot(a[:, 0], a[:, 1], a[:, 2], color=AXIS_COLOUR, linewidth=2.0, zorder=10)
        ax.plot(a[[0, -1], 0], a[[0, -1], 1], a[[0, -1], 2], "o", color=AXIS_COLOUR, ms=2.5)
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    mid, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo))
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_axis_off()
    counts = counts or {}
    handles = [
        Patch(color=CLASS_COLOURS[k], label=f"{k.replace('_', ' ')} ({counts.get(k, 0)})")
        for k in CLASS_COLOURS
    ]
    handles.append(Patch(color=AXIS_COLOUR, label="medial axis"))
    ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False)
    if title:
        ax.set_title(title, fontsize=10)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.95)
    out = Path(path)
    fig.savefig(out, format=out.suffix.lstrip(".").lower() or "png")
    return out
