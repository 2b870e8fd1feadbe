"""Why a structured grid of a region stays tangled: the obstacle named for the user.

Checked on the grid that the untangling stage (:mod:`medax.mesh.untangle`) left, in order:

1. a corner whose quad cannot be convex: the angle between the first edges along its two
   sides (the chords to the first boundary nodes) is 180 degrees or more, as at a reflex
   corner (a corner's one quad has the corner's angle);
2. the boundary nodes' polygon crosses itself: chords of two sides cross (a gap narrower
   than the division counts resolve, or a side folding back along another);
3. otherwise where the inverted quads are: the side or corner they are nearest to.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve
from medax.geometry.region import Region
from medax.mesh.grid import boundary_indices, structured_quads
from medax.mesh.untangle import corner_terms


def corner_angles(region: Region) -> FloatArray:
    """Interior angles (4,) in degrees at corners 0..3 of a planar region, between the end
    tangents of the sides meeting there (above 180: reflex)."""
    out = np.empty(4)
    for k in range(4):
        back = -region.sides[k - 1].derivative(np.array([1.0]))[0]
        ahead = region.sides[k].derivative(np.array([0.0]))[0]
        cross = ahead[0] * back[1] - ahead[1] * back[0]
        out[k] = np.degrees(np.arctan2(cross, float(ahead @ back))) % 360.0
    return out


def corner_quad_angle(p: FloatArray, n1: int, n2: int, k: int) -> float:
    """Interior angle (degrees) of the grid at region corner ``k``, between the chords to
    the first boundary nodes on its two sides."""
    sides = boundary_indices(n1, n2)
    c = p[sides[k][0]]
    ahead = p[sides[k][1]] - c
    back = p[sides[k - 1][-2]] - c
    cross = ahead[0] * back[1] - ahead[1] * back[0]
    return float(np.degrees(np.arctan2(cross, float(ahead @ back))) % 360.0)


def _ccw(u: FloatArray, v: FloatArray) -> FloatArray:
    """Angles (degrees, in [0, 360)) turning counter-clockwise from ``u`` to ``v`` (..., 2)."""
    cross = u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
    return np.asarray(np.degrees(np.arctan2(cross, np.sum(u * v, axis=-1))) % 360.0)


def stuck_corner(
    p: FloatArray, n1: int, n2: int, sides: Sequence[Curve], samples: int = 64
) -> tuple[int, float] | None:
    """A corner whose quad cannot be convex however its first boundary nodes slide (each up
    to where its neighbour on the side is, its side ``sides[k]`` sampled at ``samples``
    points): ``(corner, smallest angle in degrees)``, or None."""
    rims = boundary_indices(n1, n2)
    for k in range(4):
        c = p[rims[k][0]]
        ahead_t = sides[k].closest(p[rims[k][2:3]]).t[0] if len(rims[k]) > 2 else 1.0
        back_t = sides[k - 1].closest(p[rims[k - 1][-3:-2]]).t[0] if len(rims[k - 1]) > 2 else 0.0
        s = np.linspace(0.0, 1.0, samples + 1)[1:]
        u = sides[k].evaluate(s * ahead_t) - c  # (samples, 2) to nodes on side k
        v = sides[k - 1].evaluate(1.0 - s * (1.0 - back_t)) - c  # to nodes on side k - 1
        ang = _ccw(u[:, None, :], v[None, :, :])
        smallest = float(ang.min())
        if smallest >= 180.0:
            return k, smallest
    return None


def _segments_cross(a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray) -> np.ndarray:
    """(m, k) bool: segment ``i`` of ``a`` properly crosses segment ``j`` of ``b``."""

    def orient(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (
            r[..., 0] - p[..., 0]
        )

    A0, A1 = a0[:, None], a1[:, None]
    B0, B1 = b0[None, :], b1[None, :]
    d1, d2 = orient(A0, A1, B0), orient(A0, A1, B1)
    d3, d4 = orient(B0, B1, A0), orient(B0, B1, A1)
    return np.asarray((d1 * d2 < 0.0) & (d3 * d4 < 0.0))


def crossing_sides(p: FloatArray, n1: int, n2: int) -> tuple[int, int] | None:
    """Two sides whose boundary-node chords cross (a side with itself included), or None."""
    sides = boundary_indices(n1, n2)
    chains = [p[s] for s in sides]
    for i in range(4):
        for j in range(i, 4):
            a, b = chains[i], chains[j]
            hit = _segments_cross(a[:-1], a[1:], b[:-1], b[1:])
            if i == j:
                hit = np.triu(hit, 2)
            if hit.any():
                return i, j
    return None


def obstacle(p: FloatArray, n1: int, n2: int, corner_angles: FloatArray | None = None) -> str:
    """What keeps the grid ``p`` ((n1 + 1) * (n2 + 1), 2) tangled, in words (see the module
    docstring); ``corner_angles`` (4,) the region's own corner angles (degrees, between the
    sides' tangents), quoted when given."""
    for k in range(4):
        ang = corner_quad_angle(p, n1, n2, k)
        if ang >= 180.0:
            own = ""
            if corner_angles is not None:
                own = f", between the sides' tangents {corner_angles[k]:.1f}"
            reflex = "reflex " if corner_angles is not None and corner_angles[k] >= 180 else ""
            return (
                f"{reflex}corner {k} between sides {(k - 1) % 4} and {k}: its quad has an angle "
                f"of {ang:.1f} degrees there{own} (a structured grid's corner quad takes the "
                "corner's angle)"
            )
    hit = crossing_sides(p, n1, n2)
    if hit is not None:
        i, j = hit
        what = f"side {i} folds back on itself" if i == j else f"sides {i} and {j} come too close"
        return (
            f"{what}: chords between its boundary nodes cross at {n1}x{n2} divisions (more "
            "divisions may resolve it)"
        )
    quads = structured_quads(n1, n2)
    bad = np.flatnonzero(np.any(corner_terms(p, quads)[2] <= 0.0, axis=1))
    jj, ii = np.divmod(bad, n1)
    # distance in cells to each side: S0 j, S1 n1 - 1 - i, S2 n2 - 1 - j, S3 i
    dist = np.stack((jj, n1 - 1 - ii, n2 - 1 - jj, ii))
    side = int(np.argmin(dist.min(axis=1)))
    return (
        f"{bad.size} quads stay inverted after untangling, the nearest {int(dist[side].min())} "
        f"cells from side {side} (cell {int(ii[0])},{int(jj[0])} first)"
    )


__all__ = ["corner_angles", "corner_quad_angle", "crossing_sides", "obstacle", "stuck_corner"]
