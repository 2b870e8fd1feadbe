"""Fit a B-spline through the axis points and refine until the curve itself is on the axis.

The fitted curve is checked between the points (10 samples per interval); where it strays
beyond the tolerance, the interval's midpoint on the curve is corrected onto the axis and
inserted, all such points of a round at once. Kinks of the axis (where a foot point jumps
between distant parts of a wavy constraint) are located by Newton, all of a round in one
batch (:mod:`medax.axis.kinks`), and become C0 breaks, inserted with the field of their
global check; short pieces between breaks are split in one insertion, and points inserted
after a check start from its samples (their field measured there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from medax.axis.correct import correct_newton
from medax.axis.field import DistanceField, FieldSample
from medax.axis.kinks import KINK_SPEED, KINK_TRY, kink_intervals2, locate_kinks
from medax.axis.transitions import locate_transitions, transition_intervals, vertex_crossings
from medax.geometry._rows import row_norms
from medax.geometry._types import FloatArray
from medax.geometry.bspline import BSpline
from medax.geometry.fitting import interpolate

#: samples per interval when checking the fitted curve ("10x denser")
CHECK_SAMPLES = 10
#: rounds that check the fitted curve (and refine it)
MAX_ROUNDS = 30
#: rounds that only add breaks or points to short pieces between breaks: each adds points,
#: and an axis has as many breaks as its constraints have vertices and kinks (a 270-degree
#: channel of 361-vertex polylines: 876 breaks, 48 such rounds)
MAX_FEATURE_ROUNDS = 200
#: intervals shorter than this (x diagonal) are not refined further
MIN_INTERVAL = 1e-7
#: refinement stops when the error, still above twice the target, has not dropped by 10 %
#: over this many rounds (a singularity no break describes)
STALL_ROUNDS = 4
#: the checks aim at this fraction of the tolerance: between two check samples the error can
#: exceed the sampled maximum by a few percent (1.0047e-6 seen at tol 1e-6 on a random quad)
CHECK_MARGIN = 0.75
DEGREE = 3


@dataclass
class Fitted:
    """Refined points (n, 2), their field sample, kink indices, spline and measured errors."""

    points: FloatArray
    sample: FieldSample
    breaks: list[int]
    spline: BSpline
    u: FloatArray
    curve_error: float
    rounds: int
    corrector_iterations: int


def fit_and_refine(
    field: DistanceField,
    points: FloatArray,
    tol_point: float,
    tol_curve: float,
    sample: FieldSample | None = None,
    both_kinks: bool = False,
) -> Fitted:
    """Refine ``points`` (n, 2) (on the axis, ordered B1 -> B2, ends exact) until the fitted
    B-spline's equidistance error is within ``CHECK_MARGIN * tol_curve`` (absolute) at every
    check sample, so within ``tol_curve`` between them. ``sample`` is the field at
    ``points`` when the caller has it; ``both_kinks`` looks for a kink of each constraint
    where both feet jump in one interval (sparse first points, e.g. the batch start's),
    else only for that of the foot that moves more."""
    target = CHECK_MARGIN * tol_curve
    scale = field.region.diagonal
    pts = np.asarray(points, dtype=np.float64)
    s = field(pts) if sample is None else sample
    breaks: set[int] = set()  # indices into pts of C0 break points
    tried: set[int] = set()  # kink intervals Newton did not confirm (refined instead)
    # transitions tried, keyed by their interval's end points (kept while it is unchanged)
    tried_t: set[tuple[bytes, int, float, int]] = set()
    vertices = (field.a1.breaks(), field.a2.breaks())  # corners of the constraints
    iters = 0
    curve_error = np.inf
    spline: BSpline | None = None
    u = np.zeros(0)
    rounds = 0
    checked: _Checked | None = None
    history: list[float] = []  # curve error per checked round
    checks = features = 0
    while checks < MAX_ROUNDS and features < MAX_FEATURE_ROUNDS:
        rounds = checks + features + 1
        # 1. pieces between breaks need DEGREE + 1 points: where short, all of the piece's
        # intervals split evenly along their chords into enough pieces, in one insertion
        # (where the corrected points leave their interval, the piece stays short and is
        # fitted by a lower-degree polynomial: see interpolate)
        cuts = np.array([0, *sorted(breaks), len(pts) - 1])
        span = cuts[1:] - cuts[:-1]
        if (span < DEGREE).any():
            short = np.flatnonzero(span < DEGREE)
            intervals = np.concatenate([np.arange(cuts[j], cuts[j + 1]) for j in short])
            parts = np.repeat(-(-DEGREE // span[short]), span[short])  # ceil(DEGREE / span)
            n_before = len(pts)
            pts, s, breaks, it = _insert(
                field, pts, s, breaks, intervals, None, None, tol_point, parts
            )
            iters += it
            if len(pts) > n_before:
                features += 1
                continue
        # 2. breaks where the axis is not smooth: kinks (a foot jumps between branches of a
        # constraint) and transitions (a foot reaches its constraint's end)
        jumps, tries = kink_intervals2(s, scale, (KINK_SPEED, KINK_TRY))
        kinks = [
            i for i in tries.tolist() if i not in tried and i not in breaks and i + 1 not in breaks
        ]
        found, kink_s = locate_kinks(
            field, s, pts, kinks, tol_point, speed=KINK_TRY if both_kinks else np.inf
        )
        tried |= set(kinks)
        kinked = {i for i, _ in found}
        trans = [
            f
            for f in transition_intervals(s, vertices)
            if _key(pts, f) not in tried_t
            and f[0] not in breaks
            and f[0] + 1 not in breaks
            and f[0] not in jumps  # a foot jumping onto an end is a kink, not a transition
            and f[0] not in kinked  # (one round's breaks: the kinks there)
        ]
        # feet that cross vertices between two points (none resting on one): transitions
        # or kinks at those vertices, several per interval
        cross = [
            f
            for f in vertex_crossings(field, s, vertices)
            if _key(pts, f) not in tried_t and f[0] not in jumps and f[0] not in kinked
        ]
        cand: list[tuple[int, FloatArray, int]] = []
        trans_s = FieldSample.empty(s.dim)
        if trans or cross:
            tried_t |= {_key(pts, f) for f in trans + cross}
            ti, tq, trans_s, rows_t = locate_transitions(field, pts, s, trans + cross, tol_point)
            # new breaks: one transition per interval (found from a foot on a vertex) and
            # the vertex crossings, and the kinks, in order along each interval; each with
            # its row in the field samples of both (transitions, then kinks)
            at = rows_t < len(trans)
            one = {int(ti[j]): int(j) for j in np.flatnonzero(at)}  # one per interval
            cand = [(i, tq[j], j) for i, j in one.items()] + [
                (int(ti[j]), tq[j], int(j)) for j in np.flatnonzero(~at)
            ]
        nt = len(trans_s)
        cand += [(i, q, nt + k) for k, (i, q) in enumerate(found)]
        new_breaks = _ordered(pts, cand, 1e-12 * scale) if cand else []
        if new_breaks:
            idx = np.array([b[0] for b in new_breaks], dtype=np.int64)
            kp = np.array([b[1] for b in new_breaks])
            rows = np.array([b[2] for b in new_breaks], dtype=np.int64)
            # a break found on an existing point (e.g. a foot reaching its constraint's end
            # exactly at B1 or B2) is not inserted again: interior points become breaks
            on = _existing(pts, idx, kp, 1e-12 * scale)
            fresh = on < 0
            marked = {int(j) for j in on[~fresh] if 0 < j < len(pts) - 1} - breaks
            if np.any(fresh):
                breaks |= marked
                # (the field at the breaks is that of their global check: no evaluation)
                ks = FieldSample.concat([trans_s, kink_s]).take(rows[fresh])
                pts, s, breaks = _insert_at(pts, s, breaks, idx[fresh], kp[fresh], ks, True)
            elif marked:
                breaks |= marked
            else:
                features += 1
                continue  # nothing new: the tried sets keep these intervals from coming back
            tried = set()
            features += 1
            continue
        checks += 1
        spline, u = interpolate(pts, sorted(breaks), DEGREE)
        # 3. check the curve between the points
        err, checked = _check(field, spline, u, pts, checked, target)
        curve_error = float(err.max())
        bad = np.nonzero(err > target)[0]
        # intervals already shorter than the tracer's smallest step are not split again: no
        # smooth piece needs them, and at a singularity that no break describes (e.g. the
        # axis through a focal point of a constraint) splitting would never end
        chord = row_norms(pts[bad + 1] - pts[bad])
        bad = bad[chord > MIN_INTERVAL * scale]
        history.append(curve_error)
        stalled = False
        if len(history) > STALL_ROUNDS:
            err0 = history[-1 - STALL_ROUNDS]
            stalled = curve_error > 0.9 * err0 and curve_error > 2.0 * target
        if bad.size == 0 or stalled:
            break
        # cubic interpolation error ~ h^4: split each bad interval into enough pieces
        pieces = np.minimum(np.maximum(np.ceil(1.3 * (err[bad] / target) ** 0.25), 2), 8)
        pieces = pieces.astype(np.int64)
        pts, s, breaks, it = _insert(
            field, pts, s, breaks, bad, spline, u, tol_point, pieces, checked
        )
        iters += it
    if spline is None or len(u) != len(pts):  # rounds ran out while inserting breaks
        spline, u = interpolate(pts, sorted(breaks), DEGREE)
        err, _ = _check(field, spline, u, pts, None, target)  # the error of this spline
        curve_error = float(err.max())
    return Fitted(pts, s, sorted(breaks), spline, u, curve_error, rounds, iters)


def _ordered(
    pts: FloatArray, cand: list[tuple[int, FloatArray, int]], eps: float
) -> list[tuple[int, FloatArray, int]]:
    """New break points ``(interval, point, row)`` sorted along their intervals (by the
    projection on the chord), one of any that coincide (within ``eps``)."""
    if not cand:
        return []
    i = np.array([c[0] for c in cand], dtype=np.int64)
    q = np.array([c[1] for c in cand])
    ab = pts[i + 1] - pts[i]
    along = np.einsum("ij,ij->i", q - pts[i], ab) / np.einsum("ij,ij->i", ab, ab)
    order = np.lexsort((along, i))
    out: list[tuple[int, FloatArray, int]] = []
    for j in order.tolist():
        if out and out[-1][0] == i[j] and np.linalg.norm(q[j] - out[-1][1]) <= eps:
            continue
        out.append(cand[j])
    return out


def _key(pts: FloatArray, f: tuple[int, int, float, int]) -> tuple[bytes, int, float, int]:
    """A transition interval ``f`` keyed by its end points, which survive re-indexing."""
    return (pts[f[0] : f[0] + 2].tobytes(), f[1], f[2], f[3])


def _existing(pts: FloatArray, idx: np.ndarray, q: FloatArray, eps: float) -> np.ndarray:
    """For new points ``q`` (k, 2) in intervals ``idx`` (k,): the index of the interval end
    they coincide with (within ``eps``), or -1."""
    lo = np.linalg.norm(q - pts[idx], axis=1) <= eps
    hi = np.linalg.norm(q - pts[idx + 1], axis=1) <= eps
    return np.where(lo, idx, np.where(hi, idx + 1, -1))


@dataclass
class _Checked:
    """Check samples of the last round: per-interval endpoint keys (:func:`_ends`, sorted)
    and the intervals they key (``order``), space points (n_int, m, dim) and equidistance
    errors (n_int, m) (measured or bounded); the parameter points (n_int, m, 2), and the
    field ``sample`` at the measured ones, row ``rows[i, j]`` ((n_int, m), -1 where only
    bounded)."""

    keys: np.ndarray
    order: np.ndarray
    x: FloatArray
    err: FloatArray
    y: FloatArray
    rows: np.ndarray
    sample: FieldSample


def _check(
    field: DistanceField,
    spline: BSpline,
    u: FloatArray,
    pts: FloatArray,
    prev: _Checked | None,
    tol_curve: float,
) -> tuple[FloatArray, _Checked]:
    """Equidistance error of ``spline`` at ``CHECK_SAMPLES - 1`` samples inside each interval
    of ``u`` (n,), max per interval (n - 1,).

    ``2|g|`` is 2-Lipschitz in space (each distance is 1-Lipschitz), so where an interval
    between the same two points was checked in the previous round, ``err_old + 2 |x - x_old|``
    bounds the new error at each sample; samples whose bound is within half the tolerance
    are not re-measured (after a refit only the intervals near inserted points move by more
    than round-off), the others are measured with the field.
    """
    frac = np.arange(1, CHECK_SAMPLES) / CHECK_SAMPLES
    m = CHECK_SAMPLES - 1
    uu = (u[:-1, None] + frac[None, :] * np.diff(u)[:, None]).ravel()
    y = spline.evaluate_once(uu)
    x = field.region.embedding.evaluate(y).reshape(len(u) - 1, m, -1)
    ends = _ends(pts)
    err = np.full((len(u) - 1, m), np.inf)
    if prev is not None:  # the intervals whose two end points were checked last round
        at = np.minimum(np.searchsorted(prev.keys, ends), prev.keys.size - 1)
        same = np.flatnonzero(prev.keys[at] == ends)
        j = prev.order[at[same]]
        d = x[same] - prev.x[j]
        err[same] = prev.err[j] + 2.0 * np.sqrt(np.add.reduce(d * d, axis=2))
    need = ~(err <= 0.5 * tol_curve)
    y = y.reshape(len(u) - 1, m, 2)
    rows = np.full(need.shape, -1, dtype=np.int64)
    rows[need] = np.arange(int(need.sum()))
    measured = field(y[need]) if np.any(need) else FieldSample.empty(x.shape[2])
    err[need] = measured.error
    order = np.argsort(ends)
    return err.max(axis=1), _Checked(ends[order], order, x, err, y, rows, measured)


def _ends(pts: FloatArray) -> np.ndarray:
    """Keys (n - 1,) of the intervals of ``pts`` (n, dim): the bytes of their two end
    points (opaque ``void`` items, sortable and exact; they survive re-indexing)."""
    both = np.concatenate((pts[:-1], pts[1:]), axis=1)  # (n - 1, 2 dim), contiguous
    return both.view(np.dtype((np.void, both.shape[1] * both.itemsize))).ravel()


def _insert(
    field: DistanceField,
    pts: FloatArray,
    s: FieldSample,
    breaks: set[int],
    intervals: np.ndarray,
    spline: BSpline | None,
    u: FloatArray | None,
    tol: float,
    pieces: np.ndarray | None = None,
    checked: _Checked | None = None,
) -> tuple[FloatArray, FieldSample, set[int], int]:
    """Split each interval into ``pieces`` (default 2) by corrected points taken on the
    spline (or the chord when there is no spline yet). With the spline's ``checked``
    samples, the points start from the check samples nearest the even split (``pieces <=
    CHECK_SAMPLES`` keeps them distinct) and Newton from their field where measured."""
    if pieces is None:
        pieces = np.full(len(intervals), 2, dtype=np.int64)
    rep = pieces - 1
    intervals = np.repeat(intervals, rep)
    frac = np.concatenate([np.arange(1, m) / m for m in pieces])
    start: FieldSample | None = None
    if checked is not None:
        j = np.rint(frac * CHECK_SAMPLES).astype(np.int64) - 1  # sample j of the interval
        guess = checked.y[intervals, j]
        row = checked.rows[intervals, j]
        known = row >= 0
        if known.all():
            start = checked.sample.take(row)
        else:  # the rest evaluated, all in the guesses' order
            rest = FieldSample.concat([checked.sample.take(row[known]), field(guess[~known])])
            at = np.empty(len(row), dtype=np.int64)
            at[known] = np.arange(int(known.sum()))
            at[~known] = int(known.sum()) + np.arange(int((~known).sum()))
            start = rest.take(at)
    elif spline is not None and u is not None:
        guess = spline.evaluate(u[intervals] + frac * (u[intervals + 1] - u[intervals]))
    else:
        guess = pts[intervals] + frac[:, None] * (pts[intervals + 1] - pts[intervals])
    new, sn, _, it = correct_newton(field, guess, tol, sample=start)
    # a corrected point that left its interval (slid onto a neighbour near a singularity)
    # would break the order of the points: it is dropped
    a, b = pts[intervals], pts[intervals + 1]
    along = np.einsum("ij,ij->i", new - a, b - a) / np.einsum("ij,ij->i", b - a, b - a)
    keep = np.isfinite(along) & (along > 1e-9) & (along < 1.0 - 1e-9)
    same = intervals[1:] == intervals[:-1]
    keep[1:] &= ~same | (along[1:] > along[:-1] + 1e-9)
    if not np.all(keep):
        intervals, new, sn = intervals[keep], new[keep], sn.take(keep)
    pts, s, breaks = _insert_at(pts, s, breaks, intervals, new, sn, as_break=False)
    return pts, s, breaks, it


def _insert_at(
    pts: FloatArray,
    s: FieldSample,
    breaks: set[int],
    intervals: np.ndarray,
    new: FloatArray,
    sn: FieldSample,
    as_break: bool,
) -> tuple[FloatArray, FieldSample, set[int]]:
    """Insert ``new`` points after indices ``intervals``, keeping the order and re-indexing
    the break set."""
    n = len(pts)
    order = np.argsort(np.concatenate((np.arange(n, dtype=float), intervals + 0.5)), kind="stable")
    # several points in one interval keep their given order (stable sort, ascending input)
    pts = np.concatenate((pts, new))[order]
    s = FieldSample(np.concatenate((s.data, sn.data))[order], s.dim)
    pos = np.empty(n + len(intervals), dtype=np.int64)
    pos[order] = np.arange(n + len(intervals))
    new_breaks = {int(pos[b]) for b in breaks}
    if as_break:
        new_breaks |= {int(pos[n + j]) for j in range(len(intervals))}
    return pts, s, new_breaks
