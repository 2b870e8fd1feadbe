"""The curve interface and a global closest-point query shared by all curve kinds.

Every curve is parametrised on ``t in [0, 1]`` and lives in ``dim`` = 2 or 3 dimensions.
Methods are vectorised: ``t`` has shape ``(n,)``, points ``(n, dim)``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial import cKDTree

from medax.geometry import kernels
from medax.geometry._rows import row_norms
from medax.geometry._types import FloatArray

if TYPE_CHECKING:  # (pair_search imports this module)
    from medax.geometry.pair_search import PolySearch

#: 10-point Gauss-Legendre nodes and weights on [-1, 1] (for :meth:`Curve.length`)
_GAUSS = np.polynomial.legendre.leggauss(10)


@dataclass(frozen=True)
class Closest:
    """Answer of a closest-point query for ``n`` points.

    ``t`` (n,) curve parameters of the foot points, ``foot`` (n, dim) the foot points,
    ``distance`` (n,) the Euclidean distances (same unit as the coordinates).
    """

    t: FloatArray
    foot: FloatArray
    distance: FloatArray


def _unit_steps(n: int) -> FloatArray:
    """``np.linspace(0, 1, n)`` (a fresh copy of one made once per ``n``: curves are
    sampled again for every region and axis)."""
    return _linspace(n).copy()


@lru_cache(maxsize=64)
def _linspace(n: int) -> FloatArray:
    return np.linspace(0.0, 1.0, n)


class Curve(ABC):
    """A parametric curve ``C(t)``, ``t in [0, 1]``."""

    #: number of samples per unit of :meth:`complexity` used by the global search
    samples_per_piece: int = 48

    @property
    @abstractmethod
    def dim(self) -> int:
        """Dimension of the space the curve lives in (2 or 3)."""

    @abstractmethod
    def evaluate(self, t: FloatArray) -> FloatArray:
        """Points ``C(t)``, shape ``(n, dim)`` for ``t`` of shape ``(n,)``."""

    @abstractmethod
    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        """Derivative ``d^k C / dt^k`` (k = ``order`` in 1, 2), shape ``(n, dim)``."""

    @abstractmethod
    def reversed(self) -> Curve:
        """The same point set traversed from end to start."""

    def jet(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``C(t)``, ``C'(t)``, ``C''(t)`` together (each (n, dim)); kinds that can share
        work between them override this."""
        return self.evaluate(t), self.derivative(t), self.derivative(t, 2)

    def jet_table(self) -> tuple[FloatArray, FloatArray, FloatArray, bool] | None:
        """The one-curve polynomial table of :func:`kernels.newton_table` (interior breaks,
        span starts, coefficient rows, whether the rows are homogeneous), whose jets equal
        :meth:`jet`'s; None (the default) for kinds without one."""
        return None

    def chord_smooth(self) -> bool:
        """Whether the curve is C1 with a piecewise continuous second derivative, so that
        between two parameters it stays within ``step^2 / 8 x max|C''|`` of its chord
        (:func:`certify_closest`'s chord bound); kinds that know it override this."""
        return False

    def jet_rows(self, t: FloatArray) -> FloatArray | None:
        """The :meth:`jet` as component rows (3 * dim, n): ``C``, ``C'``, ``C''``, each
        coordinate a contiguous row (cheaper arithmetic on them than on (n, dim) columns);
        None where a kind has no such fast path (callers then use :meth:`jet`)."""
        return None

    def has_poly_table(self) -> bool:
        """Whether the curve is evaluated by polynomial pieces (:meth:`poly_search`,
        ``_row_pieces``): the compiled kernels then evaluate it themselves."""
        return False

    def poly_search(self) -> PolySearch | None:
        """The compiled search tables of a kind evaluated by polynomial pieces
        (:class:`~medax.geometry.pair_search.PolySearch`: global and bracketed closest points
        in one kernel call each), None for the others (their jets come from Python)."""
        return None

    def transformed(self, offset: FloatArray, scale: float) -> Curve:
        """The image under ``x -> (x - offset) / scale`` (a similarity; planar curves)."""
        raise NotImplementedError(f"{type(self).__name__} cannot be transformed")

    @property
    def kind(self) -> str:
        """Short name of the curve kind (``line``, ``arc``, ``bspline``, ``polyline``...)."""
        return type(self).__name__.lower()

    def complexity(self) -> int:
        """Number of smooth pieces (spans, segments); sets the sampling density."""
        return 1

    def breaks(self) -> FloatArray:
        """Interior parameters (k,) where the curve is only C0 (a corner), increasing."""
        return np.zeros(0)

    @property
    def start(self) -> FloatArray:
        """First point, shape ``(dim,)``."""
        return self.evaluate(np.zeros(1))[0]

    @property
    def end(self) -> FloatArray:
        """Last point, shape ``(dim,)``."""
        return self.evaluate(np.ones(1))[0]

    def length(self, n: int = 0) -> float:
        """Arc length, by Gauss-Legendre quadrature on ``complexity()`` pieces."""
        pieces = max(self.complexity(), 1) * 8
        x, w = _GAUSS
        edges = _unit_steps(pieces + 1)
        a, b = edges[:-1, None], edges[1:, None]
        t = (0.5 * (b - a) * x[None, :] + 0.5 * (a + b)).ravel()
        speed = np.linalg.norm(self.derivative(t), axis=1).reshape(pieces, -1)
        return float(np.sum(0.5 * (b - a) * speed * w[None, :]))

    def sample(self, n: int) -> FloatArray:
        """``n`` points at equal parameter steps, shape ``(n, dim)``."""
        return self.evaluate(_unit_steps(n))

    @cached_property
    def _search(self) -> tuple[FloatArray, FloatArray]:
        """The search samples: parameters (m,) and points (m, dim)."""
        t = _unit_steps(self.samples_per_piece * max(self.complexity(), 1) + 1)
        return t, self.evaluate(t)

    @cached_property
    def _tree(self) -> cKDTree:
        """k-d tree of the search samples (built on first use: only very large queries)."""
        return cKDTree(self._search[1])

    @cached_property
    def _slopes(self) -> FloatArray:
        """``C'`` at the search samples, (m, dim)."""
        return self.derivative(self._search[0])

    @cached_property
    def _gaps(self) -> tuple[float, float, float]:
        """Bounds between the search samples (:func:`certify_closest`): 0.55 of the longest
        chord, a quarter of its square, and how far the curve may leave its chords: the
        parameter step squared over 8 times 1.5 x the largest ``|C''|`` at the samples and
        half-way between them; infinite (no chord bound) unless the curve says it is
        continuously differentiable with a piecewise continuous ``C''``
        (:meth:`chord_smooth`: a kink between samples would take it off its chords by more)."""
        ts, pts = self._search
        chord = float(np.max(np.linalg.norm(np.diff(pts, axis=0), axis=1)))
        dt = float(ts[1] - ts[0])
        sag = np.inf
        if self.chord_smooth():
            both = np.concatenate((ts, 0.5 * (ts[1:] + ts[:-1])))
            acc = float(np.max(np.linalg.norm(self.derivative(both, 2), axis=1)))
            sag = 1.5 * acc * dt * dt / 8.0
        return 0.55 * chord, 0.25 * (1.0 + 1e-9) * chord * chord, sag

    @cached_property
    def _table(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The centre (dim,) of the search samples, the samples centred on it (|x|^2 -
        2 x.p + |p|^2 loses digits far from the origin) as coordinate rows (dim, m), and
        their squared norms (m,): the sample-distance tables of
        :func:`kernels.candidates` and :func:`kernels.certify_rows`."""
        kernels.announce_compile()
        pts = self._search[1]
        centre = pts.mean(axis=0)
        c = pts - centre
        return centre, np.ascontiguousarray(c.T), np.einsum("mj,mj->m", c, c)

    def closest_in(
        self, points: FloatArray, lo: FloatArray, hi: FloatArray, start: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The nearest point to ``points[i]`` (n, dim) with parameter in ``[lo[i], hi[i]]``
        (n,): parameters (n,) and foot points (n, dim); bracketed Newton from ``start``."""
        return _bracketed_newton(self, points, lo, hi, start=start)

    def closest(self, points: FloatArray) -> Closest:
        """Global closest points on the curve for ``points`` of shape ``(n, dim)``.

        The search is global: the nearest of dense samples picks candidate brackets (the
        ``k`` nearest samples, so a nearest point that jumps between distant parts of a
        wavy curve is found), then a safeguarded Newton iteration on
        ``g(t) = (C(t) - x) . C'(t)`` refines each bracket to machine precision.
        """
        return closest_by_search(self, np.asarray(points, dtype=np.float64))


def closest_near(curve: Curve, points: FloatArray, t0: FloatArray, width: float) -> Closest:
    """Local closest points: the nearest point of ``curve`` to ``points[i]`` with parameter in
    ``[t0[i] - width, t0[i] + width]`` (a branch of the curve), for all points at once; the
    Newton iteration starts from ``t0`` (a warm start when the points moved little)."""
    x = np.asarray(points, dtype=np.float64)
    t0 = np.asarray(t0, dtype=np.float64)
    lo = np.clip(t0 - width, 0.0, 1.0)
    hi = np.clip(t0 + width, 0.0, 1.0)
    t, foot = curve.closest_in(x, lo, hi, t0)
    return Closest(t=t, foot=foot, distance=np.linalg.norm(foot - x, axis=1))


def has_closed_form_closest(curve: Curve) -> bool:
    """True where ``curve`` answers closest-point queries in closed form (lines, arcs,
    polylines): cheap and global, so nothing is gained by warm starts."""
    return type(curve).closest not in (Curve.closest, SubCurve.closest)


def closest_from(curve: Curve, points: FloatArray, t0: FloatArray, iters: int = 8) -> Closest:
    """Local closest points by Newton steps on ``(C(t) - x) . C'(t)`` from ``t0`` (n,).

    A warm start for points that moved little since their feet ``t0`` were found: each row
    stops when its step is below ``1e-12``. Not global (a foot that should jump to another
    part of the curve is not found): callers check the result with :meth:`Curve.closest`.
    """
    x = np.asarray(points, dtype=np.float64)
    t = np.clip(np.asarray(t0, dtype=np.float64), 0.0, 1.0).copy()
    rows = np.arange(t.size)
    for _ in range(iters):
        c0, c1, c2 = curve.jet(t[rows])
        c = c0 - x[rows]
        g = np.einsum("ij,ij->i", c, c1)
        speed2 = np.einsum("ij,ij->i", c1, c1)
        dg = speed2 + np.einsum("ij,ij->i", c, c2)
        # away from a local minimum (dg <= 0) a gradient step scaled by the speed
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(dg > 0.0, g / dg, g / np.maximum(speed2, 1e-300))
        step = np.where(np.isfinite(step), step, 0.0)
        new = np.minimum(np.maximum(t[rows] - step, 0.0), 1.0)
        moved = np.abs(new - t[rows]) > 1e-12
        t[rows] = new
        rows = rows[moved]
        if rows.size == 0:
            break
    foot = curve.evaluate(t)
    return Closest(t=t, foot=foot, distance=np.linalg.norm(foot - x, axis=1))


def track_closest(
    curve: Curve, points: FloatArray, t0: FloatArray, step_tol: float = 1e-6, iters: int = 8
) -> Closest:
    """Local closest points by Newton steps on ``g(t) = (C(t) - x) . C'(t)`` from ``t0``
    (n,), as :func:`closest_from`, but each row stops at its first Newton step ``s`` of at
    most ``step_tol``: Newton converges quadratically, so the foot is then off by about
    ``K s^2`` (``K = g'' / 2 g'``) and, the distance being stationary at the foot, the
    distance by about ``g' K^2 s^4`` (1e-24 for ``s = 1e-6`` and ``K, g'`` of order one);
    the foot point is the second-order Taylor expansion from that step's jet (off by
    ``|C'''| s^3 / 6``): no separate evaluation of the feet. Gradient steps (where
    ``g' <= 0``) never stop a row."""
    x = np.asarray(points, dtype=np.float64)
    xs = np.ascontiguousarray(x.T)
    if curve.has_poly_table():  # one compiled call
        t, foot_rows, _ = track_rows(curve, xs, t0, step_tol, iters)
    else:

        def jet(tr: FloatArray, rows: np.ndarray | slice | None) -> FloatArray:
            return np.concatenate([c.T for c in curve.jet(tr)])

        t, foot_rows, _ = track_rows(jet, xs, t0, step_tol, iters)
    foot = foot_rows.T
    return Closest(t=t, foot=foot, distance=np.linalg.norm(foot - x, axis=1))


#: component-row jets of the points ``rows`` (indices; None: all) of a tracking at
#: parameters ``t``
RowJet = Callable[[FloatArray, "np.ndarray | None"], "FloatArray | None"]
#: the polynomial table of several curves (:meth:`BSpline.stacked_rows`) and each point's
#: curve offset ``2 j`` (n,) (:func:`medax.geometry.bspline.stacked_jet`)
TableJet = tuple[tuple[FloatArray, FloatArray, FloatArray], FloatArray]


def track_rows(
    curve: Curve | RowJet | TableJet,
    xs: FloatArray,
    t0: FloatArray,
    step_tol: float | FloatArray = 1e-6,
    iters: int = 8,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`track_closest` for points given as component rows ``xs`` (dim, n), on a
    curve with :meth:`Curve.jet_rows`, on several curves at once (a :data:`TableJet`, or a
    :data:`RowJet` that evaluates each point's own curve; ``step_tol`` then per point),
    or on any curve's jets as a :data:`RowJet`: feet (n,) and foot points as rows (dim, n),
    and ``|(C - x) . C''| / g'`` at the last step (n,; the curvature term of the distance's
    Hessian times the distance, see :mod:`medax.mesh.free_field`; 0 for a foot held at an
    end, inf away from a local minimum or where the steps ran out before one was short
    enough). Polynomial tables run in one compiled call (:func:`kernels.track_table`);
    other jets are evaluated here between compiled steps (:func:`kernels.track_step_rows`).
    """
    kernels.announce_compile()
    t = np.minimum(np.maximum(np.asarray(t0, dtype=np.float64), 0.0), 1.0)
    tol = np.ascontiguousarray(np.atleast_1d(np.asarray(step_tol, dtype=np.float64)))
    xs = np.ascontiguousarray(xs, dtype=np.float64)
    table: tuple[FloatArray, FloatArray, FloatArray] | None = None
    offset = _NO_OFFSET
    if isinstance(curve, tuple):
        table, offset = curve[0], np.ascontiguousarray(curve[1], dtype=np.float64)
    elif isinstance(curve, Curve):
        if not curve.has_poly_table():
            raise TypeError(f"{curve.kind} has no polynomial table: pass its jets")
        table = curve._row_pieces  # type: ignore[attr-defined]
    if table is not None:
        inner, starts, rows = table
        return kernels.track_table(inner, starts, rows, offset, xs, t, tol, iters)  # type: ignore[no-any-return]
    return _track_rows(curve, xs, t, tol, iters)  # type: ignore[arg-type]


_NO_OFFSET = np.zeros(0)


def _track_rows(
    jet: RowJet, xs: FloatArray, t: FloatArray, tol: FloatArray, iters: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`track_rows` with jets from Python (``jet``; points ``xs`` (dim, n), step
    tolerances ``tol`` (n,) or (1,)): the compiled step (:func:`kernels.track_step_rows`)
    of the rows still moving, until each is done; feet (n,), foot points (dim, n) and
    curvature terms (n,)."""
    t = t.copy()
    foot, curv = np.empty((xs.shape[0], t.size)), np.empty(t.size)
    rows: np.ndarray | None = None  # rows still moving (None: all)
    for it in range(iters):
        at: np.ndarray | slice = slice(None) if rows is None else rows
        w = jet(t[at], rows)
        assert w is not None
        tr = tol if tol.size == 1 else tol[at]
        new, f, k, done = kernels.track_step_rows(
            np.ascontiguousarray(w), np.ascontiguousarray(xs[:, at]), t[at], tr, it == iters - 1
        )
        # (a row's foot and term are stored at every step: the last one stays)
        t[at], foot[:, at], curv[at] = new, f, k
        left = np.flatnonzero(~done)
        rows = left if rows is None else rows[left]
        if rows.size == 0:
            break
    return t, foot, curv


def certify_closest(
    curve: Curve, points: FloatArray, t: FloatArray, distance: FloatArray, slack: float
) -> np.ndarray:
    """Rows (bool (n,)) where the local foot ``t`` (n,) at ``distance`` (n,) is certainly
    global: no other part of the curve is nearer than ``distance - slack``.

    Each other part of the curve is represented by a local minimum of the distance over the
    dense samples (outside one sample spacing of ``t``); a part whose best sample is at
    ``s`` has no point nearer than the larger of two bounds (:attr:`Curve._gaps`): ``s - h / 2``
    (the curve between samples is at most half a spacing ``h`` from one), and
    ``sqrt(s^2 - l^2 / 4) - e`` (a point of a chord of length ``l`` is at least that from a
    point whose distance to both its ends is at least ``s``; the curve is within ``e`` of
    its chords, the parameter step squared times a bound of ``|C''|`` over 8): far from
    the curve the second is the tighter by orders of magnitude. Cheaper than
    :meth:`Curve.closest` (no refinement); rows not certified need the full query.
    """
    ts = curve._search[0]
    centre, ct, pp = curve._table  # centred on the samples
    x = np.ascontiguousarray(np.asarray(points, dtype=np.float64) - centre)
    t = np.ascontiguousarray(t, dtype=np.float64)
    d = np.ascontiguousarray(distance, dtype=np.float64)
    half, quarter, sag = curve._gaps
    return kernels.certify_rows(ts, ct, pp, x, t, d, half, quarter, sag, float(slack))  # type: ignore[no-any-return]


def closest_by_search(curve: Curve, points: FloatArray, k: int = 2) -> Closest:
    """Generic global closest-point query (see :meth:`Curve.closest`).

    Candidates are the ``k`` best local minima of the distance over the dense samples
    (distinct parts of the curve, not neighbouring samples of one part). Each is refined in
    the bracket of its two neighbouring samples: ``g = (C - x) . C'`` at the three samples
    (from the tabulated samples and slopes: no curve evaluation) picks the half with the
    sign change, whose inverse quadratic interpolation starts a bracketed Newton iteration;
    a bracket without a sign change keeps its nearest sample (an end of the curve). Curves
    with polynomial tables run it all in one compiled call
    (:func:`medax.geometry.kernels.closest_search`); the others bracket in one compiled
    call and refine in another (:func:`_newton_in_brackets`: rational B-splines) or evaluate
    their jets from Python between the compiled steps.
    """
    n = points.shape[0]
    if n == 0:
        return Closest(t=np.zeros(0), foot=np.zeros((0, curve.dim)), distance=np.zeros(0))
    poly = curve.poly_search()
    if poly is not None and poly.k == k:
        t2, f2, d2 = poly.closest(points)
        return Closest(t=t2[:, 0], foot=f2[:, 0], distance=d2[:, 0])
    ts, pts = curve._search
    cand = _candidate_samples(curve, points, k).ravel()
    x = np.ascontiguousarray(np.repeat(points, k, axis=0))
    t, foot, ta, tb, s0, interior, w_lo, w_hi = kernels.bracket_rows(
        ts, np.ascontiguousarray(pts), np.ascontiguousarray(curve._slopes), x, cand
    )
    if interior.any():
        t[interior], foot[interior] = _newton_in_brackets(
            curve, x[interior], ta[interior], tb[interior], s0[interior]
        )
    at_breaks(curve, curve.breaks(), x, w_lo, w_hi, t, foot)
    dist = row_norms(foot - x).reshape(n, k)
    pick = dist.argmin(axis=1)
    r = np.arange(n)
    return Closest(
        t=t.reshape(n, k)[r, pick],
        foot=foot.reshape(n, k, -1)[r, pick],
        distance=dist[r, pick],
    )


def at_breaks(
    curve: Curve | Any,
    breaks: FloatArray,
    x: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    t: FloatArray,
    foot: FloatArray,
) -> None:
    """In place: where a C0 corner ``breaks`` (k,) (sorted) lies in a row's window ``[lo,
    hi]`` (n,) and is nearer to ``x`` (n, dim) than its refined foot (``t`` (n,), ``foot``
    (n, dim)), the corner. At a corner that is convex towards ``x`` the distance has its
    minimum without ``g = (C - x) . C'`` crossing zero (``g`` jumps there), which the
    bracketed Newton, meant for roots, can miss: a point on the normal line of one piece
    at the corner got a foot on that piece, farther than the corner. ``curve`` has ``jet``."""
    if breaks.size == 0 or x.shape[0] == 0:
        return
    i = np.searchsorted(breaks, lo, side="left")
    e = breaks[np.minimum(i, breaks.size - 1)]
    rows = np.flatnonzero((i < breaks.size) & (e <= hi))
    if rows.size == 0:
        return
    c = curve.jet(e[rows])[0]
    nearer = np.einsum("ij,ij->i", c - x[rows], c - x[rows]) < np.einsum(
        "ij,ij->i", foot[rows] - x[rows], foot[rows] - x[rows]
    )
    r = rows[nearer]
    t[r], foot[r] = e[rows][nearer], c[nearer]


#: a Newton step on the foot parameter at most this long ends a row: Newton converging
#: quadratically, the foot parameter is then off by about ``K s^2`` (``K = g'' / 2 g'``),
#: ~1e-16. Far from the curve the distance is stationary at the foot and would allow far
#: longer steps (``track_closest`` stops at 1e-6 by default, the mesher's at up to 1e-4);
#: near it (the deviation check's points on the surfaces) the distance is off by
#: ``|C'| K s^2``: 1e-6 left 3e-12 on a merged face's profile, 1e-8 leaves round-off, at
#: no measurable cost on the wavy axis (27 - 29 ms both)
_STEP_TOL = kernels.STEP_TOL


_TREE_ABOVE = 2_000_000  # point x sample table size above which a k-d tree answers (x 50)


def _candidate_samples(curve: Curve, points: FloatArray, k: int) -> np.ndarray:
    """Indices (n, k) of the ``k`` nearest local minima of the sample distance per point."""
    n, m = points.shape[0], curve._search[0].size
    if m * n > 50 * _TREE_ABOVE:  # very long curves: nearest samples from the k-d tree
        _, idx = curve._tree.query(points, k=4 * k)
        return np.asarray(idx)[:, ::4][:, :k]
    centre, ct, pp = curve._table
    x = np.ascontiguousarray(points - centre)
    bounds = np.array([0, m], dtype=np.int64)
    return kernels.candidates(ct, pp, bounds, x, k)[:, 0]  # type: ignore[no-any-return]


def _bracketed_newton(
    curve: Curve,
    x: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    start: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Minimise ``|C(t) - x|`` over ``t in [lo, hi]`` for all rows at once: parameters (n,)
    and foot points (n, dim).

    ``g(t) = (C - x) . C'`` is the half derivative of the squared distance. Where ``g`` has
    the same sign at both bracket ends the minimum is at an end; otherwise the bracketed
    Newton iteration from ``start`` (default: the linear interpolation of ``g`` between the
    bracket ends); in one compiled call for curves with polynomial tables
    (:func:`medax.geometry.kernels.closest_bracketed`).
    """
    poly = curve.poly_search()
    if poly is not None:
        return poly.closest_in(np.zeros(x.shape[0], dtype=np.int64), x, lo, hi, start)  # type: ignore[no-any-return]
    n = x.shape[0]
    c0, c1, _ = curve.jet(np.concatenate((lo, hi)))
    c = c0 - np.concatenate((x, x))
    g_ends = np.einsum("ij,ij->i", c, c1)
    d_ends = np.einsum("ij,ij->i", c, c)
    g_lo, g_hi, d_lo, d_hi = g_ends[:n], g_ends[n:], d_ends[:n], d_ends[n:]
    interior = (g_lo < 0.0) & (g_hi > 0.0)
    # no interior minimum: the smaller end distance wins
    at_lo = d_lo <= d_hi
    t = np.where(at_lo, lo, hi)
    foot = np.where(at_lo[:, None], c0[:n], c0[n:])
    if not np.any(interior):
        return t, foot
    a, b = lo[interior], hi[interior]
    ga, gb = g_lo[interior], g_hi[interior]
    if start is None:
        s0 = a + (b - a) * ga / (ga - gb)  # regula falsi start: g < 0 at a, > 0 at b
    else:
        s0 = np.minimum(np.maximum(start[interior], a), b)
    t[interior], foot[interior] = _newton_in_brackets(curve, x[interior], a, b, s0)
    return t, foot


def _newton_in_brackets(
    curve: Curve, x: FloatArray, a: FloatArray, b: FloatArray, s: FloatArray, iters: int = 60
) -> tuple[FloatArray, FloatArray]:
    """The root of ``g(t) = (C(t) - x) . C'(t)`` in ``[a, b]`` (n,) where ``g(a) < 0 < g(b)``,
    from ``s`` (n,): parameters (n,) and foot points (n, dim), for curves without a compiled
    global search: one compiled call for those with a jet table (rational B-splines:
    :meth:`Curve.jet_table`, :func:`kernels.newton_table`), else their jets evaluated here
    and the steps compiled (:func:`kernels.newton_rows`).

    Newton steps kept inside the shrinking sign-change bracket (bisection when a step leaves
    it or ``g' <= 0``); a row stops at its first step of at most ``_STEP_TOL`` (see there),
    its foot the second-order Taylor expansion of that step's jet (off by ``|C^(3)| s^3 / 6``):
    no separate evaluation of the feet.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    table = curve.jet_table()
    if table is not None:  # (the whole iteration compiled, the jets too; the kernel keeps
        # its inputs)
        a, b, s = (np.ascontiguousarray(v, dtype=np.float64) for v in (a, b, s))
        return kernels.newton_table(*table, x, a, b, s, iters)  # type: ignore[no-any-return]
    a = np.array(a, dtype=np.float64)  # (updated in place below)
    b = np.array(b, dtype=np.float64)
    s = np.array(s, dtype=np.float64)
    s = np.where(np.isfinite(s), s, 0.5 * (a + b))
    foot = np.empty_like(x)
    rows = np.arange(s.size)
    for it in range(iters):
        sr, ar, br, xr = s[rows], a[rows], b[rows], x[rows]
        c0, c1, c2 = (np.ascontiguousarray(c) for c in curve.jet(sr))
        fr = np.empty_like(xr)
        done = kernels.newton_rows(c0, c1, c2, xr, sr, ar, br, it == iters - 1, fr)
        s[rows], a[rows], b[rows] = sr, ar, br
        foot[rows[done]] = fr[done]
        rows = rows[~done]
        if rows.size == 0:
            break
    return s, foot


class SubCurve(Curve):
    """The piece ``t in [t0, t1]`` of ``base``, reparametrised onto ``[0, 1]`` (exact)."""

    def __init__(self, base: Curve, t0: float, t1: float) -> None:
        self.base, self.t0, self.t1 = base, float(t0), float(t1)

    @property
    def dim(self) -> int:
        return self.base.dim

    @property
    def kind(self) -> str:
        return self.base.kind

    def complexity(self) -> int:
        return max(1, int(np.ceil(self.base.complexity() * abs(self.t1 - self.t0))))

    def chord_smooth(self) -> bool:
        return self.base.chord_smooth()

    def breaks(self) -> FloatArray:
        b = (self.base.breaks() - self.t0) / (self.t1 - self.t0)
        return np.sort(b[(b > 0.0) & (b < 1.0)])

    def _map(self, t: FloatArray) -> FloatArray:
        return self.t0 + np.asarray(t, dtype=np.float64) * (self.t1 - self.t0)

    def evaluate(self, t: FloatArray) -> FloatArray:
        return self.base.evaluate(self._map(t))

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        return self.base.derivative(self._map(t), order) * (self.t1 - self.t0) ** order

    def reversed(self) -> SubCurve:
        return SubCurve(self.base, self.t1, self.t0)

    def transformed(self, offset: FloatArray, scale: float) -> SubCurve:
        return SubCurve(self.base.transformed(offset, scale), self.t0, self.t1)

    def closest(self, points: FloatArray) -> Closest:
        return closest_by_search(self, np.asarray(points, dtype=np.float64))


def sub_curve(curve: Curve, t0: float, t1: float) -> Curve:
    """The piece of ``curve`` between parameters ``t0`` and ``t1`` (reversed if ``t1 < t0``)."""
    if isinstance(curve, SubCurve):
        a = curve.t0 + t0 * (curve.t1 - curve.t0)
        b = curve.t0 + t1 * (curve.t1 - curve.t0)
        return SubCurve(curve.base, a, b)
    return SubCurve(curve, t0, t1)
