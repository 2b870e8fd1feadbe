"""The ratio field whose level curves are the node lines of the ratio mesher.

For a pair of opposite sides ``(a, b)`` and a ratio ``r`` in ``[0, 1]`` the curve of the
family is the zero set of

    g(p) = (1 - r) S((1 - r) T) d_a(p) - r S(r T) d_b(p),    S(x) = sin(x) / x,

with ``d_k`` the distance in space from ``E(p)`` to side ``k`` and ``T`` the angle between the
tangent lines of the two sides at the feet of ``p`` (``T = arccos(-u_a . u_b)``, ``u_k`` the
unit vector from the foot on side ``k`` to the point). Two weightings:

- ``"angle"``: ``T`` as defined. Between two lines meeting at an angle the curves are the
  rays of equal angle (the ray at angle ``r T`` from ``a`` solves ``g = 0`` exactly); between
  parallel lines and concentric arcs (``u_a = -u_b``, ``T = 0``) they are the curves of
  constant distance ratio.
- ``"distance"``: ``T = 0`` everywhere, the curves ``d_a / (d_a + d_b) = r``.

Both give the medial axis at ``r = 1/2`` (``g`` is then a positive multiple of
``d_a - d_b``), the tracer's object.
"""

from __future__ import annotations

import numpy as np

from medax import tolerances
from medax.geometry._types import FloatArray
from medax.geometry.arc import Arc
from medax.geometry.curve import Closest, Curve, has_closed_form_closest, track_closest
from medax.geometry.line import Line
from medax.geometry.region import Region

WEIGHTINGS = ("auto", "angle", "distance")
TRACK_STEP = 1e-6  # tracking Newton steps (in the foot parameter) that end a row, at least
TRACK_STEP_MAX = 1e-4  # ... and at most (SideDistances.set_tolerance)
_TINY = np.finfo(float).tiny
_EMPTY = np.empty(0)


def _sinc(x: FloatArray) -> FloatArray:
    """``sin(x) / x`` (1 at 0)."""
    return np.sinc(x / np.pi)


def pair_weighting(region: Region, a: int, b: int, weighting: str) -> str:
    """The weighting used for the pair ``(a, b)`` (``"angle"`` or ``"distance"``).

    ``"angle"`` applies only in the plane and between lines and arcs, where feet move
    continuously (on free-form sides the nearest point can jump, ``T`` would jump with it
    and the curves would break). ``"auto"`` (the default mesher's) takes ``"angle"`` only for
    a polar pair: two lines whose opposite sides are arcs centred where the lines meet
    (there it gives the exact polar grid; elsewhere the distance ratio measured better).
    """
    sides = region.sides
    simple = all(isinstance(sides[k], (Line, Arc)) for k in (a, b))
    if not (region.embedding.is_identity and simple) or weighting == "distance":
        return "distance"
    if not facing(region, a, b):
        return "distance"
    if weighting == "angle":
        return "angle"
    return "angle" if _is_polar_pair(region, a, b) else "distance"


def facing(region: Region, a: int, b: int) -> bool:
    """False for two line sides of which one lies behind the other (a region bent past 180
    degrees around their meeting point: the angle between the lines does not describe it)."""
    la, lb = region.sides[a], region.sides[b]
    if not (isinstance(la, Line) and isinstance(lb, Line)):
        return True
    eps = 1e-9 * region.diagonal
    for p, q in ((la, lb), (lb, la)):
        d = p.b - p.a
        inward = np.array([-d[1], d[0]]) / float(np.hypot(d[0], d[1]))  # left of a CCW side
        if min(float((q.a - p.a) @ inward), float((q.b - p.a) @ inward)) < -eps:
            return False
    return True


def _is_polar_pair(region: Region, a: int, b: int) -> bool:
    """Sides ``a``, ``b`` are lines meeting at a point where both other sides are centred,
    arcs of less than 180 degrees."""
    la, lb = region.sides[a], region.sides[b]
    others = [region.sides[k] for k in range(4) if k not in (a, b)]
    if not (isinstance(la, Line) and isinstance(lb, Line)):
        return False
    if not all(isinstance(o, Arc) and abs(o.sweep) < np.pi - 1e-9 for o in others):
        return False  # (a sector of 180 degrees or more has no apex angle to divide)
    da, db = la.b - la.a, lb.b - lb.a
    cross = da[0] * db[1] - da[1] * db[0]
    if abs(cross) <= 1e-12 * float(np.linalg.norm(da) * np.linalg.norm(db)):
        return False
    s = ((lb.a[0] - la.a[0]) * db[1] - (lb.a[1] - la.a[1]) * db[0]) / cross
    apex = la.a + s * da
    tol = tolerances.CORNER_TOL * region.diagonal
    return all(float(np.linalg.norm(o.center - apex)) <= tol for o in others)  # type: ignore[attr-defined]


def foot_angle(ua: FloatArray, ub: FloatArray, weighting: str) -> FloatArray:
    """Angle (n,) between the tangent lines at the two feet, from the unit vectors (n, dim)."""
    if weighting == "distance":
        return np.zeros(ua.shape[0])
    return np.arccos(np.clip(-np.einsum("ij,ij->i", ua, ub), -1.0, 1.0))


def _weights(r: FloatArray, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(1 - r) S((1 - r) T)`` and ``r S(r T)`` (each (n,))."""
    if not np.any(theta):
        return 1.0 - r, r
    return (1.0 - r) * _sinc((1.0 - r) * theta), r * _sinc(r * theta)


def angular_ratio(da: FloatArray, db: FloatArray, theta: FloatArray) -> FloatArray:
    """The ratio ``r`` (n,) whose curve passes through a point with distances ``da``, ``db``
    and foot angle ``theta``: ``atan2(da sin T, db + da cos T) / T`` (``da / (da + db)`` at
    ``T = 0``)."""
    small = theta < 1e-8
    t = np.where(small, 1.0, theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        lin = da / np.maximum(da + db, _TINY)
    return np.where(small, lin, np.arctan2(da * np.sin(t), db + da * np.cos(t)) / t)


def _line_closest(curve: Line, x: FloatArray) -> Closest:
    """Closest points on the supporting (infinite) line of a line side: the parameter is not
    clamped to ``[0, 1]``."""
    d = curve.b - curve.a
    t = ((x - curve.a) @ d) / float(d @ d)
    foot = curve.evaluate(t)
    return Closest(t=t, foot=foot, distance=np.linalg.norm(x - foot, axis=1))


def _arc_radial(arc: Arc, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Distances (n,), unit vectors (n, 2) from the foot, and NaN foot parameters, for points
    ``x`` (n, 2) to an arc: radial inside the arc's angle (decided by two cross products, no
    arctangent: the hot path of meshes on arc sides), the nearer end for the others."""
    v = x - arc.center
    rho = np.hypot(v[:, 0], v[:, 1])
    sgn = 1.0 if arc.sweep > 0 else -1.0
    e0 = np.array([np.cos(arc.a0), np.sin(arc.a0)])
    e1 = np.array([np.cos(arc.a0 + arc.sweep), np.sin(arc.a0 + arc.sweep)])
    after_start = sgn * (e0[0] * v[:, 1] - e0[1] * v[:, 0]) >= 0.0
    before_end = sgn * (v[:, 0] * e1[1] - v[:, 1] * e1[0]) >= 0.0
    inside = after_start & before_end if abs(arc.sweep) <= np.pi else after_start | before_end
    inside &= rho > 0.0
    d = np.abs(rho - arc.radius)
    # unit vector from the foot c + R v / rho to x: +v / rho outside the circle, -v inside
    u = v * (np.where(rho >= arc.radius, 1.0, -1.0) / np.maximum(rho, _TINY))[:, None]
    out = np.flatnonzero(~inside)
    if out.size:  # outside the arc's angle the nearer end is the foot
        xo = x[out]
        ends = arc.evaluate(np.array([0.0, 1.0]))
        r0, r1 = xo - ends[0], xo - ends[1]
        d0, d1 = np.hypot(r0[:, 0], r0[:, 1]), np.hypot(r1[:, 0], r1[:, 1])
        first = d0 <= d1
        d[out] = np.where(first, d0, d1)
        u[out] = np.where(first[:, None], r0, r1) / np.maximum(d[out], _TINY)[:, None]
    return d, u, np.full(x.shape[0], np.nan)


class SideDistances:
    """Distances to the four sides with feet tracked between calls (per node row).

    Line sides of a pair weighted by angle are measured to their supporting lines
    (``extended``): the equal-angle rays of a sector are exact only for the whole lines (a
    foot clamped to a segment's end would bend them).
    """

    def __init__(self, region: Region, n: int, kinds: tuple[str, str]) -> None:
        self.region = region
        self.curves: list[Curve] = [region.space_curve(k) for k in range(4)]
        self.extended = [
            kinds[k % 2] == "angle" and isinstance(c, Line) for k, c in enumerate(self.curves)
        ]
        self.tracked = [
            not (ext or has_closed_form_closest(c))
            for c, ext in zip(self.curves, self.extended, strict=True)
        ]
        # arcs of a distance-weighted pair: radial distances, no foot parameter needed
        self.radial = [
            kinds[k % 2] == "distance" and isinstance(c, Arc) and c.dim == 2
            for k, c in enumerate(self.curves)
        ]
        self.t = [np.full(n, np.nan) for _ in range(4)]  # accepted feet (tracked sides)
        self.t_alt = [np.full(n, np.nan) for _ in range(4)]  # second starts (NaN: none)
        self.d = [np.full(n, np.nan) for _ in range(4)]  # accepted distances
        self.step_tol = [TRACK_STEP] * 4  # of the tracking Newton (see :meth:`set_tolerance`)

    def set_tolerance(self, tol: float) -> None:
        """Let the tracked feet stop at longer steps where the distances stay within
        ``1e-3 * tol`` (region units) of the exact ones: the foot point of a step ``s`` is
        the jet's Taylor expansion, off by at most ``max|C'''| s^3 / 6`` (the curve's
        ``third_bound``), the foot parameter by about ``K s^2`` (whose effect on the
        stationary distance is of 4th order); kept between ``TRACK_STEP`` and
        ``TRACK_STEP_MAX``."""
        for k, c in enumerate(self.curves):
            bound = getattr(c, "third_bound", None)
            if not self.tracked[k] or bound is None:
                continue
            s = (6e-3 * tol / max(float(bound), 1e-300)) ** (1.0 / 3.0)
            self.step_tol[k] = min(TRACK_STEP_MAX, max(TRACK_STEP, s))

    def dist(
        self, k: int, x: FloatArray, rows: np.ndarray | None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Distances (n,), unit vectors (n, dim) and foot parameters (n,) of space points
        ``x`` to side ``k``; warm-started from the accepted feet of ``rows`` if given."""
        curve = self.curves[k]
        if self.radial[k]:
            assert isinstance(curve, Arc)
            return _arc_radial(curve, x)
        if self.extended[k]:
            assert isinstance(curve, Line)
            c = _line_closest(curve, x)
        elif rows is None or not self.tracked[k]:
            c = curve.closest(x)
        else:
            c = _tracked(curve, x, self.t[k][rows], self.t_alt[k][rows], self.step_tol[k])
        u = (x - c.foot) / np.maximum(c.distance, _TINY)[:, None]
        return c.distance, u, c.t


def _tracked(
    curve: Curve,
    x: FloatArray,
    t0: FloatArray,
    t1: FloatArray | None = None,
    step_tol: float = TRACK_STEP,
) -> Closest:
    """Feet from the accepted ones ``t0`` (n,) by :func:`track_closest` (``step_tol``); a
    global query for rows without one (NaN). Rows with a second start in ``t1`` (n,) (NaN:
    none) track it too and keep the nearer foot."""
    if t1 is not None:
        two = np.flatnonzero(~np.isnan(t1) & ~np.isnan(t0))
        out = _tracked(curve, x, t0, None, step_tol)
        if two.size:
            alt = track_closest(curve, x[two], t1[two], step_tol)
            better = alt.distance < out.distance[two]
            sel = two[better]
            out.t[sel], out.foot[sel] = alt.t[better], alt.foot[better]
            out.distance[sel] = alt.distance[better]
        return out
    cold = np.isnan(t0)
    if not cold.any():
        return track_closest(curve, x, t0, step_tol)
    if cold.all():
        return curve.closest(x)
    warm = track_closest(curve, x[~cold], t0[~cold], step_tol)
    glob = curve.closest(x[cold])
    t, foot, dist = np.empty(x.shape[0]), np.empty_like(x), np.empty(x.shape[0])
    t[~cold], foot[~cold], dist[~cold] = warm.t, warm.foot, warm.distance
    t[cold], foot[cold], dist[cold] = glob.t, glob.foot, glob.distance
    return Closest(t=t, foot=foot, distance=dist)


def evaluate_field(
    sides: SideDistances,
    a: int,
    b: int,
    r: FloatArray,
    p: FloatArray,
    weighting: str,
    rows: np.ndarray | None = None,
) -> tuple[FloatArray, FloatArray, tuple[FloatArray, ...]]:
    """``g`` at parameter points ``p`` (n, 2), its gradient (n, 2) and the feet
    ``(t_a, t_b, d_a, d_b)`` (each (n,))."""
    region = sides.region
    x = region.embedding.evaluate(p)
    da, ua, ta = sides.dist(a, x, rows)
    db, ub, tb = sides.dist(b, x, rows)
    theta = foot_angle(ua, ub, weighting)
    wa, wb = _weights(r, theta)
    g = wa * da - wb * db
    gx = wa[:, None] * ua - wb[:, None] * ub
    if weighting == "angle" and not (sides.extended[a] and sides.extended[b]):
        # (between two whole lines the foot angle is constant)
        gx += _dg_dtheta(r, theta, da, db)[:, None] * _grad_theta(sides, a, b, x, theta, (
            (ta, da, ua), (tb, db, ub)))  # fmt: skip
    if not region.embedding.is_identity:
        gx = np.einsum("nij,ni->nj", region.embedding.jacobian(p), gx)
    return g, gx, (ta, tb, da, db)


def _dsinc(x: FloatArray) -> FloatArray:
    """Derivative of ``sin(x) / x``: ``(x cos x - sin x) / x^2`` (``-x / 3`` near 0)."""
    small = np.abs(x) < 1e-4
    xs = np.where(small, 1.0, x)
    return np.where(small, -x / 3.0, (xs * np.cos(xs) - np.sin(xs)) / (xs * xs))


def _dg_dtheta(r: FloatArray, theta: FloatArray, da: FloatArray, db: FloatArray) -> FloatArray:
    """``dg / dT`` (n,) at fixed distances."""
    return (1.0 - r) ** 2 * _dsinc((1.0 - r) * theta) * da - r**2 * _dsinc(r * theta) * db


def _unit_jacobian(
    curve: Curve, t: FloatArray, d: FloatArray, u: FloatArray, extended: bool
) -> FloatArray:
    """``du / dx`` (n, dim, dim) of the unit vector from the foot ``C(t)`` to ``x``:
    ``(I - u u^T - C' C'^T / D) / d`` with ``D = |C'|^2 - d u . C''`` (the foot's own motion,
    absent when the foot is at an end of the curve). Symmetric."""
    _, c1, c2 = curve.jet(t)
    dim = u.shape[1]
    den = np.einsum("ij,ij->i", c1, c1) - d * np.einsum("ij,ij->i", u, c2)
    interior = den > 0.0
    if not extended:
        interior &= (t > 0.0) & (t < 1.0)
    m = np.where(interior, 1.0 / np.where(interior, den, 1.0), 0.0)
    jac = np.eye(dim)[None] - u[:, :, None] * u[:, None, :]
    jac -= m[:, None, None] * c1[:, :, None] * c1[:, None, :]
    return jac / np.maximum(d, _TINY)[:, None, None]


def _grad_theta(
    sides: SideDistances,
    a: int,
    b: int,
    x: FloatArray,
    theta: FloatArray,
    feet: tuple[tuple[FloatArray, FloatArray, FloatArray], ...],
) -> FloatArray:
    """Gradient (n, dim) in space of ``T = arccos(-u_a . u_b)``; zero where ``T`` is 0 or
    ``pi`` (there ``dg / dT`` vanishes or the foot angle is undefined)."""
    (ta, da, ua), (tb, db, ub) = feet
    ja = _unit_jacobian(sides.curves[a], ta, da, ua, sides.extended[a])
    jb = _unit_jacobian(sides.curves[b], tb, db, ub, sides.extended[b])
    dc = np.einsum("nij,nj->ni", ja, ub) + np.einsum("nij,nj->ni", jb, ua)
    s = np.sin(theta)
    ok = s > 1e-8
    return np.where(ok, 1.0 / np.where(ok, s, 1.0), 0.0)[:, None] * dc


class PlanarField:
    """Both equations of the ratio grid in closed form, for planar regions whose four sides
    all measure distances in closed form: line segments (clamped feet), arcs of a
    distance-weighted pair (radial, or the nearer end outside the arc's angle), the whole
    lines of an angle-weighted pair of lines (the foot angle is then one of two constants).
    The field of :func:`evaluate_field` (same formulas, same conventions at zero distance)
    on coordinates held as two contiguous arrays ``x``, ``y``, each side's weight folded
    into its term: no ``(n, 2)`` columns, no foot parameters. The hot path of meshes of
    line and arc regions.
    """

    def __init__(self, region: Region, kinds: tuple[str, str]) -> None:
        if not PlanarField.supports(region, kinds):
            raise ValueError(f"region '{region.name}' has no closed-form field")
        self.kinds = kinds
        self.curves = [region.sides[k] for k in range(4)]
        # per side, the constants of its term (computed once, not per evaluation)
        self._consts = [
            _segment_consts(c) if isinstance(c, Line) else _arc_consts(c)  # type: ignore[arg-type]
            for c in self.curves
        ]
        self._normals = [_unit_normal(c) if isinstance(c, Line) else None for c in self.curves]
        # per angle pair: the foot angle when the point is on the inner side of both lines
        # or of neither (sign product +1), of one (-1), or on a line (0)
        self.angles: list[tuple[float, float, float]] = []
        for pair, kind in zip(((0, 2), (1, 3)), kinds, strict=True):
            if kind == "angle":
                na, nb = (_unit_normal(self.curves[k]) for k in pair)  # type: ignore[arg-type]
                c = float(na @ nb)
                self.angles.append(
                    (
                        float(np.arccos(np.clip(-c, -1.0, 1.0))),
                        float(np.arccos(np.clip(c, -1.0, 1.0))),
                        float(np.arccos(0.0)),
                    )
                )
            else:
                self.angles.append((0.0, 0.0, 0.0))

    @staticmethod
    def supports(region: Region, kinds: tuple[str, str]) -> bool:
        """Whether every side of ``region`` has a closed-form term here."""
        if not region.embedding.is_identity or region.space_sides is not None:
            return False
        for pair, kind in zip(((0, 2), (1, 3)), kinds, strict=True):
            for k in pair:
                c = region.sides[k]
                if c.dim != 2:
                    return False
                if kind == "angle" and type(c) is not Line:
                    return False
                if kind == "distance" and type(c) not in (Line, Arc):
                    return False
        return True

    def weights(self, pair: int, r: FloatArray) -> tuple[FloatArray, ...]:
        """Per-row weights (non-negative) of pair ``pair`` (0: sides (0, 2), 1: sides
        (1, 3)) for ratios ``r``: ``(wa, wb)``, or for an angle pair ``(wa, wb)`` at each of
        the three foot angles of :attr:`angles`."""
        if self.kinds[pair] == "distance":
            return (1.0 - r, r)
        out: list[FloatArray] = []
        for theta in self.angles[pair]:
            out.extend(_weights(r, np.full(r.shape, theta)))
        return tuple(out)

    def pair(
        self, pair: int, x: FloatArray, y: FloatArray, w: tuple[FloatArray, ...]
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``g`` (n,) of pair ``pair`` and its gradient ``(gx, gy)`` at ``(x, y)``, with the
        rows' weights ``w`` of :meth:`weights`."""
        return self._pair(pair, x, y, w, True)

    def value(
        self, pair: int, x: FloatArray, y: FloatArray, w: tuple[FloatArray, ...]
    ) -> FloatArray:
        """``g`` alone (the same values as :meth:`pair`, bit for bit)."""
        return self._pair(pair, x, y, w, False)[0]

    def _pair(
        self, pair: int, x: FloatArray, y: FloatArray, w: tuple[FloatArray, ...], grad: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        a, b = (0, 2) if pair == 0 else (1, 3)
        if self.kinds[pair] == "angle":
            return self._angle_pair(a, b, x, y, w, grad)
        g, gx, gy = self._term(a, x, y, w[0], grad)
        hb, hx, hy = self._term(b, x, y, w[1], grad)
        g -= hb
        if grad:
            gx -= hx
            gy -= hy
        return g, gx, gy

    def _term(
        self, k: int, x: FloatArray, y: FloatArray, w: FloatArray, grad: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``w d`` (n,) and ``w u`` (two (n,), empty unless ``grad``) for side ``k`` of a
        distance-weighted pair: ``d`` the distance, ``u`` the unit vector from the foot to
        the point."""
        if isinstance(self.curves[k], Line):
            return _segment_term(self._consts[k], x, y, w, grad)
        return _arc_term(self._consts[k], x, y, w, grad)

    def _angle_pair(
        self,
        a: int,
        b: int,
        x: FloatArray,
        y: FloatArray,
        w: tuple[FloatArray, ...],
        grad: bool,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``g`` and gradient of an angle pair of whole lines: ``u = sign(s) n`` from the
        signed distance ``s``, the foot angle one of three constants by the signs."""
        la, lb, na, nb = self.curves[a], self.curves[b], self._normals[a], self._normals[b]
        assert isinstance(la, Line) and isinstance(lb, Line)
        assert na is not None and nb is not None
        sa = (x - la.a[0]) * na[0]
        sa += (y - la.a[1]) * na[1]
        sb = (x - lb.a[0]) * nb[0]
        sb += (y - lb.a[1]) * nb[1]
        ua, ub = np.sign(sa), np.sign(sb)
        case = ua * ub
        if case.all():
            wa, wb = np.where(case > 0, w[0], w[2]), np.where(case > 0, w[1], w[3])
        else:
            wa = np.where(case > 0, w[0], np.where(case < 0, w[2], w[4]))
            wb = np.where(case > 0, w[1], np.where(case < 0, w[3], w[5]))
        g = wa * np.abs(sa)
        g -= wb * np.abs(sb)
        if not grad:
            return g, _EMPTY, _EMPTY
        ua *= wa
        ub *= wb
        gx = ua * na[0]
        gx -= ub * nb[0]
        gy = ua * na[1]
        gy -= ub * nb[1]
        return g, gx, gy


def _unit_normal(line: Line) -> FloatArray:
    """The unit normal (2,) to the left of a line side (into a CCW region)."""
    d = line.b - line.a
    return np.array([-d[1], d[0]]) / float(np.sqrt(d @ d))


def _segment_consts(line: Line) -> tuple[float, ...]:
    """``(ax, ay, ex, ey, ee)``: start, direction and its squared length."""
    ax, ay = float(line.a[0]), float(line.a[1])
    ex, ey = float(line.b[0]) - ax, float(line.b[1]) - ay
    return ax, ay, ex, ey, ex * ex + ey * ey


def _segment_term(
    consts: tuple[float, ...], x: FloatArray, y: FloatArray, w: FloatArray, grad: bool = True
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``w d``, ``w u`` for a segment (the foot clamped to its ends; ``u = 0`` on it), from
    :func:`_segment_consts`."""
    ax, ay, ex, ey, ee = consts
    dx, dy = x - ax, y - ay
    t = dx * ex
    t += dy * ey
    if ee > 0.0:
        t *= 1.0 / ee
        np.maximum(t, 0.0, out=t)
        np.minimum(t, 1.0, out=t)
    else:
        t[:] = 0.0
    rx = t * ex
    np.subtract(dx, rx, out=rx)
    t *= ey
    np.subtract(dy, t, out=t)
    ry = t
    d = rx * rx
    d += ry * ry
    np.sqrt(d, out=d)
    if not grad:
        d *= w
        return d, _EMPTY, _EMPTY
    f = np.maximum(d, _TINY)
    np.divide(w, f, out=f)
    rx *= f
    ry *= f
    d *= w
    return d, rx, ry


def _arc_consts(arc: Arc) -> tuple[float, ...]:
    """``(cx, cy, R, mx, my, cos h, x0, y0, x1, y1)``: centre, radius, the bisector of the
    arc's angle and the cosine of half the sweep, the end points."""
    mid = arc.a0 + 0.5 * arc.sweep
    ends = arc.evaluate(np.array([0.0, 1.0]))
    return (
        float(arc.center[0]), float(arc.center[1]), arc.radius,
        float(np.cos(mid)), float(np.sin(mid)), float(np.cos(0.5 * abs(arc.sweep))),
        float(ends[0, 0]), float(ends[0, 1]), float(ends[1, 0]), float(ends[1, 1]),
    )  # fmt: skip


def _arc_term(
    consts: tuple[float, ...], x: FloatArray, y: FloatArray, w: FloatArray, grad: bool = True
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``w d``, ``w u`` for an arc (constants of :func:`_arc_consts`): radial inside its angle
    (``v . m >= |v| cos(h)``, ``m`` the bisector, ``h`` half the sweep), the nearer end
    outside it or at the centre."""
    cx, cy, radius, mx, my, ch, x0, y0, x1, y1 = consts
    vx, vy = x - cx, y - cy
    rho = vx * vx
    rho += vy * vy
    np.sqrt(rho, out=rho)
    dot = vx * mx
    dot += vy * my
    outside = dot < rho * ch
    if not rho.all():
        outside |= rho == 0.0
    dr = rho - radius
    if grad:
        # unit vector from the foot c + R v / rho to x: +v / rho outside the circle, -v inside
        f = np.maximum(rho, _TINY, out=rho)
        np.divide(np.copysign(w, dr), f, out=f)
        vx *= f
        vy *= f
    np.abs(dr, out=dr)
    dr *= w
    out = np.flatnonzero(outside)
    if out.size:  # outside the arc's angle the nearer end is the foot
        xo, yo, wo = x[out], y[out], w[out]
        r0x, r0y, r1x, r1y = xo - x0, yo - y0, xo - x1, yo - y1
        d0, d1 = np.sqrt(r0x * r0x + r0y * r0y), np.sqrt(r1x * r1x + r1y * r1y)
        first = d0 <= d1
        do = np.where(first, d0, d1)
        dr[out] = wo * do
        if grad:
            fo = wo / np.maximum(do, _TINY)
            vx[out] = np.where(first, r0x, r1x) * fo
            vy[out] = np.where(first, r0y, r1y) * fo
    if not grad:
        return dr, _EMPTY, _EMPTY
    return dr, vx, vy
