"""Interpolating B-splines through ordered points, with optional C0 breaks."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.interpolate import BarycentricInterpolator, make_interp_spline
from scipy.linalg import get_lapack_funcs

from medax.errors import CurveError
from medax.geometry._rows import step_norms
from medax.geometry._types import FloatArray
from medax.geometry.basis_kernel import span_basis_rows
from medax.geometry.bspline import BSpline

#: LAPACK's banded solver (double precision)
_GBSV = get_lapack_funcs(("gbsv",), (np.zeros((1, 1)),))[0]


def chord_parameters(points: FloatArray) -> FloatArray:
    """Normalised cumulative chord length of ``points`` (n, dim), shape ``(n,)``."""
    seg = step_norms(points)
    u = np.concatenate(([0.0], np.cumsum(seg)))
    return u / u[-1]


def interpolate(
    points: FloatArray, breaks: Sequence[int] = (), degree: int = 3
) -> tuple[BSpline, FloatArray]:
    """Clamped B-spline through ``points`` (n, dim) at chord-length parameters.

    ``breaks`` are indices of interior points where the curve may turn (a kink): there the
    knot multiplicity is ``degree``, so the spline is only C0. Each piece between breaks is
    a not-a-knot interpolant; a piece of ``m <= degree`` points (at least 2) is the
    polynomial of degree ``m - 1`` through them, raised to ``degree`` (e.g. a 3-point
    piece between close breaks of a traced axis is a parabola). Returns the spline
    (parameter domain [0, 1]) and the parameters ``u`` (n,) of the points on it.
    """
    pts = np.asarray(points, dtype=np.float64)
    u = chord_parameters(pts)
    du = u[1:] - u[:-1]
    if not (du > 0.0).all():
        i = int(np.argmin(du))
        raise CurveError(f"cannot fit a spline: points {i} and {i + 1} of {len(pts)} coincide")
    cuts = [0, *sorted(int(b) for b in breaks), len(pts) - 1]
    gaps = np.diff(cuts)
    if (gaps < 1).any():
        raise CurveError(f"cannot fit a spline: breaks {sorted(breaks)} of {len(pts)} points")
    u_all = u
    if (gaps < degree).any():
        u, pts, cuts = _fill_short(u, pts, cuts, degree)
    if degree % 2:
        return _interpolate_odd(pts, u, cuts, degree), u_all
    knots: list[FloatArray] = []
    ctrl: list[FloatArray] = []
    for j, (a, b) in enumerate(zip(cuts[:-1], cuts[1:], strict=True)):
        spl = make_interp_spline(u[a : b + 1], pts[a : b + 1], k=degree)
        t, c = np.asarray(spl.t), np.asarray(spl.c)
        if j == 0:
            knots.append(t[: len(t) - degree - 1])  # all but the closing knots
            ctrl.append(c)
        else:
            knots.append(t[degree + 1 : len(t) - degree - 1])
            ctrl.append(c[1:])
        if j == len(cuts) - 2:
            knots.append(t[len(t) - degree - 1 :])
        else:
            knots.append(np.full(degree, u[b]))
    # the loop appended the junction knots with multiplicity `degree` (C0 joints)
    kn = np.concatenate(knots)
    cp = np.concatenate(ctrl)
    return BSpline(cp, degree, kn), u_all


def _fill_short(
    u: FloatArray, pts: FloatArray, cuts: list[int], degree: int
) -> tuple[FloatArray, FloatArray, list[int]]:
    """Pieces between ``cuts`` with fewer than ``degree + 1`` points get points of their own
    lower-degree interpolating polynomial (in ``u``) at the middles of their widest gaps,
    until they have ``degree + 1``: the not-a-knot interpolant of those is that polynomial.
    Returns the parameters, points and cut indices with them inserted."""
    at: list[np.ndarray] = []
    sites: list[FloatArray] = []
    values: list[FloatArray] = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        if b - a >= degree:
            continue
        uu = u[a : b + 1].copy()
        extra: list[float] = []
        for _ in range(degree - (b - a)):
            grid = np.sort(np.concatenate((uu, extra)))
            i = int(np.argmax(np.diff(grid)))
            extra.append(0.5 * (grid[i] + grid[i + 1]))
        e = np.sort(np.array(extra))
        at.append(np.searchsorted(u, e))
        sites.append(e)
        values.append(BarycentricInterpolator(uu, pts[a : b + 1])(e))
    pos = np.concatenate(at)
    u_new = np.insert(u, pos, np.concatenate(sites))
    p_new = np.insert(pts, pos, np.concatenate(values), axis=0)
    shift = np.searchsorted(np.sort(pos), np.asarray(cuts), side="right")
    return u_new, p_new, [int(c) for c in np.asarray(cuts) + shift]


def _interpolate_odd(pts: FloatArray, u: FloatArray, cuts: list[int], degree: int) -> BSpline:
    """:func:`interpolate` for odd degrees in one solve: one knot vector for all pieces,
    each piece's not-a-knot interior knots (its data sites but the ``(degree - 1) / 2``
    next to each end) and ``degree`` knots at each break (a C0 joint interpolating there),
    so the pieces decouple and one banded solve fits them all (the same spline as piece by
    piece)."""
    half = (degree - 1) // 2
    # each site's multiplicity as a knot: 1 inside the pieces, 0 within ``half`` of a cut
    mult = np.ones(u.size, dtype=np.int64)
    c = np.asarray(cuts, dtype=np.int64)
    mult[np.clip((c[:, None] + np.arange(-half, half + 1)).ravel(), 0, u.size - 1)] = 0
    mult[c] = degree
    mult[[0, -1]] = degree + 1
    kn = np.repeat(u, mult)
    return BSpline.on_unit_knots(_collocation_solve(u, pts, kn, degree), degree, kn)


def _collocation_solve(u: FloatArray, pts: FloatArray, kn: FloatArray, k: int) -> FloatArray:
    """Control points (n, dim) of the degree-``k`` spline on knots ``kn`` (n + k + 1,)
    through ``pts`` (n, dim) at the sites ``u`` (n,): the banded collocation system (its
    basis values from the compiled Cox-de Boor recursion) solved by LAPACK's ``gbsv``, as
    scipy's ``make_interp_spline`` does, without its argument handling."""
    n = u.size
    span, values, _ = span_basis_rows(kn, np.zeros((0, k + 1, k + 1)), k, False, u)
    cols = span[:, None] + np.arange(-k, 1)  # (n, k + 1): the non-zero basis functions
    ab = np.zeros((3 * k + 1, n), order="F")  # LAPACK band storage, kl = ku = k
    ab[2 * k + np.arange(n)[:, None] - cols, cols] = values
    _, _, c, info = _GBSV(k, k, ab, np.array(pts, order="F"), overwrite_ab=True, overwrite_b=True)
    if info != 0:
        raise CurveError(f"cannot fit a spline: singular collocation system (info {info})")
    return np.ascontiguousarray(c)
