"""The distance field of a constraint pair: ``g(p) = (1 - r) d1 - r d2`` and its gradient.

``d1``, ``d2`` are distances in space from ``E(p)`` to the constraints ``A1``, ``A2``; the
axis is ``g = 0`` with ``r = 1/2`` (then ``g = (d1 - d2) / 2``). Other ratios give the curves
``d1 / (d1 + d2) = r`` used by the mesher.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, Curve, closest_near
from medax.geometry.pair_search import PairSearch
from medax.geometry.region import PairRoles, Region


@dataclass(frozen=True)
class FieldSample:
    """The field at ``n`` parameter points.

    ``x`` (n, dim) space points; ``d1``, ``d2`` (n,) distances; ``q1``, ``q2`` (n, dim) foot
    points; ``t1``, ``t2`` (n,) foot parameters on A1, A2; ``g`` (n,) field value;
    ``grad`` (n, 2) gradient of ``g`` in the parameter plane.
    """

    x: FloatArray
    d1: FloatArray
    d2: FloatArray
    q1: FloatArray
    q2: FloatArray
    t1: FloatArray
    t2: FloatArray
    g: FloatArray
    grad: FloatArray

    def take(self, idx: np.ndarray) -> FieldSample:
        """The sample at rows ``idx`` (k,) (indices or a mask)."""
        return FieldSample(*(getattr(self, f)[idx] for f in _FIELDS))

    @staticmethod
    def empty(dim: int) -> FieldSample:
        """No rows (points in ``dim`` dimensions)."""
        v, s = np.zeros((0, dim)), np.zeros(0)
        return FieldSample(v, s, s, v, v, s, s, s, np.zeros((0, 2)))

    @staticmethod
    def concat(samples: list[FieldSample]) -> FieldSample:
        """The samples' rows one after the other."""
        return FieldSample(*(np.concatenate([getattr(s, f) for s in samples]) for f in _FIELDS))

    @property
    def error(self) -> FloatArray:
        """Equidistance error ``2 |g|``: exactly ``|d1 - d2|`` on the axis (r = 1/2)."""
        return np.abs(self.g) * 2.0


_FIELDS = ("x", "d1", "d2", "q1", "q2", "t1", "t2", "g", "grad")


class DistanceField:
    """Evaluates ``g`` for one region, one pair and one ratio; counts evaluations."""

    def __init__(self, region: Region, roles: PairRoles, ratio: float = 0.5) -> None:
        self.region = region
        self.roles = roles
        self.ratio = float(ratio)
        self.a1: Curve = region.space_curve(roles.a1)
        self.a2: Curve = region.space_curve(roles.a2)
        self.evaluations = 0
        self._pair: PairSearch | None | bool = False  # built on first use

    def closest(self, x: FloatArray) -> tuple[Closest, Closest]:
        """Global closest points on A1 and A2 for space points ``x`` (n, dim); two B-spline
        constraints are searched together (:class:`PairSearch`: one compiled call)."""
        if self._pair is False:
            self._pair = PairSearch.build(self.a1, self.a2)
        pair = self._pair
        if isinstance(pair, PairSearch):
            return pair.closest(x)
        return self.a1.closest(x), self.a2.closest(x)

    def closest_near(self, on2: np.ndarray, x: FloatArray, t0: FloatArray, width: float) -> Closest:
        """Local (branch-restricted) closest points for space points ``x`` (n, dim): row
        ``i`` on A2 where ``on2[i]`` (bool (n,)), else on A1, with its parameter within
        ``width`` of ``t0[i]`` (:func:`medax.geometry.curve.closest_near`); two B-spline
        constraints in one bracketed Newton (:meth:`PairSearch.closest_near`)."""
        if self._pair is False:
            self._pair = PairSearch.build(self.a1, self.a2)
        pair = self._pair
        if isinstance(pair, PairSearch):
            return pair.closest_near(on2, x, t0, width)
        t, foot, dist = np.empty(len(x)), np.empty_like(x), np.empty(len(x))
        for curve, rows in ((self.a1, np.flatnonzero(~on2)), (self.a2, np.flatnonzero(on2))):
            if rows.size:
                c = closest_near(curve, x[rows], t0[rows], width)
                t[rows], foot[rows], dist[rows] = c.t, c.foot, c.distance
        return Closest(t=t, foot=foot, distance=dist)

    def __call__(self, p: FloatArray) -> FieldSample:
        """The field at parameter points ``p`` of shape ``(n, 2)``."""
        p = np.atleast_2d(np.asarray(p, dtype=np.float64))
        emb = self.region.embedding
        x = emb.evaluate(p)
        c1, c2 = self.closest(x)
        self.evaluations += p.shape[0]
        d1, d2 = c1.distance, c2.distance
        tiny = np.finfo(float).tiny
        u1 = (x - c1.foot) / np.maximum(d1, tiny)[:, None]
        u2 = (x - c2.foot) / np.maximum(d2, tiny)[:, None]
        r = self.ratio
        gx = (1.0 - r) * u1 - r * u2
        grad = gx if emb.is_identity else np.einsum("nij,ni->nj", emb.jacobian(p), gx)
        g = (1.0 - r) * d1 - r * d2
        return FieldSample(
            x=x, d1=d1, d2=d2, q1=c1.foot, q2=c2.foot, t1=c1.t, t2=c2.t, g=g, grad=grad
        )
