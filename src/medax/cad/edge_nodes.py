"""The nodes of a CAD edge: points at equal arc length on its exact 3-D curve.

Every face of a part mesh that touches edge ``j`` uses exactly these nodes on it, so shared
edges conform by construction. Nodes run in the direction of the edge's own parameter
(``TopAbs_FORWARD``); lengths in model units.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.TopAbs import TopAbs_FORWARD
from OCP.TopoDS import TopoDS

from medax.cad.face_region import _curve3d, _to_bspline
from medax.errors import CadError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve
from medax.mesh.arclength import arclength_params


def edge_curve(edge: Any) -> Curve:
    """The exact 3-D curve of ``edge`` as a numpy B-spline on ``[0, 1]``, in the direction
    of the edge's parameter (its orientation ignored)."""
    try:
        return _to_bspline(_curve3d(TopoDS.Edge(edge.Oriented(TopAbs_FORWARD))), 3)
    except CadError:
        raise
    except Exception as err:
        raise CadError(f"edge curve: OCCT ({err})") from err


def equal_arc_nodes(curve: Curve, n: int) -> FloatArray:
    """``n + 1`` points (n + 1, 3) dividing ``curve`` into ``n`` equal arc lengths, ends
    included (the curve's own end points, exactly)."""
    t = arclength_params(curve, np.arange(n + 1) / n)
    return np.asarray(curve.evaluate(t))
