"""gmsh's scaled Jacobian of quads, for comparison with Verdict's (:mod:`medax.mesh.quality`).

Verdict's scaled Jacobian of a linear quad is the smallest of its four corner values
``n . (L_{k-1} x L_k) / (|L_{k-1}| |L_k|)``: the sine of the corner angle. gmsh's
``minSJ`` (``gmsh.model.mesh.getElementQualities(tags, "minSJ")``) is computed by gmsh from
the Bezier coefficients of the Jacobian determinant over the whole element with its own
normalisation; it is not the same number: on the planar trapezoid (0, 0), (1, 0), (1.3, 1),
(0, 1) Verdict gives 0.958, gmsh 0.870 (both 1 on a rectangle, both <= 0 when inverted).
Reports give both.
"""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray, IntArray
from medax.mesh.gmsh_session import gmsh_session


def gmsh_scaled_jacobian(points: FloatArray, quads: IntArray) -> FloatArray:
    """gmsh's ``minSJ`` (m,) of ``quads`` (m, 4) over ``points`` (n, 2|3)."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.shape[1] == 2:
        pts = np.column_stack((pts, np.zeros(len(pts))))
    q = np.asarray(quads, dtype=np.int64)
    if len(q) == 0:
        return np.zeros(0)
    with gmsh_session() as gmsh:
        gmsh.model.add("medax-quality")
        try:
            gmsh.model.addDiscreteEntity(2, 1)
            gmsh.model.mesh.addNodes(
                2, 1, np.arange(1, len(pts) + 1).tolist(), pts.ravel().tolist()
            )
            tags = np.arange(1, len(q) + 1)
            gmsh.model.mesh.addElementsByType(1, 3, tags.tolist(), (q + 1).ravel().tolist())
            out = gmsh.model.mesh.getElementQualities(tags.tolist(), "minSJ")
        finally:
            gmsh.model.remove()
    return np.asarray(out, dtype=np.float64)
