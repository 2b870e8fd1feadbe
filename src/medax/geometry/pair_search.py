"""Global closest points on two polynomial B-splines at once (the two constraints of a
distance field), one query's worth of numpy calls instead of two.

The algorithm is that of :func:`medax.geometry.curve.closest_by_search` (the ``k`` best local
minima of the sampled distance per curve, each refined in the bracket of its neighbouring
samples); the two curves' search samples, slopes and polynomial pieces are stacked, curve 2
shifted to the parameter range ``[2, 3]``, so that one table pass, one start and one Newton
iteration serve both. Small batches cost numpy call overhead, not flops: the axis tracer's
field queries are mostly 1 - 100 points.
"""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.bspline import POWER_BASIS_MAX_DEGREE, BSpline
from medax.geometry.curve import (
    Closest,
    Curve,
    _bracketed_newton,
    _quick_newton,
    _start,
    at_breaks,
    sign_brackets,
)

#: parameter offset of the second curve in the stacked tables
SHIFT = 2.0
#: batches whose distance table (points x samples) is larger than this use two queries
#: (blocked to stay in cache: faster for a few hundred points and more)
MAX_TABLE = 40_000


class _Pieces:
    """The stacked polynomial pieces, evaluated like :meth:`BSpline.jet` (duck-typed as a
    curve for the Newton iteration)."""

    def __init__(self, starts: FloatArray, coefs: FloatArray) -> None:
        self.starts, self.coefs = starts, coefs
        self.powers = np.arange(coefs.shape[1] - 1, -1, -1, dtype=np.float64)

    def jet(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Value, first and second derivative (each (n, dim)) at stacked parameters (n,)."""
        i = np.searchsorted(self.starts, t, side="right") - 1
        s = np.power.outer(t - self.starts[i], self.powers)  # (n, degree + 1)
        w = np.einsum("nk,nkqd->nqd", s, self.coefs[i])
        return w[:, 0], w[:, 1], w[:, 2]


class PairSearch:
    """Closest points on ``c1`` and ``c2`` (planar or spatial, same dimension) for the same
    points; :meth:`build` returns ``None`` where the stacking does not apply."""

    def __init__(self, c1: BSpline, c2: BSpline, k: int = 2) -> None:
        (t1, p1), (t2, p2) = c1._search, c2._search
        self.k, self.m1, self.m = k, t1.size, t1.size + t2.size
        self.ts = np.concatenate((t1, t2 + SHIFT))
        self.breaks = np.concatenate((c1.breaks(), c2.breaks() + SHIFT))  # C0 corners
        self.pts = np.concatenate((p1, p2))
        self.slopes = np.concatenate((c1._slopes, c2._slopes))
        self.centre = self.pts.mean(axis=0)
        self.cpts = self.pts - self.centre
        self.pp = np.einsum("mj,mj->m", self.cpts, self.cpts)
        deg = max(c1.degree, c2.degree)
        starts, coefs = [], []
        for shift, c in ((0.0, c1), (SHIFT, c2)):
            x, cf = c._pieces  # (spans, degree + 1, 3, dim), highest power first
            pad = np.zeros((cf.shape[0], deg - c.degree, *cf.shape[2:]))
            starts.append(x[:-1] + shift)
            coefs.append(np.concatenate((pad, cf), axis=1))
        self.pieces = _Pieces(np.concatenate(starts), np.concatenate(coefs))
        # the three-sample window of each sample (m, 3), kept on its own curve
        j = np.arange(self.m)
        lo = np.where(j < self.m1, 0, self.m1)[:, None]
        hi = np.where(j < self.m1, self.m1 - 1, self.m - 1)[:, None]
        self.window = np.minimum(np.maximum(j[:, None] + np.arange(-1, 2), lo), hi)

    @staticmethod
    def build(c1: Curve, c2: Curve) -> PairSearch | None:
        """The pair search of two non-rational B-splines evaluated by their power basis in
        the same space, else ``None``."""
        ok = all(
            isinstance(c, BSpline)
            and c.weights is None
            and c.degree <= POWER_BASIS_MAX_DEGREE
            and type(c).closest is Curve.closest
            for c in (c1, c2)
        )
        if not ok or c1.dim != c2.dim:
            return None
        return PairSearch(c1, c2)  # type: ignore[arg-type]

    def fits(self, n: int) -> bool:
        """Whether a batch of ``n`` points is small enough for one stacked table."""
        return n * self.m <= MAX_TABLE

    def closest(self, points: FloatArray) -> tuple[Closest, Closest]:
        """Global closest points (n, dim) on curve 1 and on curve 2."""
        x0 = np.asarray(points, dtype=np.float64)
        n, k = x0.shape[0], self.k
        cand = self._candidates(x0).ravel()  # (n * 2k,): k on curve 1, then k on curve 2
        x = np.repeat(x0, 2 * k, axis=0)
        j3 = self.window[cand]  # (n * 2k, 3)
        g, d2, ia, ga, gb, interior = sign_brackets(self.pts, self.slopes, j3, x)
        jb = j3[np.arange(x.shape[0]), np.argmin(d2, axis=1)]
        t, foot = self.ts[jb], self.pts[jb]
        if np.any(interior):
            ta, tb = self.ts[ia[interior]], self.ts[ia[interior] + 1]
            s0 = _start(self.ts[j3[interior]], g[interior], ta, tb, ga[interior], gb[interior])
            t[interior], foot[interior] = _quick_newton(
                self.pieces,  # type: ignore[arg-type]
                x[interior], ta, tb, s0,
            )  # fmt: skip
        at_breaks(self.pieces, self.breaks, x, self.ts[j3[:, 0]], self.ts[j3[:, 2]], t, foot)
        dist = np.linalg.norm(foot - x, axis=1).reshape(n, 2, k)
        pick = np.argmin(dist, axis=2)  # (n, 2)
        r = np.arange(n)
        t, foot = t.reshape(n, 2, k), foot.reshape(n, 2, k, -1)
        out = []
        for j, shift in ((0, 0.0), (1, SHIFT)):
            pj = pick[:, j]
            tj = t[r, j, pj] - shift
            out.append(Closest(t=tj, foot=foot[r, j, pj], distance=dist[r, j, pj]))
        return out[0], out[1]

    def closest_near(
        self, on2: np.ndarray, points: FloatArray, t0: FloatArray, width: float
    ) -> Closest:
        """Local closest points as :func:`medax.geometry.curve.closest_near`, all rows in
        one bracketed Newton: row ``i`` on curve 2 where ``on2[i]`` (bool (n,)), else on
        curve 1, its parameter in ``[t0 - width, t0 + width]`` clipped to ``[0, 1]``.
        Parameters (n,), foot points (n, dim) and distances (n,)."""
        x = np.asarray(points, dtype=np.float64)
        t0 = np.asarray(t0, dtype=np.float64)
        shift = np.where(on2, SHIFT, 0.0)
        lo = np.minimum(np.maximum(t0 - width, 0.0), 1.0) + shift
        hi = np.minimum(np.maximum(t0 + width, 0.0), 1.0) + shift
        start = np.minimum(np.maximum(t0, 0.0), 1.0) + shift
        t, foot = _bracketed_newton(self.pieces, x, lo, hi, start=start)  # type: ignore[arg-type]
        return Closest(t=t - shift, foot=foot, distance=np.linalg.norm(foot - x, axis=1))

    def _candidates(self, points: FloatArray) -> np.ndarray:
        """Indices (n, 2, k) into the stacked samples: the ``k`` nearest local minima of the
        sample distance on each curve (rows with fewer repeat their best one)."""
        x = points - self.centre
        d2 = self.pp[None, :] - 2.0 * (x @ self.cpts.T)
        m1 = self.m1
        is_min = np.ones(d2.shape, dtype=bool)
        is_min[:, 1:] &= d2[:, 1:] <= d2[:, :-1]
        is_min[:, :-1] &= d2[:, :-1] <= d2[:, 1:]
        # the two curves' blocks are not neighbours: their end samples compare inward only
        is_min[:, m1 - 1] = d2[:, m1 - 1] <= d2[:, m1 - 2]
        is_min[:, m1] = d2[:, m1] <= d2[:, m1 + 1]
        score = np.where(is_min, d2, np.inf)
        k = self.k
        # the k smallest scores of each block, in any order (one call; where a block has
        # fewer than k local minima the extras are other samples: refined like the others,
        # they are never nearer than the best local minimum, which is always among them)
        out = np.empty((x.shape[0], 2, k), dtype=np.int64)
        out[:, 0] = np.argpartition(score[:, :m1], k - 1, axis=1)[:, :k]
        out[:, 1] = np.argpartition(score[:, m1:], k - 1, axis=1)[:, :k] + m1
        return out
