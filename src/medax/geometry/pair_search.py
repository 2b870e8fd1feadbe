"""Global and local closest points on polynomial B-splines by the compiled kernels
(:mod:`medax.geometry.kernels`), one kernel call per query.

:class:`PolySearch` stacks the search samples, slopes, polynomial pieces and C0 corners of
one or more non-rational B-splines of degree at most
:data:`~medax.geometry.bspline.POWER_BASIS_MAX_DEGREE` (curve ``j`` at parameter offset
``2 j`` in the span search); the algorithm is that of
:func:`medax.geometry.curve.closest_by_search` (the ``k`` best local minima of the sampled
distance per curve, each refined in the bracket of its neighbouring samples).
:class:`PairSearch` serves the two constraints of a distance field with one call: the axis
tracer's field queries are mostly 1 - 100 points, where numpy's time was per-call overhead.
"""

from __future__ import annotations

import numpy as np

from medax.errors import CurveError
from medax.geometry import kernels
from medax.geometry._rows import row_norms
from medax.geometry._types import FloatArray
from medax.geometry.bspline import POWER_BASIS_MAX_DEGREE, BSpline
from medax.geometry.curve import Closest, Curve

#: parameter offset of the second curve in the stacked tables
SHIFT = 2.0


class PolySearch:
    """The stacked search tables of ``curves`` (non-rational, power basis: see
    :meth:`BSpline.stacked_rows`) for :func:`kernels.closest_search` and
    :func:`kernels.closest_bracketed`."""

    def __init__(self, curves: list[BSpline], k: int = 2) -> None:
        table = BSpline.stacked_rows(curves)
        if table is None:
            raise CurveError(
                "compiled search tables need non-rational B-splines of degree at most "
                f"{POWER_BASIS_MAX_DEGREE}"
            )
        self.k, self.n_curves, self.dim = k, len(curves), curves[0].dim
        self.inner, self.starts, self.rows = table
        self.ts = np.concatenate([c._search[0] for c in curves])
        self.pts = np.ascontiguousarray(np.concatenate([c._search[1] for c in curves]))
        self.slopes = np.ascontiguousarray(np.concatenate([c._slopes for c in curves]))
        sizes = [c._search[0].size for c in curves]
        self.bounds = np.concatenate(([0], np.cumsum(sizes))).astype(np.int64)
        self.centre = self.pts.mean(axis=0)
        cpts = self.pts - self.centre
        self.ct = np.ascontiguousarray(cpts.T)  # (dim, m)
        self.pp = np.einsum("mj,mj->m", cpts, cpts)
        brs = [np.asarray(c.breaks(), dtype=np.float64) for c in curves]
        self.breaks = np.concatenate(brs) if brs else np.zeros(0)
        self.break_bounds = np.concatenate(([0], np.cumsum([b.size for b in brs]))).astype(np.int64)

    def closest(self, points: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Global closest points of ``points`` (n, dim) on every curve: parameters
        (n, curves), foot points (n, curves, dim), distances (n, curves)."""
        x = np.ascontiguousarray(points, dtype=np.float64)
        return kernels.closest_search(  # type: ignore[no-any-return]
            self.ts, self.pts, self.slopes, self.centre, self.ct, self.pp, self.bounds,
            self.inner, self.starts, self.rows, self.breaks, self.break_bounds, x, self.k,
        )  # fmt: skip

    def closest_in(
        self, curve: np.ndarray, points: FloatArray, lo: FloatArray, hi: FloatArray,
        start: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray]:  # fmt: skip
        """The nearest point to ``points[i]`` (n, dim) on curve ``curve[i]`` (n,; int) with
        parameter in ``[lo[i], hi[i]]`` (n,), bracketed Newton from ``start`` (n,; default:
        regula falsi): parameters (n,) and foot points (n, dim)."""
        x = np.ascontiguousarray(points, dtype=np.float64)
        lo = np.ascontiguousarray(lo, dtype=np.float64)
        hi = np.ascontiguousarray(hi, dtype=np.float64)
        s = np.full(lo.size, np.nan) if start is None else np.asarray(start, dtype=np.float64)
        c = np.ascontiguousarray(curve, dtype=np.int64)
        return kernels.closest_bracketed(  # type: ignore[no-any-return]
            self.inner, self.starts, self.rows, c, x, lo, hi, np.ascontiguousarray(s)
        )


class PairSearch:
    """Closest points on ``c1`` and ``c2`` (planar or spatial, same dimension) for the same
    points; :meth:`build` returns ``None`` where the stacking does not apply."""

    def __init__(self, c1: BSpline, c2: BSpline, k: int = 2) -> None:
        self.k = k
        self.search = PolySearch([c1, c2], k)

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

    def closest(self, points: FloatArray) -> tuple[Closest, Closest]:
        """Global closest points (n, dim) on curve 1 and on curve 2."""
        t, foot, dist = self.search.closest(points)
        return (
            Closest(t=t[:, 0], foot=foot[:, 0], distance=dist[:, 0]),
            Closest(t=t[:, 1], foot=foot[:, 1], distance=dist[:, 1]),
        )

    def closest_near(
        self, on2: np.ndarray, points: FloatArray, t0: FloatArray, width: float
    ) -> Closest:
        """Local closest points as :func:`medax.geometry.curve.closest_near`, all rows in
        one bracketed Newton: row ``i`` on curve 2 where ``on2[i]`` (bool (n,)), else on
        curve 1, its parameter in ``[t0 - width, t0 + width]`` clipped to ``[0, 1]``.
        Parameters (n,), foot points (n, dim) and distances (n,)."""
        x = np.asarray(points, dtype=np.float64)
        t0 = np.asarray(t0, dtype=np.float64)
        lo = np.minimum(np.maximum(t0 - width, 0.0), 1.0)
        hi = np.minimum(np.maximum(t0 + width, 0.0), 1.0)
        start = np.minimum(np.maximum(t0, 0.0), 1.0)
        t, foot = self.search.closest_in(on2.astype(np.int64), x, lo, hi, start)
        return Closest(t=t, foot=foot, distance=row_norms(foot - x))
