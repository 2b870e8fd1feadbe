"""The exact medial axis of two line-segment constraints in the plane, in closed form.

The axis of two disjoint segments ``A1``, ``A2`` (distances to the segments, ends included)
is the bisector of their Voronoi sites (two end points and the open segment each). Where
both feet are interior it is the angle bisector of the two lines (or the mid-parallel);
where one foot is clamped at an end point ``F`` of its segment it is the parabola with focus
``F`` and the other line as directrix; where both are clamped, the perpendicular bisector
of two end points. Every piece is a polynomial curve of degree <= 2,

    x(tau) = p + tau u + tau^2 w        (u unit; w = 0 on lines, w = N / 2f on a parabola),

so the whole axis is exactly a quadratic B-spline (one Bezier piece per conic piece, joints
of multiplicity 2 at the transitions, knots spaced so that the parametrisation is C1 there:
the axis itself is C1, both distances being C1 off the segments).

The bisector is a single simple curve (two disjoint convex sets). It is followed from the
midpoint of the segments' closest pair (which lies on it) in both directions; a transition
is where the conic crosses the normal line at an end of a segment (a foot reaches or leaves
that end), found as the root of a quadratic in ``tau``. The start and end points are the
crossings of this chain with ``B1`` and ``B2``: closed form for line sides (a quadratic in
``tau``) and arcs (quadratic or quartic), the existing Newton solver on the side for other
kinds. Errors are then measured on the result with the constraints' own ``closest``; any
failure (touching segments, a crossing count other than one, a measured error above the
point tolerance) returns ``None`` and the caller traces instead.

Lengths are in the region's unit; the work is done relative to the centre of the
constraints (far from the origin the construction keeps its relative accuracy).
"""

from __future__ import annotations

import logging
import math
from typing import NamedTuple

import numpy as np

from medax.axis.field import DistanceField
from medax.axis.result import MedialAxis, WorkCounts
from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve
from medax.geometry.line import Line
from medax.geometry.region import PairRoles, Region

log = logging.getLogger(__name__)

Vec = tuple[float, float]
#: a crossing with B1/B2: (piece index, tau on it, parameter on the side)
_Hit = tuple[int, float, float]
#: more conic pieces than this on the bisector of two segments means something went wrong
MAX_PIECES = 12
#: points per piece of the result (intervals): parabolas, lines
POINTS_PARABOLA, POINTS_LINE = 4, 2
#: check samples per interval between points (the tracer's "10x denser")
CHECK_SAMPLES = 10
_FRAC = np.arange(1, CHECK_SAMPLES)[None, :] / CHECK_SAMPLES
#: relative (x length scale) slack on transitions and on the ends of pieces
EPS = 1e-11


class _Seg(NamedTuple):
    """Segment from ``a`` to ``b`` (local coordinates): unit direction ``u``, unit left
    normal ``n``, length ``length``."""

    a: Vec
    b: Vec
    u: Vec
    n: Vec
    length: float


class Piece(NamedTuple):
    """One conic piece ``x(tau) = p + tau u + tau^2 w`` for ``lo <= tau <= hi`` (local
    coordinates), with the feet states that hold on it (0: at the segment start, 1: interior,
    2: at the end), for A1 and A2."""

    p: Vec
    u: Vec
    w: Vec
    lo: float
    hi: float
    states: tuple[int, int]

    def at(self, t: float) -> Vec:
        return (
            self.p[0] + t * (self.u[0] + t * self.w[0]),
            self.p[1] + t * (self.u[1] + t * self.w[1]),
        )

    def tangent(self, t: float) -> Vec:
        return (self.u[0] + 2.0 * t * self.w[0], self.u[1] + 2.0 * t * self.w[1])

    def reversed(self) -> Piece:
        return Piece(self.p, (-self.u[0], -self.u[1]), self.w, -self.hi, -self.lo, self.states)

    @property
    def is_line(self) -> bool:
        return self.w == (0.0, 0.0)


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1]


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1])


def _unit(a: Vec) -> Vec:
    r = math.hypot(a[0], a[1])
    return (a[0] / r, a[1] / r)


def _seg(line: Line, o: Vec) -> _Seg:
    a = (float(line.a[0]) - o[0], float(line.a[1]) - o[1])
    b = (float(line.b[0]) - o[0], float(line.b[1]) - o[1])
    d = _sub(b, a)
    length = math.hypot(d[0], d[1])
    u = (d[0] / length, d[1] / length)
    return _Seg(a, b, u, (-u[1], u[0]), length)


def _closest_pair(s1: _Seg, s2: _Seg) -> tuple[Vec, Vec, float]:
    """Closest points of two segments (assumed not crossing): the best of the four
    end point - segment distances."""
    best: tuple[Vec, Vec, float] | None = None
    for x, s, first in ((s1.a, s2, False), (s1.b, s2, False), (s2.a, s1, True), (s2.b, s1, True)):
        t = min(max(_dot(_sub(x, s.a), s.u), 0.0), s.length)
        q = (s.a[0] + t * s.u[0], s.a[1] + t * s.u[1])
        d = math.hypot(x[0] - q[0], x[1] - q[1])
        if best is None or d < best[2]:
            best = (q, x, d) if first else (x, q, d)
    assert best is not None
    return best


def _state(s: _Seg, x: Vec, t: Vec, tol: float) -> int:
    """Foot state on ``s`` just after ``x`` when moving along ``t``: 0 (at ``a``), 1
    (interior), 2 (at ``b``); on a normal line through an end, the direction decides."""
    along = _dot(_sub(x, s.a), s.u)
    go = _dot(t, s.u)
    if abs(along) <= tol:
        return 1 if go > 0.0 else 0
    if abs(along - s.length) <= tol:
        return 2 if go > 0.0 else 1
    return 0 if along < 0.0 else (2 if along > s.length else 1)


def _site(s: _Seg, state: int) -> Vec | None:
    """The end point a clamped foot sits on, or ``None`` for an interior foot."""
    return s.a if state == 0 else (s.b if state == 2 else None)


def _conic(
    s1: _Seg, s2: _Seg, st: tuple[int, int], x0: Vec, t: Vec, scale: float
) -> tuple[Vec, Vec, Vec, float] | None:
    """The bisector piece through ``x0`` for feet states ``st``: ``(p, u, w, tau0)`` with
    ``x(tau0) = x0`` and ``tau`` increasing along ``t``; ``None`` if degenerate."""
    f1, f2 = _site(s1, st[0]), _site(s2, st[1])
    zero = (0.0, 0.0)
    if f1 is not None and f2 is not None:  # two points: the perpendicular bisector
        d = _sub(f2, f1)
        if math.hypot(d[0], d[1]) <= EPS * scale:
            return None
        u = _unit((-d[1], d[0]))
        if _dot(u, t) < 0.0:
            u = (-u[0], -u[1])
        p = (0.5 * (f1[0] + f2[0]), 0.5 * (f1[1] + f2[1]))
        return p, u, zero, _dot(_sub(x0, p), u)
    if f1 is None and f2 is None:  # two lines: the bisector on x0's side of each
        n1 = s1.n if _dot(_sub(x0, s1.a), s1.n) >= 0.0 else (-s1.n[0], -s1.n[1])
        n2 = s2.n if _dot(_sub(x0, s2.a), s2.n) >= 0.0 else (-s2.n[0], -s2.n[1])
        m = _sub(n1, n2)
        mm = _dot(m, m)
        if mm <= 1e-24:
            return None
        c = _dot(n1, s1.a) - _dot(n2, s2.a)
        k = (_dot(m, x0) - c) / mm
        p = (x0[0] - k * m[0], x0[1] - k * m[1])  # x0 projected onto the line
        u = _unit((-m[1], m[0]))
        if _dot(u, t) < 0.0:
            u = (-u[0], -u[1])
        return p, u, zero, 0.0
    # a point and a line: the parabola with that focus and directrix
    focus, s = (f1, s2) if f1 is not None else (f2, s1)
    assert focus is not None
    nn = s.n if _dot(_sub(x0, s.a), s.n) >= 0.0 else (-s.n[0], -s.n[1])
    f = _dot(_sub(focus, s.a), nn)  # focus to directrix
    if f <= EPS * scale:
        return None
    v = (focus[0] - 0.5 * f * nn[0], focus[1] - 0.5 * f * nn[1])  # vertex
    e = (-nn[1], nn[0])
    tau0 = _dot(_sub(x0, v), e)
    if _dot((e[0] + tau0 / f * nn[0], e[1] + tau0 / f * nn[1]), t) < 0.0:
        e, tau0 = (-e[0], -e[1]), -tau0
    return v, e, (0.5 / f * nn[0], 0.5 / f * nn[1]), tau0


def _roots(a: float, b: float, c: float) -> list[float]:
    """Real roots of ``a t^2 + b t + c`` (stable formula; linear when ``a == 0``)."""
    if a == 0.0:
        return [] if b == 0.0 else [-c / b]
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return []
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    return [q / a] if q == 0.0 else [q / a, c / q]


#: the ends whose normal lines bound each foot state (0: at a, 1: interior, 2: at b)
_BOUNDS = {0: (0,), 1: (0, 2), 2: (2,)}


def _follow(s1: _Seg, s2: _Seg, x0: Vec, t: Vec, scale: float) -> list[Piece] | None:
    """The bisector from ``x0`` in direction ``t`` to infinity, piece by piece."""
    segs = (s1, s2)
    tol = EPS * scale
    st = (_state(s1, x0, t, tol), _state(s2, x0, t, tol))
    out: list[Piece] = []
    for _ in range(MAX_PIECES):
        c = _conic(s1, s2, st, x0, t, scale)
        if c is None:
            return None
        p, u, w, tau0 = c
        hits: list[tuple[float, int, int]] = []  # (tau, segment, state at that end)
        for k, s in enumerate(segs):
            sx, sy = s.u
            qa, qb = w[0] * sx + w[1] * sy, u[0] * sx + u[1] * sy
            for at in _BOUNDS[st[k]]:  # crossings of the normal line (x - e) . u_s = 0
                e = s.a if at == 0 else s.b
                qc = (p[0] - e[0]) * sx + (p[1] - e[1]) * sy
                hits += [(r, k, at) for r in _roots(qa, qb, qc) if r > tau0 + tol]
        if not hits:
            out.append(Piece(p, u, w, tau0, math.inf, st))
            return out
        tau1 = min(h[0] for h in hits)
        piece = Piece(p, u, w, tau0, tau1, st)
        out.append(piece)
        new = list(st)
        for r, k, at in hits:
            if r <= tau1 + tol:  # every foot reaching (or leaving) an end here
                new[k] = at if st[k] == 1 else 1
        st = (new[0], new[1])
        x0 = piece.at(tau1)
        t = _unit(piece.tangent(tau1))
    return None


def bisector(s1: _Seg, s2: _Seg, scale: float) -> list[Piece] | None:
    """The whole bisector of two disjoint segments as ordered pieces (the first and last
    unbounded), or ``None`` if they touch or a piece is degenerate."""
    q1, q2, dist = _closest_pair(s1, s2)
    if dist <= EPS * scale:
        return None
    m = (0.5 * (q1[0] + q2[0]), 0.5 * (q1[1] + q2[1]))
    w = ((q2[0] - q1[0]) / dist, (q2[1] - q1[1]) / dist)
    t = (w[1], -w[0])  # along the bisector (its gradient is along w)
    fwd = _follow(s1, s2, m, t, scale)
    bwd = _follow(s1, s2, m, (-t[0], -t[1]), scale)
    if fwd is None or bwd is None:
        return None
    back = [pc.reversed() for pc in reversed(bwd)]
    last, first = back[-1], fwd[0]
    if last.states == first.states and last.p == first.p and last.u == first.u:
        fwd[0] = first._replace(lo=last.lo)  # the same conic through m: one piece
        back.pop()
    return back + fwd


# ---- crossings with B1 / B2 ------------------------------------------------------------------
def _on_line_side(side: Line, o: Vec, chain: list[Piece], scale: float) -> list[_Hit]:
    """Crossings of the chain with the segment ``side``: a quadratic in ``tau`` per piece."""
    c0 = (float(side.a[0]) - o[0], float(side.a[1]) - o[1])
    d = (float(side.b[0]) - o[0] - c0[0], float(side.b[1]) - o[1] - c0[1])
    nx, ny = -d[1], d[0]
    dd = d[0] * d[0] + d[1] * d[1]
    slack = EPS * scale
    out = []
    for i, pc in enumerate(chain):
        (px, py), (ux, uy), (wx, wy) = pc.p, pc.u, pc.w
        rs = _roots(nx * wx + ny * wy, nx * ux + ny * uy, nx * (px - c0[0]) + ny * (py - c0[1]))
        for r in rs:
            if pc.lo - slack <= r <= pc.hi + slack:
                x = pc.at(r)
                s = ((x[0] - c0[0]) * d[0] + (x[1] - c0[1]) * d[1]) / dd
                if -EPS <= s <= 1.0 + EPS:
                    out.append((i, r, min(max(s, 0.0), 1.0)))
    return out


def _quartic_roots(coef: list[float]) -> list[float]:
    """Real roots of a quartic (coefficients highest first), polished by Newton."""
    rs = []
    for z in np.roots(coef):
        if abs(z.imag) <= 1e-7 * max(1.0, abs(z.real)):
            r = float(z.real)
            for _ in range(3):  # polish (the companion eigenvalues lose a few digits)
                f = (((coef[0] * r + coef[1]) * r + coef[2]) * r + coef[3]) * r + coef[4]
                g = ((4.0 * coef[0] * r + 3.0 * coef[1]) * r + 2.0 * coef[2]) * r + coef[3]
                if g == 0.0:
                    break
                r -= f / g
            rs.append(r)
    return rs


def _on_arc_side(side: Arc, o: Vec, chain: list[Piece], scale: float) -> list[_Hit]:
    """Crossings of the chain with the arc ``side``: roots of ``|x(tau) - c|^2 - r^2``
    (quadratic on lines, quartic on parabolas) on the arc's angular range."""
    c = (float(side.center[0]) - o[0], float(side.center[1]) - o[1])
    r2 = side.radius**2
    sweep, a0 = abs(side.sweep), side.a0
    sign = math.copysign(1.0, side.sweep)
    full = 2.0 * math.pi / sweep
    slack = EPS * scale
    out = []
    for i, pc in enumerate(chain):
        q = (pc.p[0] - c[0], pc.p[1] - c[1])
        u, w = pc.u, pc.w
        a2 = u[0] * u[0] + u[1] * u[1] + 2.0 * (w[0] * q[0] + w[1] * q[1])
        a1 = 2.0 * (u[0] * q[0] + u[1] * q[1])
        a0c = q[0] * q[0] + q[1] * q[1] - r2
        if pc.is_line:
            rs = _roots(a2, a1, a0c)
        else:
            rs = _quartic_roots([_dot(w, w), 2.0 * _dot(u, w), a2, a1, a0c])
        for r in rs:
            if pc.lo - slack <= r <= pc.hi + slack:
                x = pc.at(r)
                ang = math.atan2(x[1] - c[1], x[0] - c[0])
                s = ((ang - a0) * sign) % (2.0 * math.pi) / sweep
                if s > 0.5 * (1.0 + full):  # just before the start, across the cut
                    s -= full
                if -EPS <= s <= 1.0 + EPS:
                    out.append((i, r, min(max(s, 0.0), 1.0)))
    return out


def _locate(chain: list[Piece], x: Vec, scale: float) -> list[tuple[int, float]]:
    """``(piece index, tau)`` of a point ``x`` of the bisector."""
    out = []
    for i, pc in enumerate(chain):
        r = _dot(_sub(x, pc.p), pc.u)  # u is unit and w is normal to it
        if pc.lo - EPS * scale <= r <= pc.hi + EPS * scale:
            y = pc.at(r)
            if math.hypot(y[0] - x[0], y[1] - x[1]) <= 1e-9 * scale:
                out.append((i, r))
    return out[:1]


def _crossings(
    chain: list[Piece], side: Curve, o: Vec, scale: float, region: Region, roles: PairRoles
) -> list[_Hit]:
    """``(piece index, tau, side parameter)`` of the chain's crossings with a start/end side."""
    if isinstance(side, Line):
        return _on_line_side(side, o, chain, scale)
    if isinstance(side, Arc):
        return _on_arc_side(side, o, chain, scale)
    from medax.axis.endpoints import end_point  # any other kind: Newton on the side

    s, x = end_point(DistanceField(region, roles), side, "start/end side")
    return [(i, r, s) for i, r in _locate(chain, (float(x[0]) - o[0], float(x[1]) - o[1]), scale)]


def _dedupe(hits: list[_Hit], chain: list[Piece], scale: float) -> list[_Hit]:
    """One crossing where a root sits on a joint of two pieces (found on both)."""
    out: list[_Hit] = []
    for h in sorted(hits):
        x = chain[h[0]].at(h[1])
        if out:
            y = chain[out[-1][0]].at(out[-1][1])
            if math.hypot(x[0] - y[0], x[1] - y[1]) <= 1e-9 * scale:
                continue
        out.append(h)
    return out


# ---- the axis ---------------------------------------------------------------------------------
def segment_axis(
    region: Region, pair: tuple[int, int], roles: PairRoles, tol: float, point_tol: float
) -> MedialAxis | None:
    """The exact axis between two line-segment constraints of a planar region, or ``None``
    when this path does not apply (other constraint kinds, an embedding, degenerate or
    ambiguous geometry, a measured error above ``point_tol``): the caller then traces.

    ``tol`` and ``point_tol`` are relative to the region's diagonal as in ``trace_axis``;
    the result's errors are measured, not assumed (both are rounding noise here).
    """
    a1, a2 = region.sides[roles.a1], region.sides[roles.a2]
    if not (
        isinstance(a1, Line)
        and isinstance(a2, Line)
        and region.embedding.is_identity
        and region.space_sides is None
        and a1.dim == 2
        and a2.dim == 2
    ):
        return None
    xs = [float(a1.a[0]), float(a1.b[0]), float(a2.a[0]), float(a2.b[0])]
    ys = [float(a1.a[1]), float(a1.b[1]), float(a2.a[1]), float(a2.b[1])]
    o = (0.5 * (min(xs) + max(xs)), 0.5 * (min(ys) + max(ys)))
    scale = math.hypot(max(xs) - min(xs), max(ys) - min(ys))  # <= the region's diagonal
    s1, s2 = _seg(a1, o), _seg(a2, o)
    chain = bisector(s1, s2, scale)
    if chain is None:
        log.debug("%s pair %s: degenerate segment bisector, tracing", region.name, pair)
        return None
    b1, b2 = region.sides[roles.b1], region.sides[roles.b2]
    h1 = _dedupe(_crossings(chain, b1, o, scale, region, roles), chain, scale)
    h2 = _dedupe(_crossings(chain, b2, o, scale, region, roles), chain, scale)
    if len(h1) != 1 or len(h2) != 1:
        log.debug("%s pair %s: %d/%d crossings with B1/B2, tracing", region.name, pair,
                  len(h1), len(h2))  # fmt: skip
        return None
    (i0, r0, t_start), (i1, r1, t_end) = h1[0], h2[0]
    if (i0, r0) > (i1, r1):  # B2 comes first along the chain: walk it the other way
        chain = [pc.reversed() for pc in reversed(chain)]
        i0, r0, i1, r1 = len(chain) - 1 - i0, -r0, len(chain) - 1 - i1, -r1
    pieces = [pc for pc in chain[i0 : i1 + 1]]
    pieces[0] = pieces[0]._replace(lo=r0)
    pieces[-1] = pieces[-1]._replace(hi=r1)
    tiny = 1e-12 * scale
    pieces = [
        pc for pc in pieces if math.hypot(*_sub(pc.at(pc.hi), pc.at(pc.lo))) > tiny
    ] or pieces[:1]
    return _result(region, pair, roles, _merge_lines(pieces, scale), o, t_start, t_end, tol,
                   point_tol, scale)  # fmt: skip


def _merge_lines(pieces: list[Piece], scale: float) -> list[Piece]:
    """Consecutive line pieces as one (the axis is C1, so they lie on one line; e.g. where
    both feet reach segment ends at once on a symmetric axis): a joint inside a straight
    line describes nothing. Checked to rounding, else kept apart."""
    out = [pieces[0]]
    for pc in pieces[1:]:
        last = out[-1]
        if last.is_line and pc.is_line:
            end = pc.at(pc.hi)
            hi = _dot(_sub(end, last.p), last.u)
            y = last.at(hi)
            if math.hypot(y[0] - end[0], y[1] - end[1]) <= 1e-13 * scale:
                out[-1] = last._replace(hi=hi)
                continue
        out.append(pc)
    return out


def _result(
    region: Region,
    pair: tuple[int, int],
    roles: PairRoles,
    pieces: list[Piece],
    o: Vec,
    t_start: float,
    t_end: float,
    tol: float,
    point_tol: float,
    scale: float,
) -> MedialAxis | None:
    """Points, spline and measured errors of the exact pieces (local coordinates + ``o``).

    Piece ``i`` is the Bezier curve ``x(lo), x(lo) + span/2 x'(lo), x(hi)`` (exact for a
    quadratic polynomial); its knot span is chosen so that ``dx/du`` is continuous at the
    joints. Per-piece work is scalar (a handful of pieces); the measurements are vectorised.
    """
    ox, oy = o
    ctrl: list[Vec] = []
    breaks = [0.0]
    pts: list[Vec] = []
    u_pts: list[float] = []
    du = prev_speed = prev_span = 0.0
    for i, pc in enumerate(pieces):
        lo, span = pc.lo, pc.hi - pc.lo
        d0 = pc.tangent(lo)
        speed = math.hypot(d0[0], d0[1])
        du = span if i == 0 else du * (speed * span) / (prev_speed * prev_span)
        x0, x2 = pc.at(lo), pc.at(pc.hi)
        if i == 0:
            ctrl.append((x0[0] + ox, x0[1] + oy))
        else:  # the joint: both pieces' ends, equal to rounding
            x1 = pieces[i - 1].at(pieces[i - 1].hi)
            ctrl[-1] = (0.5 * (x0[0] + x1[0]) + ox, 0.5 * (x0[1] + x1[1]) + oy)
        h = 0.5 * span
        ctrl += [(x0[0] + h * d0[0] + ox, x0[1] + h * d0[1] + oy), (x2[0] + ox, x2[1] + oy)]
        k = POINTS_LINE if pc.is_line else POINTS_PARABOLA
        pts.append(ctrl[-3])
        u0 = breaks[-1]
        u_pts.append(u0)
        for j in range(1, k):
            y = pc.at(lo + span * j / k)
            pts.append((y[0] + ox, y[1] + oy))
            u_pts.append(u0 + du * j / k)
        breaks.append(u0 + du)
        d1 = pc.tangent(pc.hi)
        prev_speed, prev_span = math.hypot(d1[0], d1[1]), span
    pts.append(ctrl[-1])
    u_pts.append(breaks[-1])
    total = breaks[-1]
    spline = BSpline.from_bezier(np.array(ctrl), np.array(breaks) / total, 2)
    n = len(pieces)
    xy = np.array(pts)
    uu_pts = np.array(u_pts) / total
    # measured errors: at the points and 10x denser on the spline (one query per side)
    uu = (uu_pts[:-1, None] + _FRAC * np.diff(uu_pts)[:, None]).ravel()
    both = np.concatenate((xy, spline.evaluate(uu)))
    c1 = region.sides[roles.a1].closest(both)
    c2 = region.sides[roles.a2].closest(both)
    err = np.abs(c1.distance - c2.distance)
    npt = len(xy)
    point_error, curve_error = float(err[:npt].max()), float(err[npt:].max())
    if max(point_error, curve_error) > point_tol * scale:
        log.debug("%s pair %s: closed form measured %.3g, tracing", region.name, pair,
                  max(point_error, curve_error) / scale)  # fmt: skip
        return None
    counts = WorkCounts(
        points=len(xy), distance_evaluations=2 * (len(xy) + len(uu)), closed_form_pieces=n
    )
    return MedialAxis(
        region=region, pair=(int(pair[0]), int(pair[1])), roles=roles, method="frame",
        points=xy, space_points=xy, foot1=c1.foot[:npt], foot2=c2.foot[:npt],
        d1=c1.distance[:npt], d2=c2.distance[:npt], spline=spline, t_start=float(t_start),
        t_end=float(t_end),
        max_point_error=point_error, max_curve_error=curve_error, tol=tol, counts=counts,
    )  # fmt: skip


__all__ = ["Piece", "bisector", "segment_axis"]
