"""The nodes a part mesh puts on its CAD edges and vertices, built once per meshing round and
shared by every face that touches them (:mod:`medax.cad.part_mesh`,
:mod:`medax.cad.gmsh_faces`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from medax.geometry._types import FloatArray, IntArray


@dataclass(frozen=True)
class SharedNodes:
    """The part's nodes on its edges and vertices (lengths in model units).

    ``edge_ids[j]`` (n + 1,) and ``edge_pts[j]`` (n + 1, 3): node ids and points along edge
    ``j`` in the direction of its parameter, end nodes the vertex nodes (:mod:`medax.cad.
    edge_nodes`); ``edge_mid[j]`` (3,): the point at the middle of its curve's parameter;
    ``vert_ids`` (v,) and ``vert_pts`` (v, 3): the node of each vertex of the part (-1 and
    zeros for vertices no meshed edge uses); ``owner`` (k,) and ``where`` (k,), for each of
    these k nodes: the edge it lies inside and its position on that edge, or -1 and the
    vertex index; ``size`` the target edge length; ``tol`` the distance below which points
    are the same point.
    """

    edge_ids: Mapping[int, IntArray]
    edge_pts: Mapping[int, FloatArray]
    edge_mid: Mapping[int, FloatArray]
    vert_ids: IntArray
    vert_pts: FloatArray
    owner: IntArray
    where: IntArray
    size: float
    tol: float
