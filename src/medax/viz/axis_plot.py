"""Plot of a region, its medial axes and a few of the equal-distance circles defining them."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from medax.axis.result import MedialAxis
from medax.geometry.region import Region
from medax.viz.view3d import new_figure, save

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_SIDE_COLOURS = ("#1f77b4", "#2ca02c", "#1f77b4", "#2ca02c")
_AXIS_COLOURS = ("#d62728", "#9467bd")


def plot_axes(
    region: Region,
    axes: Sequence[MedialAxis],
    path: str | Path | None = None,
    circles: int = 5,
    ax: Axes | None = None,
) -> Figure:
    """Plot a region with its medial axes and equal-distance circles.

    The sides are labelled S0..S3, each axis drawn as its fitted B-spline with its points;
    each circle has its centre on the axis and radius ``d1 = d2``, touching both constraints.

    Parameters
    ----------
    region : Region
        The region ([Region][medax.geometry.region.Region]), drawn in the parameter plane.
    axes : sequence of MedialAxis
        Its axes ([MedialAxis][medax.axis.result.MedialAxis]).
    path : str or Path, optional
        Write the figure there (PNG, SVG or PDF by the extension).
    circles : int
        Equal-distance circles per axis.
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).

    Returns
    -------
    Figure
        The figure drawn into.
    """
    from matplotlib.patches import Circle

    if ax is None:
        ax = new_figure((7, 7), 110).add_subplot()
    fig: Figure = ax.figure  # type: ignore[assignment]
    for k, side in enumerate(region.sides):
        pts = side.sample(400)
        ax.plot(pts[:, 0], pts[:, 1], color=_SIDE_COLOURS[k], lw=2)
        mid = pts[len(pts) // 2]
        ax.annotate(f"S{k}", mid, color=_SIDE_COLOURS[k], fontsize=11, weight="bold")
    for j, axis in enumerate(axes):
        colour = _AXIS_COLOURS[j % 2]
        curve = axis.spline.sample(2000)
        rel = axis.max_curve_error / axis.diagonal
        label = f"axis {axis.pair} ({axis.method}), {axis.n_points} pts, err {rel:.1e}"
        ax.plot(curve[:, 0], curve[:, 1], color=colour, lw=1.6, label=label)
        ax.plot(axis.points[:, 0], axis.points[:, 1], ".", color=colour, ms=3)
        idx = np.linspace(0, axis.n_points - 1, circles + 2).round().astype(int)[1:-1]
        for i in idx:
            c = Circle(
                axis.points[i], axis.d1[i], fill=False, ls="--", lw=0.8, color=colour, alpha=0.7
            )
            ax.add_patch(c)
            for foot in (axis.foot1[i], axis.foot2[i]):
                ax.plot(
                    *np.column_stack((axis.points[i], foot[:2])), color=colour, lw=0.5, alpha=0.7
                )
    ax.set_aspect("equal")
    ax.set_title(f"medax: medial axes of '{region.name}'")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.06), fontsize=8, frameon=False)
    ax.grid(alpha=0.2)
    save(fig, path, bbox_inches="tight")
    return fig
