"""Clamped (optionally rational) B-spline curve of any degree."""

from __future__ import annotations

import math
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING

import numpy as np
from scipy.interpolate import BSpline as _ScipyBSpline

from medax.errors import CurveError
from medax.geometry import kernels
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve


def clamped_uniform_knots(n_ctrl: int, degree: int) -> FloatArray:
    """Clamped knot vector on [0, 1] with uniform interior knots, shape ``(n_ctrl+degree+1,)``."""
    n_inner = n_ctrl - degree - 1
    inner = np.linspace(0.0, 1.0, n_inner + 2)[1:-1]
    return np.concatenate((np.zeros(degree + 1), inner, np.ones(degree + 1)))


if TYPE_CHECKING:  # (pair_search imports this module)
    from medax.geometry.pair_search import PolySearch

#: above this degree the power basis loses digits (6e-10 seen on degree-13 NURBS from
#: OCCT fillets): evaluate with scipy's de Boor instead
POWER_BASIS_MAX_DEGREE = 5
_NO_OFFSET = np.zeros(0)  # kernels.jet_rows: all points on the table's only curve


@lru_cache(maxsize=8)
def _bezier_to_power(k: int) -> FloatArray:
    """(k+1, k+1) matrix taking a degree-``k`` Bezier's control points to its coefficients
    in powers of the local parameter ``s``, highest power first:
    ``coef_j = C(k, j) sum_i (-1)^(j-i) C(j, i) P_i``."""
    m = np.zeros((k + 1, k + 1))
    for j in range(k + 1):
        for i in range(j + 1):
            m[k - j, i] = math.comb(k, j) * math.comb(j, i) * (-1.0) ** (j - i)
    return m


@lru_cache(maxsize=64)
def _bezier_layout(
    m: int, k: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, FloatArray, FloatArray]:
    """For ``m`` Bezier pieces of degree ``k``: knot multiplicities (m+1,), control point
    rows of each piece (m, k+1), powers (k+1,) highest first, and the factors taking value
    to first (k, 1) and first to second (k-1, 1) derivative coefficients."""
    mult = np.full(m + 1, k)
    mult[[0, -1]] = k + 1
    rows = np.arange(m)[:, None] * k + np.arange(k + 1)
    powers = np.arange(k, -1, -1)
    d1 = np.arange(k, 0, -1, dtype=np.float64)[:, None]
    d2 = np.arange(k - 1, 0, -1, dtype=np.float64)[:, None]
    for a in (mult, rows, powers, d1, d2):
        a.flags.writeable = False
    return mult, rows, powers, d1, d2


class BSpline(Curve):
    """B-spline ``C(t)`` with control points (m, dim), clamped knots (m + p + 1,) and optional
    positive weights (m,) (then a NURBS). The knot domain is mapped linearly onto ``[0, 1]``."""

    def __init__(
        self,
        control_points: FloatArray,
        degree: int,
        knots: FloatArray | None = None,
        weights: FloatArray | None = None,
    ) -> None:
        ctrl = np.asarray(control_points, dtype=np.float64)
        if ctrl.ndim != 2 or ctrl.shape[1] not in (2, 3):
            raise CurveError(f"B-spline control points must be (m, 2|3), got shape {ctrl.shape}")
        if not 1 <= degree < ctrl.shape[0]:
            raise CurveError(
                f"B-spline degree {degree} needs at least {degree + 1} control points, "
                f"got {ctrl.shape[0]}"
            )
        if knots is None:
            knots = clamped_uniform_knots(ctrl.shape[0], degree)
        kn = np.asarray(knots, dtype=np.float64)
        if kn.size != ctrl.shape[0] + degree + 1 or (kn[1:] < kn[:-1]).any():
            raise CurveError("B-spline knots must be non-decreasing, m + degree + 1 of them")
        lo, hi = kn[degree], kn[-degree - 1]
        if not hi > lo:
            raise CurveError("B-spline knot domain is empty")
        kn = (kn - lo) / (hi - lo)
        self.control_points, self.degree, self.knots = ctrl, int(degree), kn
        self.weights = None if weights is None else np.asarray(weights, dtype=np.float64)
        if self.weights is not None and (
            self.weights.shape != (ctrl.shape[0],) or np.any(self.weights <= 0)
        ):
            raise CurveError("B-spline weights must be positive, one per control point")

    @classmethod
    def on_unit_knots(cls, control_points: FloatArray, degree: int, knots: FloatArray) -> BSpline:
        """The non-rational spline of ``control_points`` (m, dim) and a clamped knot vector
        ``knots`` (m + degree + 1,) whose domain is already [0, 1] (as :meth:`__init__`
        would map it), from trusted inputs (the fitter's): no checks."""
        spline = cls.__new__(cls)
        spline.control_points, spline.degree = control_points, int(degree)
        spline.knots, spline.weights = knots, None
        return spline

    @classmethod
    def from_bezier(cls, control_points: FloatArray, breaks: FloatArray, degree: int) -> BSpline:
        """The spline made of ``m`` Bezier pieces of ``degree`` joined end to end: control
        points ``(m * degree + 1, dim)`` (each piece's last is the next one's first), piece
        ``i`` on ``[breaks[i], breaks[i + 1]]`` (``breaks`` (m + 1,), increasing; mapped onto
        [0, 1] as every knot domain is). Interior knots have multiplicity ``degree`` (each
        piece is exactly its Bezier curve; C0 in the knot structure). The polynomial
        coefficients come from the control points in closed form (no spline evaluation)."""
        ctrl = np.asarray(control_points, dtype=np.float64)
        x = np.asarray(breaks, dtype=np.float64)
        k, m = int(degree), len(x) - 1
        if (
            k < 1
            or m < 1
            or ctrl.ndim != 2
            or ctrl.shape[1] not in (2, 3)
            or ctrl.shape[0] != m * k + 1
            or np.any(np.diff(x) <= 0)
        ):
            raise CurveError(
                f"Bezier pieces: {ctrl.shape} control points for {m} pieces of degree {k} "
                "(need (m * degree + 1, 2|3)) and increasing breaks"
            )
        xu = (x - x[0]) / (x[-1] - x[0])  # as __init__ normalises the knot domain
        mult, rows, powers, d1, d2 = _bezier_layout(m, k)
        # the checks above are those of __init__ for these knots: set the fields directly
        spline = cls.__new__(cls)
        spline.control_points, spline.degree = ctrl, k
        spline.knots, spline.weights = np.repeat(xu, mult), None
        if k <= POWER_BASIS_MAX_DEGREE:
            c = _bezier_to_power(k) @ ctrl[rows]  # (m, k+1, dim) in powers of s, highest first
            c /= (np.diff(xu)[:, None] ** powers)[:, :, None]  # powers of t - x_i
            coefs = np.zeros((m, k + 1, 3, ctrl.shape[1]))  # the layout of _pieces
            coefs[:, :, 0] = c
            coefs[:, 1:, 1] = c[:, :-1] * d1
            coefs[:, 2:, 2] = coefs[:, 1:-1, 1] * d2
            spline.__dict__["_pieces"] = (xu, coefs)
        return spline

    @cached_property
    def _spl(self) -> _ScipyBSpline:
        """scipy's B-spline of the same knots (de Boor; homogeneous for a NURBS)."""
        if self.weights is None:
            ctrl = np.ascontiguousarray(self.control_points)  # (checked by __init__)
            return _ScipyBSpline.construct_fast(self.knots, ctrl, self.degree, extrapolate=False)
        hom = np.column_stack((self.control_points * self.weights[:, None], self.weights))
        return _ScipyBSpline(self.knots, hom, self.degree, extrapolate=False)

    @property
    def dim(self) -> int:
        return int(self.control_points.shape[1])

    @cached_property
    def _runs(self) -> tuple[FloatArray, np.ndarray, FloatArray]:
        """The distinct knots (k,), their multiplicities (k,) and the C0 joints (read-only;
        the tracer asks for them at every query)."""
        knots = self.knots  # (non-decreasing: np.unique's runs without its sort)
        first = np.flatnonzero(np.concatenate(([True], knots[1:] != knots[:-1])))
        kn, mult = knots[first], np.diff(np.append(first, knots.size))
        joints = kn[(kn > 0.0) & (kn < 1.0) & (mult >= self.degree)]
        for a in (kn, mult, joints):
            a.flags.writeable = False
        return kn, mult, joints

    def breaks(self) -> FloatArray:
        """Interior knots of multiplicity >= degree (C0 joints)."""
        return self._runs[2]

    def complexity(self) -> int:
        return max(1, int(self._runs[0].size - 1))

    @cached_property
    def _pieces(self) -> tuple[FloatArray, FloatArray]:
        """Break points (m+1,) and polynomial coefficients of value, first and second
        derivative, stacked as (m, degree+1, 3, dim[+1]) in powers of ``t - x_i``, highest
        first (the derivatives' missing top powers are zero), so that one row gather per
        point fetches all it needs.
        Evaluating them by Horner's rule costs a few numpy operations for all points and
        orders at once, where scipy's BSpline call pays its overhead once per call and
        derivative."""
        x = self._runs[0].copy()  # the distinct knots
        k = self.degree
        # Taylor coefficients at each interval start (right limits: scipy evaluates a knot
        # with the interval to its right)
        taylor = np.array([np.asarray(self._spl(x[:-1], nu)) for nu in range(k + 1)])
        fact = np.array([float(math.factorial(nu)) for nu in range(k + 1)])
        return self._pack(x, (taylor / fact[:, None, None])[::-1])  # highest power first

    def _pack(self, x: FloatArray, c0: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Break points ``x`` (m+1,) and the value coefficients ``c0`` (degree+1, m, dim),
        highest power first, stacked with those of the first and second derivative as
        :attr:`_pieces` holds them."""
        k = self.degree
        powers = np.arange(k, -1, -1, dtype=np.float64)[:, None, None]
        coefs = np.zeros((3, *c0.shape))
        coefs[0] = c0
        c1 = (c0 * powers)[:-1]
        coefs[1, 1:] = c1
        if k >= 2:
            coefs[2, 2:] = (c1 * powers[1:])[:-1]
        return x, np.ascontiguousarray(coefs.transpose(2, 1, 0, 3))

    def _raw(self, t: FloatArray, nu: int) -> FloatArray:
        return self._raw_many(t, (nu,))[0]

    def _raw_many(self, t: FloatArray, orders: tuple[int, ...]) -> list[FloatArray]:
        """Homogeneous (or plain) derivatives of the given orders (each (n, dim[+1])), from
        one compiled jet evaluation (:func:`kernels.jet_rows`)."""
        # np.minimum/np.maximum: np.clip costs microseconds more per call on small arrays
        t = np.minimum(np.maximum(np.asarray(t, dtype=np.float64), 0.0), 1.0)
        if self.degree > POWER_BASIS_MAX_DEGREE:
            return [np.asarray(self._spl(t, nu)) for nu in orders]
        inner, x, rows = self._row_pieces
        w = kernels.jet_rows(inner, x, rows, np.ascontiguousarray(t.ravel()), _NO_OFFSET)
        dim = rows.shape[1]
        return [w[nu * dim : (nu + 1) * dim].T for nu in orders]

    def evaluate_once(self, t: FloatArray) -> FloatArray:
        """:meth:`evaluate` (equal to rounding) at ``t`` (n,) in [0, 1] by scipy's de Boor
        evaluation, without building the polynomial pieces of :meth:`evaluate`: for a
        spline evaluated once (the fitter's check of each new spline), where building them
        would cost more than the evaluation."""
        if self.weights is not None:
            return self.evaluate(t)
        spl = _ScipyBSpline.construct_fast(
            self.knots, self.control_points, self.degree, extrapolate=False
        )
        return np.asarray(spl(np.asarray(t, dtype=np.float64)))

    def jet(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        h0, h1, h2 = self._raw_many(t, (0, 1, 2))
        if self.weights is None:
            return h0, h1, h2
        w0, w1, w2 = h0[:, -1:], h1[:, -1:], h2[:, -1:]
        c = h0[:, :-1] / w0
        d1 = (h1[:, :-1] - w1 * c) / w0
        d2 = (h2[:, :-1] - 2.0 * w1 * d1 - w2 * c) / w0
        return c, d1, d2

    @cached_property
    def third_bound(self) -> float | None:
        """A bound of ``|C'''|`` over the curve (None for rational curves): per span, the
        sum over powers ``p >= 3`` of ``p (p - 1) (p - 2) |a_p| h^(p - 3)`` (``a_p`` the
        power-basis coefficients, ``h`` the span's width)."""
        if self.weights is not None or self.degree > POWER_BASIS_MAX_DEGREE:
            return None
        x, coefs = self._pieces  # (m, k + 1, 3, dim), highest power first
        k = self.degree
        h = np.diff(x)
        total = np.zeros(h.size)
        for j in range(k + 1):
            p = k - j
            if p >= 3:
                a = np.linalg.norm(coefs[:, j, 0, :], axis=1)
                total += p * (p - 1) * (p - 2) * a * h ** (p - 3)
        return float(total.max(initial=0.0))

    @cached_property
    def _row_pieces(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:attr:`_pieces` for :meth:`jet_rows`: the interior breaks, all breaks, and the
        value's coefficients (degree+1, dim, m) by power (highest first), then coordinate,
        spans last (the derivatives' follow from them: :func:`kernels.jet_rows`)."""
        kernels.announce_compile()  # (every compiled jet and query uses this table)
        x, coefs = self._pieces
        rows = np.ascontiguousarray(coefs[:, :, 0, :].transpose(1, 2, 0))
        return np.ascontiguousarray(x[1:-1]), x, rows

    def jet_table(self) -> tuple[FloatArray, FloatArray, FloatArray, bool] | None:
        """:attr:`_row_pieces` (homogeneous for a NURBS) and whether rational, for the
        compiled Newton of :func:`kernels.newton_table`; None above
        :data:`POWER_BASIS_MAX_DEGREE` (jets from scipy)."""
        if self.degree > POWER_BASIS_MAX_DEGREE:
            return None
        inner, x, rows = self._row_pieces
        return inner, x, rows, self.weights is not None

    def poly_search(self) -> PolySearch | None:
        """The compiled search tables of this curve
        (:class:`~medax.geometry.pair_search.PolySearch`), or None for a rational curve or
        one of a high degree (built on first use)."""
        if "_poly" not in self.__dict__:
            from medax.geometry.pair_search import PolySearch  # (imports this module)

            self.__dict__["_poly"] = PolySearch([self]) if self.has_poly_table() else None
        return self.__dict__["_poly"]

    def has_poly_table(self) -> bool:
        return self.weights is None and self.degree <= POWER_BASIS_MAX_DEGREE

    def chord_smooth(self) -> bool:
        """C1 with a piecewise polynomial ``C''``: no interior knot of multiplicity above
        ``degree - 1`` (and degree at least 2)."""
        mult = self._runs[1]
        return self.degree >= 2 and bool(np.all(mult[1:-1] <= self.degree - 1))

    @staticmethod
    def stacked_rows(
        curves: list[BSpline],
    ) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """The :attr:`_row_pieces` of several non-rational curves in one table (None if one
        is rational or of a high degree): curve ``j`` on parameters ``2 j + t``, the spans of
        all curves in order (a break ``2 j + 1.5`` between curves ``j`` and ``j + 1`` in the
        searched breaks), lower degrees padded with zero top powers; see
        :func:`stacked_jet`."""
        if any(c.weights is not None or c.degree > POWER_BASIS_MAX_DEGREE for c in curves):
            return None
        top = max(c.degree for c in curves) + 1
        inner, starts, rows = [], [], []
        for j, c in enumerate(curves):
            ci, cx, cr = c._row_pieces
            if j:
                inner.append(np.array([2.0 * j - 0.5]))
            inner.append(ci + 2.0 * j)
            starts.append(cx[:-1])  # (local: s = t - start keeps every digit of t)
            pad = np.zeros((top - cr.shape[0], *cr.shape[1:]))
            rows.append(np.concatenate((pad, cr)))
        return np.concatenate(inner), np.concatenate(starts), np.concatenate(rows, axis=2)

    def jet_rows(self, t: FloatArray) -> FloatArray | None:
        if self.weights is not None or self.degree > POWER_BASIS_MAX_DEGREE:
            return None
        inner, x, rows = self._row_pieces
        t = np.minimum(np.maximum(np.asarray(t, dtype=np.float64), 0.0), 1.0)
        return kernels.jet_rows(inner, x, rows, np.ascontiguousarray(t), _NO_OFFSET)  # type: ignore[no-any-return]

    def evaluate(self, t: FloatArray) -> FloatArray:
        h = self._raw(t, 0)
        if self.weights is None:
            return h
        return h[:, :-1] / h[:, -1:]

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        if self.weights is None:
            return self._raw(t, order)
        # (one jet evaluation for all orders: the homogeneous derivatives come together)
        h = self._raw_many(t, (0, 1) if order == 1 else (0, 1, 2))
        h0, h1 = h[0], h[1]
        w0, w1 = h0[:, -1:], h1[:, -1:]
        c = h0[:, :-1] / w0
        d1 = (h1[:, :-1] - w1 * c) / w0
        if order == 1:
            return d1
        h2 = h[2]
        w2 = h2[:, -1:]
        return (h2[:, :-1] - 2.0 * w1 * d1 - w2 * c) / w0

    def reversed(self) -> BSpline:
        kn = 1.0 - self.knots[::-1]
        w = None if self.weights is None else self.weights[::-1]
        return BSpline(self.control_points[::-1], self.degree, kn, w)

    def transformed(self, offset: FloatArray, scale: float) -> BSpline:
        # (the checks of __init__ hold for the image: the same degree, knots and weights)
        out = BSpline.__new__(BSpline)
        out.control_points = (self.control_points - offset) / scale
        out.degree, out.knots, out.weights = self.degree, self.knots, self.weights
        if self.weights is None and "_pieces" in self.__dict__:
            # the image's polynomial pieces in closed form (no de Boor evaluations): all
            # coefficients scaled, the value's constant term moved
            x, coefs = self._pieces
            moved = coefs / scale
            moved[:, -1, 0] -= np.asarray(offset, dtype=np.float64) / scale
            out.__dict__["_pieces"] = (x, moved)
        if "_runs" in self.__dict__:  # (the same knots)
            out.__dict__["_runs"] = self._runs
        return out


def stacked_jet(
    table: tuple[FloatArray, FloatArray, FloatArray], t: FloatArray, offset: FloatArray
) -> FloatArray:
    """:meth:`BSpline.jet_rows` of points on several curves at once (``table``:
    :meth:`BSpline.stacked_rows`; ``offset`` (n,) ``2 j`` for a point on curve ``j``)."""
    inner, starts, rows = table
    t = np.minimum(np.maximum(np.asarray(t, dtype=np.float64), 0.0), 1.0)
    off = np.ascontiguousarray(offset, dtype=np.float64)
    return kernels.jet_rows(inner, starts, rows, t, off)  # type: ignore[no-any-return]
