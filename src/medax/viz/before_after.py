"""Before/after picture of a fillet simplification: two opaque shaded 3D views side by side.

Faces come as triangle arrays ``(m, 3, 3)`` per face (``medax.cad.simplify.tessellate``).
Before: fillets removed in red, blends kept in black, the faces that absorb fillet halves each
in its own colour, the rest grey. After: each merged face in the colour of its supporting
face, the kept blends black, the rest grey, so both the merged faces and what stayed are
visible. Face boundaries are outlined. Rendered by
[render_faces][medax.viz.view3d.render_faces].
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from medax.viz.view3d import Faces, new_figure, render_faces, save

if TYPE_CHECKING:
    from matplotlib.figure import Figure

GREY = (0.78, 0.78, 0.8)
"""Colour of untouched faces (key -1), RGB 0-1."""
FILLET = (0.85, 0.2, 0.2)
"""Colour of removed fillets (key -2), RGB 0-1."""
KEPT = (0.12, 0.12, 0.12)
"""Colour of kept blends (key -3), RGB 0-1."""
PANEL = (660, 600)
"""Pixels of each of the two views."""


def group_colour(key: int) -> tuple[float, float, float]:
    """Give the colour of a face's key.

    Parameters
    ----------
    key : int
        A key of [plot_before_after][medax.viz.before_after.plot_before_after]: ``-1`` grey,
        ``-2`` red, ``-3`` black, ``k >= 0`` the ``k``-th colour of ``tab20`` (cyclic).

    Returns
    -------
    tuple of float
        The colour, RGB 0-1.
    """
    from matplotlib import colormaps

    fixed = {-1: GREY, -2: FILLET, -3: KEPT}
    if key < 0:
        return fixed[key]
    r, g, b, _ = colormaps["tab20"](key % 20)
    return (r, g, b)


def plot_before_after(
    before: Sequence[NDArray[np.float64]],
    after: Sequence[NDArray[np.float64]],
    before_colour: Sequence[int],
    after_colour: Sequence[int],
    path: str | Path | None = None,
    title: str = "",
    fig: Figure | None = None,
) -> Figure:
    """Draw the before and after views of a simplification side by side.

    Both views share one camera frame (the bounding box of all faces).

    Parameters
    ----------
    before, after : sequence of ndarray
        Per face its triangles (m, 3, 3).
    before_colour, after_colour : sequence of int
        Colour key of each face: ``-1`` grey, ``-2`` fillet removed (red), ``-3`` blend kept
        (black), ``k >= 0`` the ``k``-th colour of the qualitative map (same key = same new
        face).
    path : str or Path, optional
        Write the figure there (PNG, SVG or PDF by the extension).
    title : str
        The figure's title.
    fig : matplotlib Figure, optional
        Draw into it (default: a new figure).

    Returns
    -------
    Figure
        The figure drawn into.
    """
    dpi = 110
    if fig is None:
        fig = new_figure((2 * PANEL[0] / dpi, PANEL[1] / dpi + 0.4), dpi)
    # one camera frame for both views: the bounding box of all faces, as a hidden face
    allpts = np.vstack([t.reshape(-1, 3) for t in list(before) + list(after) if t.size])
    frame = Faces(np.vstack([allpts.min(axis=0), allpts.max(axis=0)]), np.zeros((0, 3), int), GREY)
    for k, (faces, keys, label) in enumerate(
        ((before, before_colour, "before"), (after, after_colour, "after"))
    ):
        ax = fig.add_axes((0.5 * k, 0.0, 0.5, 0.92))
        shaded = [
            Faces(t.reshape(-1, 3), np.arange(3 * len(t)).reshape(-1, 3), group_colour(key))
            for t, key in zip(faces, keys, strict=True)
        ]
        render_faces([*shaded, frame], ax, outline=True, view=(28.0, -58.0), size=PANEL)
        n_kept = sum(1 for key in keys if key == -3)
        ax.set_title(
            f"{label}: {len(faces)} faces" + (f", {n_kept} blends kept (black)" if n_kept else ""),
            fontsize=10,
        )
    if title:
        fig.suptitle(title)
    save(fig, path)
    return fig
