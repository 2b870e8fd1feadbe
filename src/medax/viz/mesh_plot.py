"""Plot of a structured quad mesh, quads coloured by their scaled Jacobian."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from medax.mesh.grid import QuadMesh
from medax.viz.view3d import new_figure, save

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def plot_mesh(
    mesh: QuadMesh,
    path: str | Path | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Plot a structured quad mesh, quads filled by their scaled Jacobian.

    Quads are drawn in the parameter plane (the plane itself for a planar region), filled by
    scaled Jacobian (0..1, colour bar), edges in black, the region's sides on top.

    Parameters
    ----------
    mesh : QuadMesh
        The mesh ([QuadMesh][medax.mesh.grid.QuadMesh]).
    path : str or Path, optional
        Write the figure there (PNG, SVG or PDF by the extension).
    title : str, optional
        The title (default: the region, divisions, method and scaled Jacobian min and p5).
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).

    Returns
    -------
    Figure
        The figure drawn into.
    """
    from matplotlib.collections import PolyCollection

    quality = mesh.quality()
    sj = quality.scaled_jacobian
    polys = list(mesh.params[mesh.quads])  # m arrays (4, 2)
    own = ax is None
    if ax is None:
        ax = new_figure((7.5, 6.5), 120).add_subplot()
    fig: Figure = ax.figure  # type: ignore[assignment]
    edge_width = float(np.clip(8.0 / max(mesh.n1, mesh.n2), 0.05, 0.8))
    coll = PolyCollection(polys, array=sj, cmap="viridis", edgecolors="k", linewidths=edge_width)
    coll.set_clim(min(0.0, float(sj.min())), 1.0)
    ax.add_collection(coll)
    for side in mesh.region.sides:
        pts = side.sample(600)
        ax.plot(pts[:, 0], pts[:, 1], color="#d62728", lw=1.2)
    cbar = fig.colorbar(coll, ax=ax, shrink=0.85)
    cbar.set_label("scaled Jacobian (Verdict)")
    s = quality.summary()
    ax.set_title(
        title
        or f"{mesh.region.name}: {mesh.n1}x{mesh.n2} quads ({mesh.method}), scaled Jacobian "
        f"min {s['scaled_jacobian']['min']:.3f}, p5 {s['scaled_jacobian']['p5']:.3f}",
        fontsize=9,
    )
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    if own:
        fig.tight_layout()
    save(fig, path)
    return fig
