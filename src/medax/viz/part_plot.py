"""Picture of a part's quad mesh in space, quads coloured by their scaled Jacobian."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from medax.geometry._types import FloatArray, IntArray
from medax.viz.view3d import Faces, render_faces, save

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def plot_part_mesh(
    points: FloatArray,
    quads: IntArray,
    values: FloatArray,
    path: str | Path | None = None,
    title: str = "",
    ax: Axes | None = None,
) -> Figure:
    """Plot a part's quad mesh in an axonometric view, quads filled by a value.

    The view is opaque (one renderer, [render_faces][medax.viz.view3d.render_faces]), quads
    outlined, with a colour bar.

    Parameters
    ----------
    points : ndarray
        Nodes (n, 3).
    quads : ndarray
        Node indices (m, 4).
    values : ndarray
        Value per quad (m,): the scaled Jacobian, coloured over 0..1.
    path : str or Path, optional
        Write the figure there (PNG, SVG or PDF by the extension).
    title : str
        The title.
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).

    Returns
    -------
    Figure
        The figure drawn into.
    """
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    values = np.asarray(values, dtype=np.float64)
    norm = Normalize(min(0.0, float(values.min())) if len(values) else 0.0, 1.0)
    cmap = colormaps["viridis"]
    rgb = cmap(norm(values))[:, :3]
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    cells = np.concatenate([np.arange(len(quads))] * 2)
    faces = [Faces(points, tris, np.concatenate([rgb, rgb]), cells)]
    fig = render_faces(faces, ax, outline=True, view=(25.0, -60.0), size=(860, 780), light=0.35)
    ax = ax or fig.axes[0]
    cbar = fig.colorbar(ScalarMappable(norm, cmap), ax=ax, shrink=0.7)
    cbar.set_label("scaled Jacobian (Verdict)")
    ax.set_title(title, fontsize=9)
    save(fig, path)
    return fig
