"""Embeddings ``x = E(p)`` of the parameter plane into space.

A planar region uses :class:`PlaneEmbedding` (the identity). A region on a CAD face uses a
parametric surface ``S(u, v)``; the CAD adapter supplies one built on numpy evaluators so
that the tracer never calls into OpenCASCADE.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from medax.geometry._types import FloatArray


@runtime_checkable
class Embedding(Protocol):
    """A smooth map from parameter points ``p`` (n, 2) to space points (n, dim)."""

    @property
    def dim(self) -> int:
        """Dimension of the space (2 for the plane, 3 for a surface)."""
        ...

    @property
    def is_identity(self) -> bool:
        """True when ``E(p) = p`` (the planar case)."""
        ...

    def evaluate(self, p: FloatArray) -> FloatArray:
        """Space points ``E(p)``, shape ``(n, dim)``."""
        ...

    def jacobian(self, p: FloatArray) -> FloatArray:
        """``dE/dp``, shape ``(n, dim, 2)``."""
        ...


class PlaneEmbedding:
    """The identity: the region lies in the plane and is measured there."""

    dim = 2
    is_identity = True

    def evaluate(self, p: FloatArray) -> FloatArray:
        return np.asarray(p, dtype=np.float64)

    def jacobian(self, p: FloatArray) -> FloatArray:
        n = np.asarray(p).shape[0]
        return np.broadcast_to(np.eye(2), (n, 2, 2)).copy()
