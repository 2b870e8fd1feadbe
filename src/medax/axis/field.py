"""The distance field of a constraint pair: ``g(p) = (1 - r) d1 - r d2`` and its gradient.

``d1``, ``d2`` are distances in space from ``E(p)`` to the constraints ``A1``, ``A2``; the
axis is ``g = 0`` with ``r = 1/2`` (then ``g = (d1 - d2) / 2``). Other ratios give the curves
``d1 / (d1 + d2) = r`` used by the mesher.
"""

from __future__ import annotations

import numpy as np

from medax.geometry._rows import points2d
from medax.geometry._types import FloatArray
from medax.geometry.curve import Closest, Curve, closest_near
from medax.geometry.pair_search import PairSearch
from medax.geometry.region import PairRoles, Region


class FieldSample:
    """The field at ``n`` parameter points, its columns packed in one array ``data``
    (n, 3 dim + 7) so that taking or joining rows is one operation.

    ``x`` (n, dim) space points; ``d1``, ``d2`` (n,) distances; ``q1``, ``q2`` (n, dim) foot
    points; ``t1``, ``t2`` (n,) foot parameters on A1, A2; ``g`` (n,) field value;
    ``grad`` (n, 2) gradient of ``g`` in the parameter plane (views of ``data``).
    """

    __slots__ = ("data", "dim")

    def __init__(self, data: FloatArray, dim: int) -> None:
        self.data = data
        self.dim = dim

    @property
    def x(self) -> FloatArray:
        return self.data[:, : self.dim]

    @property
    def q1(self) -> FloatArray:
        return self.data[:, self.dim : 2 * self.dim]

    @property
    def q2(self) -> FloatArray:
        return self.data[:, 2 * self.dim : 3 * self.dim]

    @property
    def d1(self) -> FloatArray:
        return self.data[:, 3 * self.dim]

    @property
    def d2(self) -> FloatArray:
        return self.data[:, 3 * self.dim + 1]

    @property
    def t1(self) -> FloatArray:
        return self.data[:, 3 * self.dim + 2]

    @property
    def t2(self) -> FloatArray:
        return self.data[:, 3 * self.dim + 3]

    @property
    def g(self) -> FloatArray:
        return self.data[:, 3 * self.dim + 4]

    @property
    def grad(self) -> FloatArray:
        return self.data[:, 3 * self.dim + 5 :]

    def __len__(self) -> int:
        return len(self.data)

    def take(self, idx: np.ndarray) -> FieldSample:
        """The sample at rows ``idx`` (k,) (indices or a mask)."""
        return FieldSample(self.data[idx], self.dim)

    @staticmethod
    def empty(dim: int) -> FieldSample:
        """No rows (points in ``dim`` dimensions)."""
        return FieldSample(np.zeros((0, 3 * dim + 7)), dim)

    @staticmethod
    def concat(samples: list[FieldSample]) -> FieldSample:
        """The samples' rows one after the other."""
        return FieldSample(np.concatenate([s.data for s in samples]), samples[0].dim)

    @property
    def error(self) -> FloatArray:
        """Equidistance error ``2 |g|``: exactly ``|d1 - d2|`` on the axis (r = 1/2)."""
        return np.abs(self.g) * 2.0


_TINY = np.finfo(float).tiny


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
        p = points2d(p)
        emb = self.region.embedding
        x = emb.evaluate(p)
        self.evaluations += p.shape[0]
        if self._pair is False:
            self._pair = PairSearch.build(self.a1, self.a2)
        pair = self._pair
        n, dim = x.shape
        data = np.empty((n, 3 * dim + 7))
        c = 3 * dim
        data[:, :dim] = x
        if isinstance(pair, PairSearch):  # both feet from one kernel call, packed at once
            t, foot, dist = pair.search.closest(x)  # (n, 2), (n, 2, dim), (n, 2)
            data[:, dim:c] = foot.reshape(n, 2 * dim)
            data[:, c : c + 2] = dist
            data[:, c + 2 : c + 4] = t
        else:
            c1, c2 = self.a1.closest(x), self.a2.closest(x)
            data[:, dim : 2 * dim], data[:, 2 * dim : c] = c1.foot, c2.foot
            data[:, c], data[:, c + 1], data[:, c + 2], data[:, c + 3] = (
                c1.distance, c2.distance, c1.t, c2.t,
            )  # fmt: skip
            dist = data[:, c : c + 2]
        # unit vectors from the feet, both at once: (x - q) / max(d, tiny)
        feet = data[:, dim:c].reshape(n, 2, dim)
        u = (x[:, None, :] - feet) / np.maximum(dist, _TINY)[:, :, None]
        r = self.ratio
        gx = (1.0 - r) * u[:, 0] - r * u[:, 1]
        data[:, c + 4] = (1.0 - r) * dist[:, 0] - r * dist[:, 1]
        data[:, c + 5 :] = gx if emb.is_identity else np.einsum("nij,ni->nj", emb.jacobian(p), gx)
        return FieldSample(data, dim)
