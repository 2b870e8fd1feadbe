"""Before/after picture of a fillet simplification: two shaded 3-D views side by side.

Faces come as triangle arrays ``(m, 3, 3)`` per face (``medax.cad.simplify.tessellate``).
Before: fillets removed in red, blends kept in black, the faces that absorb fillet halves each
in its own colour, the rest grey. After: each merged face in the colour of its supporting
face, the kept blends black, the rest grey, so both the merged faces and what stayed are
visible. Rendered off-screen with matplotlib (Agg).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

GREY = (0.78, 0.78, 0.8)
FILLET = (0.85, 0.2, 0.2)
KEPT = (0.12, 0.12, 0.12)


def _shade(tris: NDArray[np.float64], rgb: tuple[float, float, float]) -> NDArray[np.float64]:
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    light = np.array([0.4, -0.5, 0.75])
    light /= np.linalg.norm(light)
    k = 0.45 + 0.55 * np.abs(n @ light)
    return np.clip(np.outer(k, rgb), 0, 1)


def refine(tris: NDArray[np.float64], max_len: float, levels: int = 5) -> NDArray[np.float64]:
    """Split triangles (m, 3, 3) with an edge longer than ``max_len`` into 4 (repeatedly):
    matplotlib depth-sorts whole triangles, so long slivers would paint over near faces."""
    for _ in range(levels):
        edge = np.linalg.norm(tris - np.roll(tris, 1, axis=1), axis=2).max(axis=1)
        big = edge > max_len
        if not big.any():
            break
        t = tris[big]
        a, b, c = t[:, 0], t[:, 1], t[:, 2]
        ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
        parts = [np.stack(x, axis=1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
        tris = np.concatenate([tris[~big], *parts])
    return tris


def plot_before_after(
    before: Sequence[NDArray[np.float64]],
    after: Sequence[NDArray[np.float64]],
    before_colour: Sequence[int],
    after_colour: Sequence[int],
    path: str | Path,
    title: str = "",
) -> Path:
    """Write the PNG ``path``.

    ``before_colour[i]``/``after_colour[j]``: colour key of each face, ``-1`` grey, ``-2``
    fillet removed (red), ``-3`` blend kept (black), ``k >= 0`` the ``k``-th colour of the
    qualitative map (same key = same new face).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    cmap = plt.get_cmap("tab20")
    fig = plt.figure(figsize=(12, 5.5))
    allpts = np.vstack([t.reshape(-1, 3) for t in list(before) + list(after) if t.size])
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    for k, (faces, keys, label) in enumerate(
        ((before, before_colour, "before"), (after, after_colour, "after"))
    ):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        polys, colours = [], []
        for tris, key in zip(faces, keys, strict=True):
            if not tris.size:
                continue
            fixed = {-1: GREY, -2: FILLET, -3: KEPT}
            rgb = fixed[key] if key < 0 else cmap(key % 20)[:3]
            fine = refine(tris, 2 * half / 25)
            polys.append(fine)
            colours.append(_shade(fine, rgb))
        # one collection, so matplotlib depth-sorts all triangles together
        pc = Poly3DCollection(np.vstack(polys), facecolors=np.vstack(colours), edgecolors="none")
        ax.add_collection3d(pc)
        for i, c in enumerate(centre):
            getattr(ax, "set_" + "xyz"[i] + "lim")(c - half, c + half)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=28, azim=-58)
        ax.set_axis_off()
        n_kept = sum(1 for key in keys if key == -3)
        ax.set_title(
            f"{label}: {len(faces)} faces" + (f", {n_kept} blends kept (black)" if n_kept else "")
        )
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
