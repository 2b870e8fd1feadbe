"""Least-squares tensor-product cubic B-spline of a height field ``z = h(x, y)``.

Used where a merged face has no exact surface: the face is the graph of a height over a
plane, known exactly (``h`` evaluates the original surfaces) only on the part of a
rectangle that the face covers. The fit therefore takes data only where ``h`` says it is
defined and relevant, and a small penalty on the coefficients' second (and, weaker, first)
differences decides the rest of the rectangle (a minimum-curvature continuation, so nothing
oscillates outside), stronger on the coefficients that touch the data only with their tails.

Knots: double (C1) knots at prescribed *breaks* (lines ``x = const`` / ``y = const`` where
the height's curvature jumps: the smooth edges between a plane and a fillet, the cross
edges between a fillet and a corner blend), so the spline converges at its full order on
both sides; between breaks, spans of at most ``spacing`` where the height is curved in that
direction and, where it is linear, spans doubling away from the curved neighbours (flat
strips cost a few spans; a curved strip in a wide flat interval gets breaks of its own, so
only the strip is fine; the doubling keeps the fit's continuation where it has no data near
the data, see :func:`_graded`). The spacing is
halved until the error, measured on a grid 7 points per span (not the fitting samples),
is within the tolerance; in one direction only when the first halvings show that the other
hardly matters (a curvature jump along a curve that is no knot line, see
:func:`_one_direction`). The normal equations are assembled from the tensor structure and
solved by banded Cholesky (:func:`solve_masked`). scipy has no constrained/penalised
tensor-product fit on a masked grid (``LSQBivariateSpline`` takes no penalty and fails on
large empty areas), hence this.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol, TypeVar

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import BSpline
from scipy.linalg import LinAlgError, cho_solve_banded, cholesky_banded
from scipy.sparse.linalg import spsolve
from threadpoolctl import ThreadpoolController

from medax.geometry._types import FloatArray

#: Cubic in both directions.
DEGREE = 3
#: Fitting samples per knot span and direction.
SAMPLES_PER_SPAN = 4
#: Error-check samples per knot span and direction.
CHECK_PER_SPAN = 7
#: Refinement stops when two halvings of the spacing did not divide the error by 1 / STALL.
STALL = 0.25
#: Refinement stops when the last halving's rate, kept for the levels left, would still end
#: above this many times the tolerance (each level costs about 4x the one before; a cubic
#: fit's error falls 16x per halving on smooth data, 4x across a curvature jump). At 50
#: the fits that reached the tolerance on five corpus parts were the same as at 100, and
#: a 229-face bracket took 156 s CPU instead of 191; at 25 a part lost five accepted fits.
HOPELESS = 50.0
#: Largest number of coefficients of one fit (a finer level is not tried): 8e4 unknowns take
#: about 2 s (banded Cholesky); a plate under many bosses would otherwise ask for 10^6.
MAX_COEFFICIENTS = 80_000
#: Long (flat) spans are sampled at most this many spacings apart, so that a span over a
#: hole keeps data on both sides of it, and checked at half that.
FLAT_GAP = 4.0
#: Uniform lines per direction along which the height is probed for curvature.
UNIFORM_PROBES = 41
#: Most extra probe lines per direction (through the curved pieces) besides those.
MAX_PROBES = 200
#: Weight of the second-difference penalty (data rows have weight 1). It only has to make
#: the coefficients without data determinate: larger values bias the fit (measured on the
#: 12-edge box: 1e-6 -> 1e-4 error, 1e-9 -> 1.5e-5, 1e-12 -> 3e-6 at the same knots).
PENALTY = 1e-12
#: Weight of the first differences in the penalty, relative to the second ones (a tension):
#: where the fit has no data, a slope at the face's edge dies out over about
#: ``TENSION ** -0.5`` spans instead of running on as a straight line (OCCT's default
#: mass properties, FreeCAD's and CadQuery's, integrate over the surface's parameter box
#: beyond the face): on a 555-face part's fitted faces 0.3 - 20 mm high the run-on outside
#: went from 124 and 355 mm to 72 and 191 mm. What mended that part's reading is the
#: weak coefficients' penalty below.
TENSION = 1e-2
#: Coefficients whose basis function meets less data than WEAK_MASS times a typical one's
#: (the normal matrix's diagonal against its median over the coefficients with data) take
#: the penalty at WEAK_PENALTY: only the tails of their functions touch data, and at
#: ``PENALTY`` the least squares bent them to 20 - 200x slopes just outside the face (the
#: 555-face part's fitted flange read 28 % off in area by OCCT's default integrator).
WEAK_MASS = 0.05
WEAK_PENALTY = 1e-10
#: Weight of the ``prior`` values (the supporting surface's own) that a fit may take where it
#: has no data (:func:`solve_masked`): the continuation then returns to the support within
#: a few spans of the face instead of bulging as a free membrane. OCCT's default mass
#: properties integrate the surface beyond the face (from the face's first ``u``, one Gauss
#: rule of at most 61 points): a field over a cylinder whose points ran on freely across a
#: 3-radian notch read 25 % off on its face, the whole part 3 % (GrabCAD part 19). Small
#: enough not to bias the data: 1e-10 x a height difference on the coefficients that meet both.
PRIOR_WEIGHT = 1e-10
#: Largest banded normal matrix (entries: (band + 1) x unknowns) solved by banded Cholesky;
#: larger ones go to SuperLU. Every fit within MAX_COEFFICIENTS fits (at most 6.9e7 entries,
#: 550 MB): on 283 x 283 unknowns banded Cholesky took 2.2 s and 550 MB more than the
#: process had, SuperLU 15.7 s and 1160 MB (its Kronecker design matrix and fill).
MAX_BAND_ENTRIES = 70_000_000

#: ``h(X, Y) -> (Z, defined, inside)``: heights on a grid (arrays of one shape), where they
#: are defined (data rows of the fit) and where the fit error counts (the face itself).
HeightFn = Callable[[FloatArray, FloatArray], tuple[FloatArray, np.ndarray, np.ndarray]]


class _Measured(Protocol):
    @property
    def error(self) -> float: ...


F = TypeVar("F", bound=_Measured)


@dataclass(frozen=True)
class TensorFit:
    """``z(x, y) = sum_ij c_ij Bx_i(x) By_j(y)``: clamped cubic knot vectors ``tx``, ``ty``
    (with repeats), coefficients ``coef`` (nx, ny), measured ``error`` (max |z - h| on the
    check grid where ``inside``, length unit), the ``spacing`` used and ``volume``, the
    signed integral of ``z - h`` over ``inside`` (length unit cubed, midpoint rule on the
    check grid)."""

    tx: FloatArray
    ty: FloatArray
    coef: FloatArray
    error: float
    spacing: float
    volume: float = 0.0

    def check_samples(self) -> tuple[FloatArray, FloatArray]:
        """The x and y samples where the error is measured: CHECK_PER_SPAN per span, at most
        FLAT_GAP / 2 spacings apart in long spans."""
        gap = 0.5 * FLAT_GAP * self.spacing
        return span_samples(self.tx, CHECK_PER_SPAN, gap), span_samples(
            self.ty, CHECK_PER_SPAN, gap
        )

    def __call__(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """Heights on the tensor grid ``x`` (n,) by ``y`` (m,), shape (n, m)."""
        bx = BSpline.design_matrix(x, self.tx, DEGREE)
        by = BSpline.design_matrix(y, self.ty, DEGREE)
        return np.asarray(bx @ (by @ self.coef.T).T)


def greville(t: FloatArray, degree: int = DEGREE) -> FloatArray:
    """Greville abscissae of a full knot vector ``t`` of ``degree`` (one per coefficient):
    placing control points there reproduces ``x`` itself exactly."""
    t = np.asarray(t, dtype=np.float64)
    n = t.size - degree - 1
    if degree == 0:
        return t[:n].copy()
    return np.lib.stride_tricks.sliding_window_view(t[1:], degree)[:n].mean(axis=1)


def _coefficient_count(
    lo: float, hi: float, breaks: Sequence[float], fine: Sequence[bool], sp_: float
) -> float:
    """Coefficients of :func:`knot_vector` with the same arguments, counted without building the
    knots (inf for a spacing that is not positive: a degenerate piece's radius)."""
    if not sp_ > 0.0:
        return float("inf")
    pts = [lo, *breaks, hi]
    spans = sum(
        max(1.0, np.ceil((b - a) / sp_ - 1e-9))
        if fine[k]
        else 1.0 + len(_graded(a, b, sp_, k > 0 and fine[k - 1], k + 1 < len(fine) and fine[k + 1]))
        for k, (a, b) in enumerate(zip(pts[:-1], pts[1:], strict=True))
    )
    return float(spans + DEGREE + (DEGREE - 2) * len(breaks))


def knot_vector(
    lo: float, hi: float, breaks: Sequence[float], fine: Sequence[bool], sp_: float
) -> FloatArray:
    """Clamped cubic knot vector on [lo, hi], double knots at ``breaks`` (sorted, inside),
    intervals flagged ``fine`` split into spans of at most ``sp_``, the others graded from
    their fine neighbours (:func:`_graded`)."""
    pts = [lo, *breaks, hi]
    t = [lo] * (DEGREE + 1)
    for k, (a, b) in enumerate(zip(pts[:-1], pts[1:], strict=True)):
        if fine[k]:
            n = max(1, int(np.ceil((b - a) / sp_ - 1e-9)))
            t += list(np.linspace(a, b, n + 1)[1:-1])
        else:  # graded from a fine neighbour: the spans double away from it
            t += _graded(a, b, sp_, k > 0 and fine[k - 1], k + 1 < len(fine) and fine[k + 1])
        if k < len(pts) - 2:
            t += [b] * (DEGREE - 1)
    t += [hi] * (DEGREE + 1)
    return np.array(t)


def _graded(a: float, b: float, sp_: float, from_a: bool, from_b: bool) -> list[float]:
    """Inner knots of a flat interval [a, b]: none, or spans of ``sp_``, ``2 sp_``, ``4 sp_``
    ... growing from an end next to a fine interval (``from_a``, ``from_b``), up to the
    middle. One long span next to fine ones carries the fine data's last slope across all
    of it where it has no data (outside the face: 35 mm high on a 40 mm span beside a
    fillet strip, where OCCT's default mass properties still integrate, and read the solid
    5.5 % off); graded spans keep the continuation near the data (0.6 mm there, read
    1.3e-5 off)."""
    half = 0.5 * (b - a)
    out: list[float] = []
    for start, sign, on in ((a, 1.0, from_a), (b, -1.0, from_b)):
        step, d = sp_, sp_
        while on and d < (half if from_a and from_b else 2 * half) - step:
            out.append(start + sign * d)
            step *= 2.0
            d += step
    return sorted(out)


def _span_counts(u: FloatArray, per_span: int, max_gap: float) -> np.ndarray:
    """Samples per span between the distinct knots ``u``: ``per_span``, more in spans longer
    than ``per_span * max_gap``."""
    n = np.full(len(u) - 1, per_span)
    if np.isfinite(max_gap) and max_gap > 0.0:
        n = np.maximum(n, np.ceil(np.diff(u) / max_gap - 1e-9).astype(int))
    return n


def span_samples(t: FloatArray, per_span: int, max_gap: float = np.inf) -> FloatArray:
    """Centres of equal cells of every knot span of ``t``: ``per_span`` per span, and in
    long spans (a flat strip fitted by one span) cells at most ``max_gap`` wide, so that a
    span over a hole in the face keeps samples on both sides of it."""
    u = np.unique(t)
    n = _span_counts(u, per_span, max_gap)
    if np.all(n == per_span):
        off = (np.arange(per_span) + 0.5) / per_span
        return (u[:-1, None] + (u[1:] - u[:-1])[:, None] * off[None, :]).ravel()
    k = np.repeat(np.arange(len(n)), n)
    j = np.arange(k.size) - np.repeat(np.cumsum(n) - n, n)
    return u[k] + (u[k + 1] - u[k]) * (j + 0.5) / n[k]


def span_weights(t: FloatArray, per_span: int, max_gap: float = np.inf) -> FloatArray:
    """Widths of the cells of :func:`span_samples` with the same arguments (midpoint rule)."""
    u = np.unique(t)
    n = _span_counts(u, per_span, max_gap)
    return np.repeat(np.diff(u) / n, n)


def _second_diff(n: int) -> sp.spmatrix:
    if n < 3:
        return sp.csr_matrix((0, n))
    return sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n), dtype=float)


def _penalty_diff(n: int) -> sp.spmatrix:
    """The penalty's difference rows along one direction of ``n`` coefficients: second
    differences, and first ones weighted by ``sqrt(TENSION)``."""
    rows = [_second_diff(n)]
    if n >= 2:
        rows.append(np.sqrt(TENSION) * sp.diags([-1.0, 1.0], [0, 1], shape=(n - 1, n)))
    return sp.vstack(rows).tocsr()


def curved_intervals(
    lo: float,
    hi: float,
    breaks: Sequence[float],
    h: HeightFn,
    other: FloatArray,
    axis: int,
    spacing: float,
) -> tuple[list[float], list[bool]]:
    """Where is the height curved along this axis? Each interval between breaks is probed
    with second differences of samples at most ``spacing`` apart, at every ``other``
    coordinate; a curved part that does not fill its interval gets breaks of its own at its
    ends (padded by two samples), so only it gets fine spans (a fillet strip on a wide
    plate), and so does each of several curved parts apart by more than 5 % of the
    interval. Returns the breaks (the given ones and those) and a flag per interval."""
    pts = [lo, *breaks, hi]
    out_breaks: list[float] = []
    flags: list[bool] = []
    for k, (a, b) in enumerate(zip(pts[:-1], pts[1:], strict=True)):
        n = int(np.clip(np.ceil((b - a) / spacing) + 1, 9, 4000))
        s = np.linspace(a, b, n)
        x, y = (s, other) if axis == 0 else (other, s)
        z, ok, _ = h(*np.meshgrid(x, y, indexing="ij"))
        if axis == 1:
            z, ok = z.T, ok.T
        d2 = np.diff(z, n=2, axis=0)
        ok2 = ok[:-2] & ok[1:-1] & ok[2:]
        scale = max((b - a) / (n - 1), 1e-300)
        hit = np.flatnonzero(np.any(ok2 & (np.abs(d2) > 1e-12 * scale), axis=1))
        if k > 0:
            out_breaks.append(a)
        if hit.size == 0:
            flags.append(False)
            continue
        wide = 0.05 * (b - a)  # a curved part nearly filling its interval: keep it whole
        # curved runs (padded by two samples before, four after) more than ``wide`` apart
        # are fine on their own, the flat stretch between them one span (bosses spread over
        # a plate: fine spans only across each)
        runs: list[list[float]] = []
        for part in np.split(hit, np.flatnonzero(np.diff(hit) > 1) + 1):
            ca, cb = float(s[max(part[0] - 2, 0)]), float(s[min(part[-1] + 4, n - 1)])
            if runs and ca - runs[-1][1] <= wide:
                runs[-1][1] = cb
            else:
                runs.append([ca, cb])
        if runs[0][0] - a <= wide:
            runs[0][0] = a
        if b - runs[-1][1] <= wide:
            runs[-1][1] = b
        cuts: list[tuple[float, bool]] = []  # (start, fine) of each piece of [a, b]
        for ca, cb in runs:
            if not cuts and ca > a:
                cuts.append((a, False))
            cuts.append((ca, True))
            if cb < b:
                cuts.append((cb, False))
        out_breaks += [x for x, _ in cuts[1:]]
        flags += [fine for _, fine in cuts]
    return out_breaks, flags


def fit_height(
    x_range: tuple[float, float],
    y_range: tuple[float, float],
    x_breaks: Sequence[float],
    y_breaks: Sequence[float],
    h: HeightFn,
    tol: float,
    spacing: float,
    levels: int = 5,
) -> TensorFit | None:
    """Fit ``h`` on the rectangle to ``tol`` (length unit), starting at ``spacing`` and
    halving it at most ``levels - 1`` times; the best fit is returned with its measured
    error (the caller decides whether it is good enough), None when even the first level
    has more than ``MAX_COEFFICIENTS``.

    ``x_breaks``/``y_breaks``: coordinates strictly inside the ranges where the height's
    curvature may jump (C1 knots there). See :class:`HeightFitter` to fit one height
    several times (its fits made once each).
    """
    if not spacing > 0.0:  # (a degenerate piece's radius): no fit
        return None
    return HeightFitter(x_range, y_range, x_breaks, y_breaks, h, spacing).fit(tol, levels)


class HeightFitter:
    """The fits of one height ``h`` on a rectangle (arguments as :func:`fit_height`'s,
    ``spacing > 0``), each spacing fitted once: a coarse first check (``fit(tol, 1)``) and
    the full refinement after it share their common fits and the knot placement.
    ``probes``: x and y coordinates (1-D arrays) of more lines along which the height is
    probed for curvature, besides 41 uniform ones in each direction (lines through each
    curved part: a thin strip between two uniform lines would be taken for flat)."""

    def __init__(
        self,
        x_range: tuple[float, float],
        y_range: tuple[float, float],
        x_breaks: Sequence[float],
        y_breaks: Sequence[float],
        h: HeightFn,
        spacing: float,
        probes: tuple[FloatArray, FloatArray] | None = None,
    ) -> None:
        (x0, x1), (y0, y1) = x_range, y_range
        self.x_range, self.y_range, self.h, self.spacing = x_range, y_range, h, spacing
        xb = sorted(b for b in set(x_breaks) if x0 < b < x1)
        yb = sorted(b for b in set(y_breaks) if y0 < b < y1)
        probe_x, probe_y = np.linspace(x0, x1, UNIFORM_PROBES), np.linspace(y0, y1, UNIFORM_PROBES)
        if probes is not None:
            probe_x = probe_lines(probe_x, probes[0], spacing)
            probe_y = probe_lines(probe_y, probes[1], spacing)
        self.xb, self.fine_x = curved_intervals(x0, x1, xb, h, probe_y, 0, spacing)
        self.yb, self.fine_y = curved_intervals(y0, y1, yb, h, probe_x, 1, spacing)
        self._fits: dict[tuple[float, float], TensorFit | None] = {}

    def fit_at(self, sx: float, sy: float) -> TensorFit | None:
        """The fit with spans of at most ``sx``, ``sy``; None when too large to solve."""
        key = (sx, sy)
        if key not in self._fits:
            # (counted first: a spacing near 0 would build knot vectors beyond memory)
            (x0, x1), (y0, y1) = self.x_range, self.y_range
            nx = _coefficient_count(x0, x1, self.xb, self.fine_x, sx)
            ny = _coefficient_count(y0, y1, self.yb, self.fine_y, sy)
            self._fits[key] = (
                _fit_once(self.x_range, self.y_range, self.xb, self.yb, self.fine_x,
                          self.fine_y, self.h, sx, sy)
                if nx * ny <= MAX_COEFFICIENTS
                else None
            )  # fmt: skip
        return self._fits[key]

    def coarser(self, fit: TensorFit) -> TensorFit | None:
        """The fit made with the most coefficients below ``fit``'s, None when there is none."""
        made = [f for f in self._fits.values() if f is not None and f.coef.size < fit.coef.size]
        return max(made, key=lambda f: f.coef.size, default=None)

    def fit(self, tol: float, levels: int = 5) -> TensorFit | None:
        """As :func:`fit_height` with this fitter's height and spacing."""
        return refine_both(self.fit_at, self.spacing, tol, levels)


def probe_lines(uniform: FloatArray, extra: FloatArray, spacing: float) -> FloatArray:
    """The probe coordinates ``uniform`` with ``extra`` ones (the caller's: where thin curved
    parts lie, which 41 uniform lines can all miss), one per bin of ``spacing / 2`` (wider
    where that would give more than ``MAX_PROBES``)."""
    extra = np.sort(np.asarray(extra, dtype=np.float64).ravel())
    if extra.size == 0:
        return uniform
    # one line per bin: bins of half the spacing, at most MAX_PROBES over the range (each
    # line is a row of height evaluations per interval)
    width = max(0.5 * spacing, float(uniform[-1] - uniform[0]) / MAX_PROBES)
    keep = np.concatenate([[True], np.diff(np.floor(extra / width)) > 0])
    return np.union1d(uniform, extra[keep])


def refine_both(
    fit_at: Callable[[float, float], F | None], spacing: float, tol: float, levels: int
) -> F | None:
    """:func:`refine` of a fit with a spacing per direction, ``fit_at(sx, sy)``: both
    halved together, or one alone once the first halvings show the other hardly matters
    (:func:`_one_direction`, tried after the second level)."""

    def shortcut(level: int, step: float, errors: list[float], fit: F) -> F | None:
        if level != 1 or levels <= 2:
            return None
        return _one_direction(fit_at, errors[0], fit, step, spacing / 2 ** (levels - 1), tol)

    return refine(lambda step: fit_at(step, step), spacing, tol, levels, shortcut)


def refine(
    fit_at: Callable[[float], F | None],
    spacing: float,
    tol: float,
    levels: int,
    shortcut: Callable[[int, float, list[float], F], F | None] | None = None,
) -> F | None:
    """The refinement loop shared by the fits here and in :mod:`.periodic_fit`: fits
    ``fit_at(step)`` from ``step = spacing``, halved at most ``levels - 1`` times while the
    measured ``error`` misses ``tol`` (stops when it is within, not finite (data missing
    inside the face: no knots will mend that), two halvings did not divide it by
    ``1 / STALL`` (a step or a kink in the data), or the last halving's rate cannot bring it
    near ``tol`` in the levels left (:func:`_hopeless`)); the best fit, None when even the first is
    too large to solve (``fit_at`` gave None). ``shortcut(level, step, errors, fit)`` may
    end the loop with a fit of its own after a level that missed ``tol`` (``errors``: the
    earlier levels' errors)."""
    best: F | None = None
    step = spacing
    errors: list[float] = []
    for level in range(levels):
        fit = fit_at(step)
        if fit is None:
            break  # too large to solve: keep the best one (None when even the first is)
        if best is None or fit.error < best.error:
            best = fit
        if fit.error <= tol or not np.isfinite(fit.error):
            break
        if len(errors) >= 2 and fit.error > STALL * errors[-2]:
            break
        if errors and _hopeless(fit.error, errors[-1], levels - 1 - level, tol):
            break
        if shortcut is not None:
            done = shortcut(level, step, errors, fit)
            if done is not None:
                return done
        errors.append(fit.error)
        step /= 2
    return best


def _hopeless(error: float, before: float, left: int, tol: float) -> bool:
    """Whether halving ``left`` more times at the rate ``error / before`` of the last
    halving would leave the error above ``HOPELESS x tol``."""
    rate = error / before if before > 0 else 1.0
    return error * min(rate, 1.0) ** left > HOPELESS * tol


#: A direction's halving "does not matter" when the fit with only the other direction
#: halved is within this factor of the fit with both halved.
ONE_DIRECTION = 1.5


def _one_direction(
    fit_at: Callable[[float, float], F | None],
    first: float,
    both: F,
    step: float,
    finest: float,
    tol: float,
) -> F | None:
    """Refinement along one direction only, tried once the first halving of both (``both``,
    spans ``step``; ``first`` the error at ``2 step``) missed ``tol``: a fit within ``tol``,
    or None (the caller goes on halving both directions, as without this).

    Where the error comes from curvature jumps along curves that are not knot lines (the
    variable-radius fillet's curved contact line, nearly along y), it converges only as
    ``h^2`` in the spacing across them and is near its floor along them: halving both
    directions quadruples the unknowns and the height samples for the gain of one (the
    variable-radius box: 127 x 330 unknowns where 127 x 88 give the same 1.9e-5). So when
    halving only one direction gives nearly the error of halving both (``ONE_DIRECTION``),
    that direction is halved alone, and the other once whenever a halving gains less than
    2x (its floor shows), each at most down to ``finest``; stops as the isotropic loop does
    (too large, data missing, stalled)."""
    only_x = fit_at(step, 2 * step)
    only_y = fit_at(2 * step, step)
    cands = [(f, d) for f, d in ((only_x, 0), (only_y, 1)) if f is not None]
    cands = [(f, d) for f, d in cands if f.error <= ONE_DIRECTION * both.error]
    if len(cands) != 1:
        return None  # both directions matter (or neither fit could be made)
    fit, primary = cands[0]
    if fit.error <= tol:
        return fit
    steps = [2 * step, 2 * step]
    steps[primary] = step
    # the last error reduction by halving each direction; the other one untried (0)
    ratio = [0.0, 0.0]
    ratio[primary] = fit.error / first
    errors = [first, fit.error]
    for _ in range(64):
        # the primary direction while its halvings gain 2x, else the more effective one
        d = primary if ratio[primary] <= 0.5 else int(np.argmin(ratio))
        if steps[d] / 2 < finest * (1 - 1e-9):
            d = 1 - d
            if steps[d] / 2 < finest * (1 - 1e-9):
                return None  # both at the finest spacing
        trial = list(steps)
        trial[d] /= 2
        nxt = fit_at(trial[0], trial[1])
        if nxt is None or not np.isfinite(nxt.error):
            return None
        if nxt.error <= tol:
            return nxt
        if nxt.error > STALL * errors[-2]:
            return None  # stalled
        ratio[d] = nxt.error / errors[-1]
        errors.append(nxt.error)
        steps = trial
    return None


def _fit_once(
    x_range, y_range, xb, yb, fine_x, fine_y, h: HeightFn, sx: float, sy: float
) -> TensorFit:  # type: ignore[no-untyped-def]
    tx = knot_vector(x_range[0], x_range[1], xb, fine_x, sx)
    ty = knot_vector(y_range[0], y_range[1], yb, fine_y, sy)
    step = min(sx, sy)
    # long (flat) spans sampled at most FLAT_GAP steps apart (checked at half that)
    gap = FLAT_GAP * step
    xs, ys = span_samples(tx, SAMPLES_PER_SPAN, gap), span_samples(ty, SAMPLES_PER_SPAN, gap)
    z, ok, _ = h(*np.meshgrid(xs, ys, indexing="ij"))
    bx = BSpline.design_matrix(xs, tx, DEGREE).tocsr()
    by = BSpline.design_matrix(ys, ty, DEGREE).tocsr()
    coef = solve_masked(bx, by, ok, z)
    fit = TensorFit(tx, ty, coef, 0.0, step)
    xc, yc = fit.check_samples()
    zc, okc, inside = h(*np.meshgrid(xc, yc, indexing="ij"))
    diff = fit(xc, yc) - zc
    use = inside & okc
    missing = bool(np.any(inside & ~okc))
    error = float("inf") if missing else float(np.abs(diff[use]).max(initial=0.0))
    # signed volume between fit and data over the face: midpoint rule on the check cells
    # (the samples sit at the centres of equal cells of every span)
    wx = span_weights(tx, CHECK_PER_SPAN, 0.5 * gap)
    wy = span_weights(ty, CHECK_PER_SPAN, 0.5 * gap)
    volume = float(np.sum(np.where(use, diff, 0.0) * np.outer(wx, wy)))
    return TensorFit(tx, ty, coef, error, step, volume)


def solve_masked(
    bx: sp.csr_matrix,
    by: sp.csr_matrix,
    ok: np.ndarray,
    z: FloatArray,
    prior: FloatArray | None = None,
) -> FloatArray:
    """Coefficients (nx, ny) of the penalised least-squares fit to the heights ``z`` at the
    samples of the tensor grid where ``ok`` (both (sx, sy)), ``bx`` (sx, nx) and ``by``
    (sy, ny) the design matrices of the two directions; (nx, ny, k) for values with
    components ``z`` (sx, sy, k) (points: one factorisation, k right-hand sides).
    ``prior`` (the shape of ``z``): values taken at weight ``PRIOR_WEIGHT`` at the samples
    outside ``ok`` (the supporting surface's), so that the fit returns to them away from
    its data.

    Our own solver, because the data are masked (no samples outside the face), so the
    normal matrix ``A^T A + PENALTY D^T D`` is no Kronecker product and no separable solve
    applies; but it is a sum over the samples of ``(bx_s bx_s^T) kron (by_t by_t^T)``,
    assembled here in O(samples) by two sparse products (the masked sample weights between
    the per-direction products of neighbouring basis functions) instead of forming the
    (samples x unknowns) Kronecker design matrix. With the smaller direction inner it is
    banded (half-width ``3 n_inner + 3``) and symmetric positive definite, and LAPACK's
    banded Cholesky solves it 4 - 7x faster than SuperLU's general sparse LU (0.85 s
    against 3.7 s for 127 x 330 unknowns, the variable-radius box, the same fit error;
    2.2 s against 15.7 s and half the memory for 283 x 283). SuperLU stays the fallback
    for bands too large to store or a failed factorisation."""
    nx, ny = bx.shape[1], by.shape[1]
    w, z = _weighted(ok, z, prior)
    comps = z.shape[2:]  # values with components (sx, sy, k): one factorisation, k sides
    zk = z.reshape(*ok.shape, -1)
    rhs = np.stack(
        [np.asarray(bx.T @ (w * zk[..., k]) @ by, dtype=np.float64) for k in range(zk.shape[2])],
        axis=2,
    )  # (nx, ny, k)
    inner_x = nx <= ny  # the smaller direction inner: the narrower band
    if inner_x:
        b_in, b_out, w, rhs = bx, by, w.T, rhs.transpose(1, 0, 2)  # w (sy, sx), rhs (ny, nx, k)
    else:
        b_in, b_out = by, bx
    n_in, n_out = b_in.shape[1], b_out.shape[1]
    kd = DEGREE * n_in + DEGREE
    if (kd + 1) * n_in * n_out > MAX_BAND_ENTRIES:
        coef = _solve_superlu(bx, by, ok, z, prior=prior)
    else:
        ab = _banded_normal(b_in, b_out, w)
        try:
            with _one_lapack_thread():
                factor = cholesky_banded(ab, overwrite_ab=True, check_finite=False)
                c = cho_solve_banded(
                    (factor, False), rhs.reshape(n_out * n_in, -1), check_finite=False
                )
            coef = c.reshape(n_out, n_in, -1)
            coef = coef.transpose(1, 0, 2) if inner_x else coef
            coef = coef.reshape(nx, ny, *comps)
        except LinAlgError:  # not numerically positive definite: the general solver
            coef = _solve_superlu(bx, by, ok, z, prior=prior)
    return np.asarray(coef)


def _weighted(
    ok: np.ndarray, z: FloatArray, prior: FloatArray | None
) -> tuple[FloatArray, FloatArray]:
    """The samples' weights (sx, sy) and values (the shape of ``z``): 1 and ``z`` where
    ``ok``; elsewhere 0, or ``PRIOR_WEIGHT`` and ``prior`` when given."""
    if prior is None:
        return ok.astype(np.float64), z
    mask = ok.reshape(ok.shape + (1,) * (z.ndim - ok.ndim))
    return np.where(ok, 1.0, PRIOR_WEIGHT), np.where(mask, z, prior)


@contextmanager
def _one_lapack_thread() -> Iterator[None]:
    """BLAS (scipy's and numpy's OpenBLAS) limited to one thread inside the block: the banded
    factorisation is thousands of small BLAS calls, and their thread hand-offs stalled it
    for 2 - 17 s (0.3 s single-threaded, the same otherwise) on a shared 2-core machine under
    other loads. threadpoolctl finds the libraries loaded in the process, once (its scan of
    the process's libraries cost 4 ms per fit, as much as a small fit itself)."""
    with _blas_controller().limit(limits=1, user_api="blas"):
        yield


@lru_cache(maxsize=1)
def _blas_controller() -> ThreadpoolController:
    """The process's thread pools (numpy's and scipy's BLAS are loaded with this module)."""
    return ThreadpoolController()


def _pair_products(b: sp.csr_matrix, lo: int) -> sp.csr_matrix:
    """(samples, n x (DEGREE + 1 - lo)) sparse: column ``a (DEGREE + 1 - lo) + (d - lo)``
    holds ``B_a B_{a+d}`` at each sample, for offsets ``d = lo .. DEGREE`` (zero where
    ``a + d`` is out of range). ``b``: (samples, n), DEGREE + 1 non-zeros per row."""
    s, n = b.shape
    dense = b.toarray()  # samples x n: a few hundred by a few hundred
    width = DEGREE + 1 - lo
    out = np.zeros((s, n, width))
    for k, d in enumerate(range(lo, DEGREE + 1)):
        a0, a1 = max(0, -d), min(n, n - d)
        out[:, a0:a1, k] = dense[:, a0:a1] * dense[:, a0 + d : a1 + d]
    return sp.csr_matrix(out.reshape(s, n * width))


def _banded_normal(b_in: sp.csr_matrix, b_out: sp.csr_matrix, w: FloatArray) -> FloatArray:
    """Upper banded storage (LAPACK ``ab``, half-width ``DEGREE n_in + DEGREE``) of
    ``sum_{t,s} w[t, s] (b_out_t b_out_t^T) kron (b_in_s b_in_s^T) + PENALTY D^T D``, unknown
    ``(j, a)`` at index ``j n_in + a`` (``j`` outer, ``a`` inner); ``w`` (outer samples,
    inner samples)."""
    n_in, n_out = b_in.shape[1], b_out.shape[1]
    n = n_in * n_out
    kd = DEGREE * n_in + DEGREE
    p_out = _pair_products(b_out, 0)  # (t, j, dj) for dj = 0..3: entries with l >= j
    p_in = _pair_products(b_in, -DEGREE)  # (s, a, da) for da = -3..3
    # vals[(j, dj), (a, da)] = sum_t sum_s p_out[t, (j, dj)] w[t, s] p_in[s, (a, da)]
    left = np.asarray(p_out.T @ w)  # (n_out * 4, inner samples)
    vals = np.asarray((p_in.T @ left.T).T).reshape(n_out, DEGREE + 1, n_in, 2 * DEGREE + 1)
    j = np.arange(n_out)[:, None, None, None]
    dj = np.arange(DEGREE + 1)[None, :, None, None]
    a = np.arange(n_in)[None, None, :, None]
    da = np.arange(-DEGREE, DEGREE + 1)[None, None, None, :]
    row, col = j * n_in + a, (j + dj) * n_in + a + da
    use = (j + dj < n_out) & (a + da >= 0) & (a + da < n_in) & (col >= row)
    use = np.broadcast_to(use, vals.shape)
    row, col = np.broadcast_to(row, vals.shape)[use], np.broadcast_to(col, vals.shape)[use]
    ab = np.zeros((kd + 1, n))
    ab[kd + row - col, col] = vals[use]
    # the penalty, stronger on the coefficients with little data (their own diagonal)
    mass = vals[:, 0, :, DEGREE]  # (n_out, n_in): dj = 0, da = 0
    pen = _penalty(n_in, n_out, mass.ravel()).tocoo()
    upper = pen.col >= pen.row
    np.add.at(ab, (kd + pen.row[upper] - pen.col[upper], pen.col[upper]), pen.data[upper])
    return ab


def _penalty(n_in: int, n_out: int, mass: FloatArray) -> sp.csr_matrix:
    """The penalty ``D^T W D`` (n, n), unknown ``(j, a)`` at ``j n_in + a``: the difference
    rows (:func:`_penalty_diff`) along each direction, each weighted by ``PENALTY``, or by
    ``WEAK_PENALTY`` where it touches a coefficient whose data ``mass`` (n,) (the normal
    matrix's diagonal) is below ``WEAK_MASS`` times the median of the positive ones."""
    d = sp.vstack(
        [
            sp.kron(sp.eye(n_out), _penalty_diff(n_in)),
            sp.kron(_penalty_diff(n_out), sp.eye(n_in)),
        ]
    ).tocsr()
    full = mass[mass > 0]
    ref = float(np.median(full)) if full.size else 0.0
    weak = (mass < WEAK_MASS * ref).astype(np.float64)
    touches = (abs(d) @ weak) > 0
    w = np.where(touches, WEAK_PENALTY, PENALTY)
    return (d.T @ sp.diags(w) @ d).tocsr()


def _solve_superlu(
    bx: sp.csr_matrix,
    by: sp.csr_matrix,
    ok: np.ndarray,
    z: FloatArray,
    diff_x: sp.spmatrix | None = None,
    free_y: np.ndarray | None = None,
    prior: FloatArray | None = None,
) -> FloatArray:
    """:func:`solve_masked` by the Kronecker design matrix and SuperLU (the general route).
    ``diff_x``: the penalty's difference operator in x (default :func:`_penalty_diff`; the
    periodic fit passes cyclic differences). ``z`` may carry components, (sx, sy, k): the
    coefficients are then (nx, ny, k). ``free_y`` (ny,) bool: only the coefficients of
    these y functions are solved for, the others are held at zero. ``prior``: as in
    :func:`solve_masked`."""
    nx, ny = bx.shape[1], by.shape[1]
    w, z = _weighted(ok, z, prior)
    rows = np.flatnonzero(w.ravel())
    a = sp.diags(np.sqrt(w.ravel()[rows])) @ sp.kron(bx, by, format="csr")[rows]
    if diff_x is None:  # unknown (i, j) at i ny + j: x outer
        mass = np.asarray(a.multiply(a).sum(axis=0)).ravel()
        pen = _penalty(ny, nx, mass)
    else:
        d = sp.vstack([sp.kron(diff_x, sp.eye(ny)), sp.kron(sp.eye(nx), _penalty_diff(ny))])
        pen = PENALTY * (d.T @ d)
    cols = None if free_y is None else np.flatnonzero(np.tile(np.asarray(free_y, bool), nx))
    if cols is not None:
        a, pen = a.tocsc()[:, cols], pen.tocsc()[cols][:, cols]
    normal = (a.T @ a + pen).tocsc()
    # SuperLU's default column ordering: MMD_AT_PLUS_A (symmetric) was 2.3x slower here;
    # values with components (sx, sy, k): one factorisation, k right-hand sides
    rhs = a.T @ (np.sqrt(w.ravel()[rows])[:, None] * z.reshape(ok.size, -1)[rows])
    sol = np.asarray(spsolve(normal, rhs if rhs.shape[1] > 1 else rhs.ravel()))
    if cols is not None:
        full = np.zeros((nx * ny, rhs.shape[1]))
        full[cols] = sol.reshape(len(cols), -1)
        sol = full
    return sol.reshape((nx, ny, *z.shape[2:]))
