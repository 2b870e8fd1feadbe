"""The structured grid: node numbering, quads, and the mesh result.

Node ``(i, j)`` (``i = 0..n1`` along side S0 from corner 0 to corner 1, ``j = 0..n2`` along
side S1 from corner 1 to corner 2) has index ``j * (n1 + 1) + i``. Node rows ``j = 0`` and
``j = n2`` lie on S0 and on S2 (reversed), columns ``i = 0`` and ``i = n1`` on S3 (reversed)
and on S1. Quads are ``(i, j), (i+1, j), (i+1, j+1), (i, j+1)``: counter-clockwise because the
region's sides are.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from medax.geometry._types import FloatArray, IntArray
from medax.geometry.region import Region
from medax.mesh.quality import QuadQuality, quad_quality


def structured_quads(n1: int, n2: int) -> IntArray:
    """Build the quads of an ``(n1 + 1) x (n2 + 1)`` node grid, row by row.

    Parameters
    ----------
    n1, n2 : int
        Divisions along S0 and along S1.

    Returns
    -------
    ndarray
        Node indices (n1 * n2, 4), counter-clockwise for a counter-clockwise region.
    """
    i, j = np.meshgrid(np.arange(n1, dtype=np.int64), np.arange(n2, dtype=np.int64))
    a = (j * (n1 + 1) + i).ravel()
    return np.column_stack((a, a + 1, a + n1 + 2, a + n1 + 1))


def boundary_indices(n1: int, n2: int) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """Give the node indices on the four sides of an ``(n1 + 1) x (n2 + 1)`` node grid.

    Parameters
    ----------
    n1, n2 : int
        Divisions along S0 and along S1.

    Returns
    -------
    tuple of 4 ndarray
        Node indices on S0, S1, S2, S3 ((n1 + 1,) or (n2 + 1,)), each in the side's own
        direction (corner k first).
    """
    row = n1 + 1
    s0 = np.arange(row, dtype=np.int64)
    s1 = n1 + row * np.arange(n2 + 1, dtype=np.int64)
    s2 = (n2 * row + np.arange(row, dtype=np.int64))[::-1]
    s3 = (row * np.arange(n2 + 1, dtype=np.int64))[::-1]
    return s0, s1, s2, s3


def transfinite_grid(params: FloatArray, n1: int, n2: int) -> FloatArray:
    """Fill a grid's interior with the transfinite (Coons) patch of its boundary nodes.

    The patch blends linearly in ``i / n1`` and ``j / n2`` (the boundary nodes divide their
    sides into equal arc lengths); boundary nodes are kept exactly.

    Parameters
    ----------
    params : ndarray
        Nodes ((n1 + 1) * (n2 + 1), 2), node ``(i, j)`` at row ``j * (n1 + 1) + i``; only
        the boundary nodes are read.
    n1, n2 : int
        Divisions along S0 and along S1.

    Returns
    -------
    ndarray
        The patch, same shape as ``params`` (a new array).
    """
    g = params.reshape(n2 + 1, n1 + 1, -1)
    u = (np.arange(n1 + 1) / n1)[None, :, None]
    v = (np.arange(n2 + 1) / n2)[:, None, None]
    c00, c10, c01, c11 = g[0, 0], g[0, -1], g[-1, 0], g[-1, -1]
    out = (1 - v) * g[:1] + v * g[-1:] + (1 - u) * g[:, :1] + u * g[:, -1:]
    out -= (1 - u) * (1 - v) * c00 + u * (1 - v) * c10 + (1 - u) * v * c01 + u * v * c11
    out[0], out[-1], out[:, 0], out[:, -1] = g[0], g[-1], g[:, 0], g[:, -1]  # exact rims
    return out.reshape(params.shape)


@dataclass(frozen=True)
class QuadMesh:
    """A structured quad mesh of a 4-sided region.

    Node numbering and quads as in [medax.mesh.grid][medax.mesh.grid].

    Attributes
    ----------
    region : Region
        The region meshed ([Region][medax.geometry.region.Region]).
    params : ndarray
        Nodes (n, 2) in the parameter plane.
    points : ndarray
        Nodes (n, dim) in space (equal to ``params`` for a planar region).
    n1, n2 : int
        Divisions along S0 and along S1.
    method : str
        How it was built (``"ratio"``, ``"angle"``, ``"paper"``).
    info : dict
        Counts and timings (JSON-ready).
    """

    region: Region
    params: FloatArray
    points: FloatArray
    n1: int
    n2: int
    method: str
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def quads(self) -> IntArray:
        """Node indices (n1 * n2, 4), counter-clockwise."""
        return structured_quads(self.n1, self.n2)

    @property
    def n_nodes(self) -> int:
        """Number of nodes, ``(n1 + 1) * (n2 + 1)``."""
        return int(self.points.shape[0])

    @property
    def n_quads(self) -> int:
        """Number of quads, ``n1 * n2``."""
        return self.n1 * self.n2

    def __repr__(self) -> str:
        return (
            f"QuadMesh(region {self.region.name!r}, {self.n1}x{self.n2} quads ({self.method}), "
            f"{self.n_nodes} nodes)"
        )

    def grid(self) -> FloatArray:
        """Space nodes as a grid ``(n2 + 1, n1 + 1, dim)``."""
        return self.points.reshape(self.n2 + 1, self.n1 + 1, -1)

    def quality(self) -> QuadQuality:
        """Verdict metrics of the quads, measured in space
        ([QuadQuality][medax.mesh.quality.QuadQuality])."""
        return quad_quality(self.points, self.quads)
