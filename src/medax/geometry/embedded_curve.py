"""A parameter-plane curve seen in space through an embedding: ``C(t) = E(c(t))``."""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve
from medax.geometry.embedding import Embedding

#: relative step of the central difference used for the second derivative
_FD_STEP = 1e-5


class EmbeddedCurve(Curve):
    """``E(c(t))`` for a 2-D curve ``c`` and an embedding ``E``.

    The first derivative is exact (chain rule ``J c'``); the second, used only as the
    Newton slope in closest-point queries, is a central difference of the first.
    """

    def __init__(self, curve: Curve, embedding: Embedding) -> None:
        self.curve = curve
        self.embedding = embedding

    @property
    def dim(self) -> int:
        return self.embedding.dim

    def breaks(self) -> FloatArray:
        return self.curve.breaks()

    def complexity(self) -> int:
        return max(4, self.curve.complexity())

    def evaluate(self, t: FloatArray) -> FloatArray:
        return self.embedding.evaluate(self.curve.evaluate(t))

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        t = np.asarray(t, dtype=np.float64)
        if order == 1:
            jac = self.embedding.jacobian(self.curve.evaluate(t))
            return np.einsum("nij,nj->ni", jac, self.curve.derivative(t))
        h = _FD_STEP
        tp, tm = np.minimum(t + h, 1.0), np.maximum(t - h, 0.0)
        return (self.derivative(tp) - self.derivative(tm)) / (tp - tm)[:, None]

    def reversed(self) -> EmbeddedCurve:
        return EmbeddedCurve(self.curve.reversed(), self.embedding)
