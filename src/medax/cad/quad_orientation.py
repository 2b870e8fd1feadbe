"""Quads of a CAD face turned to its outward normal, and refused when a corner turns the
other way.

The outward normal at each node comes from the face's surface at the node's OCCT parameters
(reversed with a ``TopAbs_REVERSED`` face); the quads of a face are reversed as a whole when
their corners mostly turn against it (``sum n . (L_{k-1} x L_k) < 0``), then every corner
must turn along it (``n_k . (L_{k-1} x L_k) > 0``): a zero or negative corner is a flat or
inverted quad.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.TopAbs import TopAbs_REVERSED

from medax.cad.face_region import exact_embedding
from medax.cad.topology import face_normals
from medax.errors import CadError, MeshError
from medax.geometry._types import FloatArray, IntArray
from medax.geometry.embedding import Embedding


def oriented(
    face: Any, i: int, q: IntArray, uv: FloatArray, pts: FloatArray, emb: Embedding | None = None
) -> IntArray:
    """``q`` turned counter-clockwise about the face's outward normal; :class:`MeshError`
    if a quad corner still turns the other way or is flat (an inverted quad). ``emb``: the
    face's surface in OCCT's parameters when the caller has it (see :func:`outward_normals`)."""
    q, problem = orient(face, q, uv, pts, emb)
    if problem is not None:
        raise MeshError(f"face {i}: {problem}")
    return q


def orient(
    face: Any, q: IntArray, uv: FloatArray, pts: FloatArray, emb: Embedding | None = None
) -> tuple[IntArray, str | None]:
    """``q`` turned to the outward normal, and what is wrong with it (or None)."""
    normal = outward_normals(face, uv, emb)
    area = corner_areas(pts, q, normal)
    if np.nansum(area) < 0.0:
        q = q[:, ::-1]
        area = corner_areas(pts, q, normal)
    bad = np.flatnonzero(np.any(area <= 0.0, axis=1))
    if bad.size:
        at = np.round(pts[q[bad[0]]].mean(axis=0), 6).tolist()
        return q, f"{bad.size} quads inverted or flat against the face normal (first at {at})"
    return q, None


def outward_normals(face: Any, uv: FloatArray, emb: Embedding | None = None) -> FloatArray:
    """Outward unit normals (n, 3) at OCCT parameters ``uv`` (n, 2): from the numpy copy of
    the surface in OCCT's parameters (``emb``, else
    :func:`~medax.cad.face_region.exact_embedding`) where there is one, else from OCCT point
    by point."""
    if emb is None:
        try:
            emb = exact_embedding(face)
        except CadError:
            return face_normals(face, uv)
    normal = np.asarray(emb.normal(uv)) if hasattr(emb, "normal") else np.zeros((len(uv), 3))
    return -normal if face.Orientation() == TopAbs_REVERSED else normal


def corner_areas(pts: FloatArray, q: IntArray, normal: FloatArray) -> FloatArray:
    """``n_k . (L_{k-1} x L_k)`` (m, 4) at each quad corner, NaN where the normal is."""
    p = pts[q]
    e = np.roll(p, -1, axis=1) - p
    c = np.cross(np.roll(e, 1, axis=1), e)
    return np.asarray(np.einsum("mkd,mkd->mk", c, normal[q]))
