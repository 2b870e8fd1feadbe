"""The exact medial axis of two constraints that are lines or circular arcs, in closed form.

Each constraint offers three sites: its interior (a line or a circle) and its two end
points. Between transitions (where a foot point reaches or leaves an end of its constraint)
each foot stays on one site, and the axis is the bisector of two sites: a conic (a parabola
for a line and a circle or a point; a conic with foci at the centres for two circles, a
circle and a point or two points). Every piece is exactly a rational quadratic Bezier curve,
so the whole axis is a rational quadratic B-spline, at any tolerance.

Points are explicit. A point of the axis whose foot on constraint ``A`` is interior at
``q = A(t)`` lies on the normal ray ``q + d n(t)`` where the distance to the other
constraint equals ``d``; ``d -> dist(q + d n) - d`` is non-increasing, so that root is
unique, and for each site of the other constraint it solves a linear equation in ``d``: the
consistent root (checked with the other constraint's global ``closest``) is the smallest.
Transitions are such points on the normal lines at the ends of the constraints. Each piece
is parametrised by the foot of a constraint that moves on it and split into sub-arcs
turning at most ``MAX_TURN``; a sub-arc's middle control point is the crossing of the axis
tangents at its ends, its weight follows from one more axis point inside it.

The ends are the tracer's exact end points on ``B1`` and ``B2``. Errors are measured on the
result (points, and the spline 10x denser) with the constraints' own ``closest``; anything
unexpected (a foot that goes back, a degenerate piece, a measured error above the point
tolerance) returns ``None`` and the caller traces instead. Work is done in the normalised
region (unit diagonal, centred), as the tracer's.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from medax.axis.endpoints import end_points
from medax.axis.field import DistanceField
from medax.axis.result import MedialAxis, WorkCounts
from medax.errors import TraceError
from medax.geometry._types import FloatArray
from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve
from medax.geometry.line import Line
from medax.geometry.region import PairRoles, Region, normalised_region

log = logging.getLogger(__name__)

#: a foot parameter this close to 0 or 1 sits at that end; also the relative slack (unit
#: diagonal) on roots and duplicate points
EPS = 1e-12
#: largest tangent turn of one rational quadratic sub-arc (radians); pieces are split
#: aiming at two thirds of it (uniform foot steps do not turn uniformly)
MAX_TURN = math.pi / 3
#: output point intervals per sub-arc (the middle point gives the weight)
PER_ARC = 4
#: check samples per interval between points (the tracer's "10x denser")
CHECK_SAMPLES = 10

Sides = tuple[Line | Arc, Line | Arc]


def _normals(curve: Curve, t: FloatArray) -> FloatArray:
    """Unit left normals (n, 2) of ``curve`` at ``t`` (n,): into a counter-clockwise region."""
    d = curve.derivative(t)
    n = np.column_stack((-d[:, 1], d[:, 0]))
    return n / np.linalg.norm(n, axis=1)[:, None]


def _site_roots(other: Line | Arc, q: FloatArray, n: FloatArray) -> FloatArray:
    """Candidate ``d`` (m, 3) with ``dist(q + d n) = d`` to the sites of ``other`` (its start,
    its end, its interior); ``nan`` where a site has no positive root."""
    v = np.stack((other.start, other.end))[None, :, :] - q[:, None, :]  # (m, 2, 2)
    den = 2.0 * np.einsum("mkj,mj->mk", v, n)
    vv = np.einsum("mkj,mkj->mk", v, v)
    if isinstance(other, Line):  # the line's inward normal distance m . (x - a) = d
        u = (other.b - other.a) / np.linalg.norm(other.b - other.a)
        m = np.array([-u[1], u[0]])
        den_i = 1.0 - n @ m
        num_i = (q - other.a) @ m
    else:  # the circle: rho = r + sigma d, sigma = +1 where the region is outside it
        sigma = -math.copysign(1.0, other.sweep)
        w = q - other.center
        den_i = 2.0 * (sigma * other.radius - np.einsum("mj,mj->m", n, w))
        num_i = np.einsum("mj,mj->m", w, w) - other.radius**2
    num = np.column_stack((vv, num_i))
    den = np.column_stack((den, den_i))
    with np.errstate(divide="ignore", invalid="ignore"):
        d = num / den
    # no sign condition on den: a root that solves the squared equation but not the
    # distance itself fails the caller's consistency check
    return np.where((d > 0.0) & np.isfinite(d), d, np.nan)


def _on_rays(drive: Curve, other: Line | Arc, t: FloatArray) -> FloatArray:
    """Axis points (m, 2) whose foot on ``drive`` is ``drive(t)`` (t (m,)); ``nan`` rows where
    no site root is consistent."""
    q, n = drive.evaluate(t), _normals(drive, t)
    d = _site_roots(other, q, n)
    ok = np.isfinite(d)
    x = q[:, None, :] + np.where(ok, d, 0.0)[:, :, None] * n[:, None, :]
    dist = other.closest(x.reshape(-1, 2)).distance.reshape(d.shape)
    ok &= np.abs(dist - d) <= EPS * (1.0 + np.where(ok, d, 0.0))
    best = np.min(np.where(ok, d, np.inf), axis=1)
    best = np.where(np.isfinite(best), best, np.nan)
    return q + best[:, None] * n


def _tangents(a: Sides, x: FloatArray, q1: FloatArray, q2: FloatArray) -> FloatArray:
    """Unit axis tangents (m, 2) at axis points ``x`` with feet ``q1``, ``q2`` (m, 2):
    normal to ``u1 - u2`` (the unit vectors from the feet), unoriented."""
    u1, u2 = x - q1, x - q2
    g = u1 / np.linalg.norm(u1, axis=1)[:, None] - u2 / np.linalg.norm(u2, axis=1)[:, None]
    t = np.column_stack((-g[:, 1], g[:, 0]))
    return t / np.linalg.norm(t, axis=1)[:, None]


def _consistent(a: Sides, x: FloatArray, d: FloatArray) -> np.ndarray:
    """Rows (bool (m,)) where both constraints are at distance ``d`` (m,) from ``x`` (m, 2)."""
    ok = np.all(np.isfinite(x), axis=1)
    xs = np.where(ok[:, None], x, 0.0)
    d1, d2 = a[0].closest(xs).distance, a[1].closest(xs).distance
    return ok & (np.abs(d1 - d) <= EPS * (1.0 + d)) & (np.abs(d2 - d) <= EPS * (1.0 + d))


def _jump(a: Sides, k: int, region: Region) -> FloatArray | None:
    """The kink (2,) where the foot on ``a[k]`` jumps from one end to the other: on the
    perpendicular bisector ``M + s v`` of the ends, at distance ``R = sqrt(h^2 + s^2)`` from
    both and from the other constraint (a quadratic in ``s`` per site of it); the one such
    point inside the region, or ``None``."""
    f0, f1, other = a[k].start, a[k].end, a[1 - k]
    mid, h = 0.5 * (f0 + f1), 0.5 * float(np.linalg.norm(f1 - f0))
    v = np.array([-(f1 - f0)[1], (f1 - f0)[0]]) / (2.0 * h)
    coef = []
    for f in (other.start, other.end):  # a point: linear
        e = mid - f
        coef.append((0.0, 2.0 * float(v @ e), h * h - float(e @ e)))
    if isinstance(other, Line):  # R = m . (x - a) = al + be s
        u = (other.b - other.a) / np.linalg.norm(other.b - other.a)
        m = np.array([-u[1], u[0]])
        al, be = float(m @ (mid - other.a)), float(m @ v)
        coef.append((1.0 - be * be, -2.0 * al * be, h * h - al * al))
    else:  # rho = r + sigma R: A + 2 ga s = 2 sigma r R, squared
        e, r = mid - other.center, other.radius
        big, ga = float(e @ e) - r * r - h * h, float(v @ e)
        coef.append((4.0 * (ga * ga - r * r), 4.0 * big * ga, big * big - 4.0 * r * r * h * h))
    roots = [z.real for c in coef for z in np.roots(c) if abs(z.imag) <= EPS]
    if not roots:
        return None
    sr = np.array(roots)
    x = mid[None, :] + sr[:, None] * v[None, :]
    xs = x[_consistent(a, x, np.sqrt(h * h + sr * sr)) & region.contains(x)]
    if len(xs) == 0 or np.max(np.linalg.norm(xs - xs[0], axis=1)) > 1e3 * EPS:
        return None  # none, or two different crossings: ambiguous
    return xs[0]


Break = tuple[FloatArray, FloatArray, FloatArray]  # a point (2,), feet before and after (2,)


def _transitions(a: Sides, k: int, t_end: FloatArray, field: DistanceField) -> list[list[Break]]:
    """Hypotheses for the transitions of the foot on ``a[k]`` between the axis ends (foot
    parameters ``t_end`` (2, 2)): it leaves (or reaches) an end continuously, on the normal
    line there; or, at end 0 at one axis end and at end 1 at the other, it may jump between
    them at a kink instead."""
    at = [np.abs(t_end[:, k] - e) <= EPS for e in (0.0, 1.0)]
    ends = [e for e in (0, 1) if at[e][0] != at[e][1]]
    if not ends:
        return [[]]
    out = []
    rays = _on_rays(a[k], a[1 - k], np.array(ends, dtype=np.float64))
    if np.all(np.isfinite(rays)):
        fs = field(rays)
        feet = np.column_stack((fs.t1, fs.t2))
        out.append([(x, f, f) for x, f in zip(rays, feet, strict=True)])
    if len(ends) == 2:
        kink = _jump(a, k, field.region)
        if kink is not None:
            o = field(kink[None, :])
            f_in, f_out = np.empty(2), np.empty(2)
            f_in[k], f_out[k] = t_end[0, k], t_end[1, k]
            f_in[1 - k] = f_out[1 - k] = (o.t1 if k == 1 else o.t2)[0]
            out.append([(kink, f_in, f_out)])
    return out


def _breakpoints(a: Sides, p: FloatArray, field: DistanceField) -> list[list[Break]]:
    """Candidate break sequences from B1 to B2: the axis ends ``p`` (2, 2) and the
    transitions between them, ordered along the axis (both feet move monotonically from end
    to end; a jump counts half way), each with the foot parameters on the pieces before and
    after it (they differ at a kink). The continuous hypotheses come first."""
    fe = field(p)
    t_end = np.column_stack((fe.t1, fe.t2))
    span = t_end[1] - t_end[0]
    out = []
    for h1 in _transitions(a, 0, t_end, field):
        for h2 in _transitions(a, 1, t_end, field):
            inner = h1 + h2
            progress = np.zeros(len(inner))
            for k in (0, 1):
                if abs(span[k]) > EPS:
                    mid = np.array([0.5 * (b[1][k] + b[2][k]) for b in inner])
                    progress += (mid - t_end[0, k]) / span[k] if inner else 0.0
            total = float(np.sum(np.abs(span) > EPS))
            if np.any(progress < -EPS) or np.any(progress > total + EPS):
                continue
            seq = [(p[0], t_end[0], t_end[0])]
            for i in np.argsort(progress, kind="stable"):
                # a transition on an end (a B side along a normal line) coincides with it
                x = inner[i][0]
                if min(np.linalg.norm(x - seq[-1][0]), np.linalg.norm(x - p[1])) > EPS:
                    seq.append(inner[i])
            seq.append((p[1], t_end[1], t_end[1]))
            out.append(seq)
    return out


def _piece_points(
    a: Sides, xa: FloatArray, xb: FloatArray, fa: FloatArray, fb: FloatArray
) -> tuple[FloatArray, FloatArray] | None:
    """Axis points (PER_ARC * m + 1, 2) from ``xa`` to ``xb`` (ends exact, feet ``fa``,
    ``fb`` (2,) on this piece) and their unit tangents (unoriented): ``m`` sub-arcs of at
    most ``MAX_TURN`` each, uniform in the foot parameter of the constraint that moves
    (uniform on the chord where neither foot moves: the bisector of two end points)."""
    speed = np.abs(fb - fa) * np.array([a[0].length(), a[1].length()])
    k = int(np.argmax(speed))
    m = 1
    for _ in range(3):
        s = np.linspace(0.0, 1.0, PER_ARC * m + 1)
        if speed[k] <= EPS:
            x = xa + s[:, None] * (xb - xa)
        else:
            x = _on_rays(a[k], a[1 - k], fa[k] + s * (fb[k] - fa[k]))
        x[0], x[-1] = xa, xb
        steps = np.diff(x, axis=0)
        if not np.all(np.isfinite(x)) or np.any(np.einsum("ij,ij->i", steps[:-1], steps[1:]) <= 0):
            return None  # no root, or the points turn back
        # the feet: at the piece's ends those of this piece (a kink has two pairs)
        q1, q2 = a[0].closest(x).foot, a[1].closest(x).foot
        q1[[0, -1]] = a[0].evaluate(np.array([fa[0], fb[0]]))
        q2[[0, -1]] = a[1].evaluate(np.array([fa[1], fb[1]]))
        tan = _tangents(a, x, q1, q2)
        # turning between neighbouring points (each well below 90 degrees)
        c = np.abs(np.einsum("ij,ij->i", tan[:-1], tan[1:]))
        turn = np.arccos(np.minimum(c, 1.0)).reshape(m, PER_ARC).sum(axis=1)
        if np.all(turn <= MAX_TURN):
            return x, tan
        m = max(m + 1, int(math.ceil(1.5 * turn.sum() / MAX_TURN)))
    return None


def _rational_arcs(
    x: FloatArray, tan: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray] | None:
    """Control points (m, 3, 2) and weights (m,) of the sub-arcs of points ``x`` (PER_ARC * m
    + 1, 2) with tangents ``tan``, and each sub-arc's first-derivative lengths at its ends
    (m, 2) per unit parameter; ``None`` if a sub-arc is not a proper conic arc."""
    p0, s, p2 = x[:-1:PER_ARC], x[PER_ARC // 2 :: PER_ARC], x[PER_ARC::PER_ARC]
    chord = p2 - p0
    t0 = tan[:-1:PER_ARC] * np.sign(np.einsum("ij,ij->i", tan[:-1:PER_ARC], chord))[:, None]
    t2 = (
        tan[PER_ARC::PER_ARC]
        * np.sign(np.einsum("ij,ij->i", tan[PER_ARC::PER_ARC], chord))[:, None]
    )
    det = t0[:, 0] * t2[:, 1] - t0[:, 1] * t2[:, 0]
    clen = np.linalg.norm(chord, axis=1)
    off = np.abs(chord[:, 0] * (s - p0)[:, 1] - chord[:, 1] * (s - p0)[:, 0]) / clen
    straight = (np.abs(det) <= EPS) & (off <= EPS)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = (chord[:, 0] * t2[:, 1] - chord[:, 1] * t2[:, 0]) / det
        beta = (t0[:, 0] * chord[:, 1] - t0[:, 1] * chord[:, 0]) / det
        p1 = np.where(straight[:, None], 0.5 * (p0 + p2), p0 + alpha[:, None] * t0)
    # barycentric coordinates of s in (p0, p1, p2): b1^2 / (b0 b2) = 4 w^2
    e1, e2, r = p1 - p0, p2 - p0, s - p0
    area = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        b1 = (r[:, 0] * e2[:, 1] - r[:, 1] * e2[:, 0]) / area
        b2 = (e1[:, 0] * r[:, 1] - e1[:, 1] * r[:, 0]) / area
        b0 = 1.0 - b1 - b2
        w = np.where(straight, 1.0, b1 / (2.0 * np.sqrt(b0 * b2)))
    proper = straight | ((alpha > 0.0) & (beta > 0.0) & (b0 > 0.0) & (b1 > 0.0) & (b2 > 0.0))
    if not np.all(proper & np.isfinite(w) & (w > 0.0)):
        return None
    ctrl = np.stack((p0, p1, p2), axis=1)
    speeds = np.column_stack(
        (w * np.linalg.norm(p1 - p0, axis=1), w * np.linalg.norm(p2 - p1, axis=1))
    )
    return ctrl, w, speeds


def _spline(ctrl: FloatArray, w: FloatArray, speeds: FloatArray) -> tuple[BSpline, FloatArray]:
    """The rational quadratic B-spline of the sub-arcs (m, 3, 2) with weights ``w`` (m,), knot
    spans chosen so that ``dx/du`` is continuous at the joints; and the joints (m + 1,)."""
    m = len(w)
    span = np.ones(m)
    for j in range(1, m):  # a handful of sub-arcs
        span[j] = span[j - 1] * speeds[j, 0] / speeds[j - 1, 1]
    u = np.concatenate(([0.0], np.cumsum(span)))
    u /= u[-1]
    knots = np.concatenate((np.zeros(3), np.repeat(u[1:-1], 2), np.ones(3)))
    pts = np.concatenate((ctrl[:, :2].reshape(-1, 2), ctrl[-1:, 2]))
    weights = np.ones(2 * m + 1)
    weights[1::2] = w
    return BSpline(pts, 2, knots, weights), u


def conic_axis(
    region: Region, pair: tuple[int, int], roles: PairRoles, tol: float, point_tol: float
) -> MedialAxis | None:
    """The exact axis between two line or arc constraints of a planar region, or ``None``
    when this path does not apply or fails a check (the caller then traces).

    ``tol`` and ``point_tol`` are relative to the region's diagonal as in ``trace_axis``;
    errors are measured on the result (both are rounding noise here).
    """
    if not region.embedding.is_identity or region.space_sides is not None:
        return None
    # (the kinds first: normalising is not free, and a transformed side keeps its kind)
    if not all(isinstance(region.sides[k], (Line, Arc)) for k in (roles.a1, roles.a2)):
        return None
    work, offset, scale = normalised_region(region)
    a1, a2 = work.sides[roles.a1], work.sides[roles.a2]
    if not (isinstance(a1, (Line, Arc)) and isinstance(a2, (Line, Arc))):
        return None
    if a1.dim != 2 or a2.dim != 2:
        return None
    a: Sides = (a1, a2)
    field = DistanceField(work, roles)
    try:
        (s0, s1), (p0, p1) = end_points(
            field,
            (work.sides[roles.b1], work.sides[roles.b2]),
            (f"side {roles.b1} (B1)", f"side {roles.b2} (B2)"),
        )
    except TraceError:
        return None  # the tracer reports it
    for seq in _breakpoints(a, np.stack((p0, p1)), field):
        got = _assemble(a, seq)
        if got is None:
            continue
        spline, pts, u = got
        res = _result(region, pair, roles, field, pts, spline, u, (s0, s1), (offset, scale),
                      tol, point_tol)  # fmt: skip
        if res is not None:
            return res
    log.debug("%s pair %s: no conic axis passed the checks, tracing", region.name, pair)
    return None


def _assemble(a: Sides, seq: list[Break]) -> tuple[BSpline, FloatArray, FloatArray] | None:
    """The spline, the points (n, 2) and the joints of the pieces between the breaks
    ``seq``, or ``None`` where a piece or sub-arc is degenerate."""
    pieces, arcs = [], []
    for i in range(len(seq) - 1):  # a handful of pieces
        got = _piece_points(a, seq[i][0], seq[i + 1][0], seq[i][2], seq[i + 1][1])
        arc = None if got is None else _rational_arcs(*got)
        if got is None or arc is None:
            return None
        pieces.append(got[0] if i == 0 else got[0][1:])
        arcs.append(arc)
    spline, u = _spline(*(np.concatenate(z) for z in zip(*arcs, strict=True)))
    return spline, np.concatenate(pieces), u


def _result(
    region: Region,
    pair: tuple[int, int],
    roles: PairRoles,
    field: DistanceField,
    pts: FloatArray,
    spline: BSpline,
    u: FloatArray,
    ends: tuple[float, float],
    frame: tuple[FloatArray, float],
    tol: float,
    point_tol: float,
) -> MedialAxis | None:
    """Measured errors at the points (n, 2) and 10x denser on ``spline`` (joints ``u``),
    and the result in the caller's coordinates (``x * scale + offset``)."""
    per = PER_ARC * CHECK_SAMPLES
    frac = np.arange(1, per) / per
    uu = (u[:-1, None] + frac[None, :] * np.diff(u)[:, None]).ravel()
    both = np.concatenate((pts, spline.evaluate(uu)))
    c1, c2 = field.a1.closest(both), field.a2.closest(both)
    err = np.abs(c1.distance - c2.distance)
    n = len(pts)
    point_error, curve_error = float(err[:n].max()), float(err[n:].max())
    if max(point_error, curve_error) > point_tol:  # unit diagonal
        log.debug("%s pair %s: conic axis measured %.3g, tracing", region.name, pair,
                  max(point_error, curve_error))  # fmt: skip
        return None
    offset, scale = frame
    counts = WorkCounts(
        points=n, distance_evaluations=field.evaluations + 2 * len(both),
        closed_form_pieces=len(u) - 1,
    )  # fmt: skip
    xy = pts * scale + offset
    return MedialAxis(
        region=region, pair=(int(pair[0]), int(pair[1])), roles=roles, method="frame",
        points=xy, space_points=xy, foot1=c1.foot[:n] * scale + offset,
        foot2=c2.foot[:n] * scale + offset, d1=c1.distance[:n] * scale,
        d2=c2.distance[:n] * scale, spline=spline.transformed(-offset / scale, 1.0 / scale),
        t_start=float(ends[0]), t_end=float(ends[1]), max_point_error=point_error * scale,
        max_curve_error=curve_error * scale, tol=tol, counts=counts,
    )  # fmt: skip


__all__ = ["conic_axis"]
