"""``trace_axis``: the medial axis of a 4-sided region between one pair of opposite sides."""

from __future__ import annotations

import logging

import numpy as np

from medax import tolerances
from medax.axis.chords import chord_points
from medax.axis.conics import conic_axis
from medax.axis.endpoints import end_points
from medax.axis.field import DistanceField
from medax.axis.refine import fit_and_refine
from medax.axis.result import MedialAxis, WorkCounts
from medax.axis.segments import segment_axis
from medax.axis.trace import TraceStats, trace_frame, trace_paper
from medax.errors import InputError, TraceError
from medax.geometry.fitting import interpolate
from medax.geometry.region import Region, normalised_region, pair_roles

log = logging.getLogger(__name__)
METHODS = ("frame", "paper")
#: A traced point farther from the axis than this many point tolerances means the trace
#: lost the axis (a fuzzed thin non-convex quad gave 6e-3 x diagonal): refused, not returned.
#: Stalled refinements that end near the tolerance (the paper mesher's sub-traces, ~1e-7)
#: only warn.
LOST_FACTOR = 1e4
#: chords of the batch start (``medax.axis.chords``) at ``tol = 1e-6``; the cubic fit's
#: error falls like ``h^4``, so the count grows like ``tol^(-1/4)``
CHORDS = 16


def trace_axis(
    region: Region,
    pair: tuple[int, int] = (0, 2),
    tol: float = tolerances.CURVE_TOL,
    method: str = "frame",
    ratio: float = 0.5,
    point_tol: float = tolerances.POINT_TOL,
    closed_form: bool = True,
    batch: bool = True,
) -> MedialAxis:
    """Trace the medial axis of a 4-sided region between one pair of opposite sides.

    The axis is the curve ``d1 / (d1 + d2) = ratio`` (the medial axis for ``ratio = 1/2``)
    between the constraints ``A1 = S[pair[0]]`` and ``A2 = S[pair[1]]``, from B1 to B2.
    Planar regions are traced in normalised coordinates (centred, unit diagonal) so that
    regions far from the origin or in small units keep their relative accuracy.

    ``method="paper"`` reproduces the paper: direction ``e1 + e2``, step = shortest side / 5,
    the ``|d1 - d2| / 2n`` correction to ``0.99 < d1/d2 < 1.01``, a B-spline through the
    points without refinement.

    Parameters
    ----------
    region : Region
        The region ([Region][medax.geometry.region.Region]), planar or on a surface.
    pair : tuple of int
        The constraint sides, ``(0, 2)`` or ``(1, 3)``.
    tol : float
        Bound on the fitted B-spline's equidistance error, relative to the region's diagonal.
    method : str
        ``"frame"`` (default) or ``"paper"``.
    ratio : float
        Distance ratio ``d1 / (d1 + d2)`` of the traced curve, in (0, 1).
    point_tol : float
        Bound on every traced point's equidistance error, relative to the diagonal.
    closed_form : bool
        With ``method="frame"`` and ``ratio = 1/2``, two line-segment constraints of a planar
        region get the exact axis instead (lines and parabolas, an exact quadratic B-spline:
        ``medax.axis.segments``); ``False`` always traces.
    batch : bool
        A planar region's first points come in one batch (the roots of the field along B1,
        B2 and chords across the region, ``medax.axis.chords``) instead of the step-by-step
        trace, where that applies (else the trace).

    Returns
    -------
    MedialAxis
        The axis points from B1 to B2, their distances and the fitted spline
        ([MedialAxis][medax.axis.result.MedialAxis]).

    Raises
    ------
    InputError
        Unknown ``method``, ``ratio`` outside (0, 1) or a tolerance that is not positive.
    RegionError
        ``pair`` is neither ``(0, 2)`` nor ``(1, 3)``.
    TraceError
        The trace could not follow the axis (points off it by more than ``1e4 x point_tol``,
        for a region too thin or bent at a reflex corner).
    """
    if method not in METHODS:
        raise InputError(f"unknown method '{method}' (known: {', '.join(METHODS)})")
    if not 0.0 < ratio < 1.0:
        raise InputError(f"ratio must be in (0, 1), got {ratio}")
    if not tol > 0.0 or not point_tol > 0.0:
        raise InputError(f"tolerances must be positive, got tol={tol}, point_tol={point_tol}")
    roles = pair_roles(pair)
    if closed_form and method == "frame" and ratio == 0.5:
        ij = (int(pair[0]), int(pair[1]))
        exact = segment_axis(region, ij, roles, tol, point_tol)
        if exact is None:
            exact = conic_axis(region, ij, roles, tol, point_tol)
        if exact is not None:
            return exact
    work, offset, scale = normalised_region(region)
    field = DistanceField(work, roles, ratio)
    diag = work.diagonal
    tol_pt, tol_cv = point_tol * diag, tol * diag
    b1, b2 = work.sides[roles.b1], work.sides[roles.b2]
    stats = TraceStats()
    fit = None
    if method == "frame" and batch and work.embedding.is_identity:
        n_chords = max(4, int(np.ceil(CHORDS * (1e-6 / tol) ** 0.25)))
        first = chord_points(field, b1, b2, n_chords, tol_pt)
        if first is not None:
            fit = fit_and_refine(field, first.points, tol_pt, tol_cv, first.sample, True)
            s0, s1 = first.t_start, first.t_end
            stats.corrector_iterations += first.iterations + fit.corrector_iterations
            if not fit.curve_error <= tol_cv:  # the refinement stalled: trace instead
                log.debug("%s pair %s: batch start did not converge", region.name, pair)
                fit = None
    if fit is None:
        (s0, s1), (p0, p1) = end_points(
            field, (b1, b2), (f"side {roles.b1} (B1)", f"side {roles.b2} (B2)")
        )
    if method == "frame":
        if fit is None:
            shortest = float(work.side_lengths().min())
            # the paper's first step (shortest side / 5), but at most half the chord: on a
            # thin non-convex quad the axis was shorter than one such step and the trace
            # was lost
            pts = trace_frame(
                field, p0, p1, h0=min(shortest / 5.0, 0.5 * float(np.linalg.norm(p1 - p0))),
                h_min=1e-7 * diag, h_max=0.1 * diag,
                tol=tol_pt, stats=stats,
            )  # fmt: skip
            fit = fit_and_refine(field, pts, tol_pt, tol_cv)
            stats.corrector_iterations += fit.corrector_iterations
        pts, s, spline = fit.points, fit.sample, fit.spline
        curve_error, rounds = fit.curve_error, fit.rounds
    else:
        shortest = float(work.side_lengths().min())
        b2_curve = work.space_curve(roles.b2)
        pts = trace_paper(
            field, p0, p1, shortest / 5.0,
            lambda q: b2_curve.closest(work.embedding.evaluate(q)).distance, stats,
        )  # fmt: skip
        s = field(pts)
        spline, u = interpolate(pts, (), degree=min(3, len(pts) - 1))
        uu = np.linspace(0.0, 1.0, 10 * (len(pts) - 1) + 1)
        curve_error, rounds = float(field(spline.evaluate(uu)).error.max()), 0
    point_error = float(s.error.max())
    if method == "frame" and point_error > LOST_FACTOR * tol_pt:
        raise TraceError(
            f"{region.name} pair {tuple(pair)}: the trace lost the axis (points off it by "
            f"{point_error / diag:.2e} x diagonal, guarantee {point_tol:g}); the region is "
            "probably too thin or bent at a reflex corner for the tracer"
        )
    if method == "frame" and curve_error > tol_cv:
        log.warning(
            "%s pair %s: fitted curve error %.3g exceeds the tolerance %.3g",
            region.name, pair, curve_error / diag, tol,
        )  # fmt: skip
    counts = WorkCounts(
        points=len(pts),
        predictor_steps=stats.steps,
        corrector_iterations=stats.corrector_iterations,
        distance_evaluations=field.evaluations,
        refinements=rounds,
    )
    # back to the caller's coordinates (identity for surface regions)
    pts_out = pts * scale + offset
    sx = s.x * scale + offset if work.embedding.is_identity else s.x.copy()
    q1 = s.q1 * scale + offset if work.embedding.is_identity else s.q1.copy()
    q2 = s.q2 * scale + offset if work.embedding.is_identity else s.q2.copy()
    spline_out = (
        spline.transformed(-offset / scale, 1.0 / scale)
        if scale != 1.0 or np.any(offset)
        else spline
    )
    return MedialAxis(
        region=region, pair=(int(pair[0]), int(pair[1])), roles=roles, method=method,
        points=pts_out, space_points=sx, foot1=q1, foot2=q2, d1=s.d1 * scale, d2=s.d2 * scale,
        spline=spline_out, t_start=s0, t_end=s1,
        max_point_error=point_error * scale, max_curve_error=curve_error * scale,
        tol=tol, counts=counts,
    )  # fmt: skip
