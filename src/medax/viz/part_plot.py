"""Picture of a part's quad mesh in space, quads coloured by their scaled Jacobian."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from medax.geometry._types import FloatArray, IntArray


def plot_part_mesh(
    points: FloatArray,
    quads: IntArray,
    values: FloatArray,
    path: str | Path,
    title: str = "",
) -> Path:
    """Draw ``quads`` (m, 4) over ``points`` (n, 3) in an axonometric view, filled by
    ``values`` (m,) (the scaled Jacobian, 0..1, colour bar), thin black edges; PNG, SVG or PDF
    by the file's extension."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: PLC0415

    fig = plt.figure(figsize=(8, 6.5), dpi=120)
    ax = fig.add_subplot(projection="3d")
    polys = points[quads]
    width = float(np.clip(30.0 / np.sqrt(max(len(quads), 1)), 0.05, 0.6))
    coll = Poly3DCollection(polys, cmap="viridis", edgecolors="k", linewidths=width)
    coll.set_array(np.asarray(values))
    coll.set_clim(min(0.0, float(np.min(values))) if len(values) else 0.0, 1.0)
    ax.add_collection3d(coll)
    lo, hi = points.min(axis=0), points.max(axis=0)
    mid, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo))
    for set_lim, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), mid, strict=True):
        set_lim(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=25, azim=-60)
    cbar = fig.colorbar(coll, ax=ax, shrink=0.7)
    cbar.set_label("scaled Jacobian (Verdict)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(str(path))
    plt.close(fig)
    return Path(path)
